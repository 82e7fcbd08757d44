//! The SVG document of a picture: plotters' [`SVGBackend`], with every stroke put on the
//! pixels plotters means and curves at sub-pixel positions.
//!
//! plotters gives pixel coordinates as integers meaning pixels: a 1-pixel line at x = 143
//! fills pixel column 143, whose centre is at 143.5 in SVG coordinates (pixel (i, j) is the
//! unit square [i, i+1) × [j, j+1)). Its SVG backend writes the line at 143, across two
//! half-covered columns, which a renderer draws grey and two pixels wide. [`SvgCanvas`]
//! moves strokes of odd width (lines, paths, outlines) and circles half a pixel on, so
//! that they cover whole pixels; it draws discs at the size plotters fills and text at the
//! size plotters measures it with. Filled rectangles, polygons and images are passed on
//! unchanged (their integer corners are pixel edges already).

use super::marks::Rect;
use super::stroke::Canvas;
use plotters::prelude::*;
use plotters::style::{FontFamily, FontStyle, FontTransform};
use plotters_backend::text_anchor::Pos;
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind,
};
use std::collections::HashMap;
use std::fmt::Write;
use std::hash::{Hash, Hasher};

/// A backend writing an SVG document: plotters' [`SVGBackend`], where the elements this
/// canvas writes itself (sub-pixel polylines, pixel-aligned strokes and circles) are left
/// as one-point placeholder polylines that [`SvgCanvas::finish`] replaces by the real ones.
pub(crate) struct SvgCanvas<'a> {
    inner: SVGBackend<'a>,
    elements: std::rc::Rc<std::cell::RefCell<Vec<String>>>,
    /// The clip rectangles defined in the document so far (x, y, w, h as written), each
    /// with its number in the clip paths' ids.
    clips: HashMap<String, usize>,
}

/// Stands for the document's own token in the ids this canvas writes, until
/// [`SvgCanvas::finish`] knows the document.
const DOCUMENT_TOKEN: &str = "@document@";

/// The y coordinate of the placeholders: no picture is drawn there.
const PLACEHOLDER_Y: i32 = -7777;

type DrawResult<E> = Result<(), DrawingErrorKind<E>>;

impl<'a> SvgCanvas<'a> {
    /// A canvas writing into `buf`; `elements` collects the elements for [`Self::finish`].
    pub(crate) fn new(
        buf: &'a mut String,
        size: (u32, u32),
        elements: std::rc::Rc<std::cell::RefCell<Vec<String>>>,
    ) -> Self {
        SvgCanvas {
            inner: SVGBackend::with_string(buf, size),
            elements,
            clips: HashMap::new(),
        }
    }

    /// The finished document `svg` with each placeholder replaced by its element
    /// (`elements`, in drawing order). The ids in those elements carry a hash of the whole
    /// document, so that pictures inlined in one page never share an id.
    pub(crate) fn finish(svg: &str, elements: &[String]) -> String {
        let mut hasher = rustc_hash::FxHasher::default();
        svg.hash(&mut hasher);
        elements.hash(&mut hasher);
        let document = format!("{:016x}", hasher.finish());
        let mut out =
            String::with_capacity(svg.len() + elements.iter().map(String::len).sum::<usize>());
        let mut rest = svg;
        for (k, tag) in elements.iter().enumerate() {
            let needle = format!("points=\"{k},{PLACEHOLDER_Y} \"/>");
            let Some(end) = rest.find(&needle) else {
                break;
            };
            let Some(start) = rest[..end].rfind("<polyline") else {
                break;
            };
            out.push_str(&rest[..start]);
            if tag.contains(DOCUMENT_TOKEN) {
                out.push_str(&tag.replace(DOCUMENT_TOKEN, &document));
            } else {
                out.push_str(tag);
            }
            rest = &rest[end + needle.len()..];
        }
        out.push_str(rest);
        out
    }

    /// Write `tag` (one or more SVG elements) at this point of the document.
    fn element(&mut self, tag: String) -> DrawResult<<Self as DrawingBackend>::ErrorType> {
        let k = {
            let mut elements = self.elements.borrow_mut();
            elements.push(tag);
            elements.len() - 1
        };
        self.inner
            .draw_path([(k as i32, PLACEHOLDER_Y)], &Color::stroke_width(&BLACK, 1))
    }

    /// The clip-path attribute that keeps a drawing inside `clip`, with the clip path's
    /// definition when the document does not have it yet.
    fn clip_path(&mut self, clip: Rect) -> (String, String) {
        let Rect { x, y, w, h } = clip;
        let rect = format!("x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\"");
        let next = self.clips.len();
        let (n, new) = match self.clips.get(&rect) {
            Some(&n) => (n, false),
            None => {
                self.clips.insert(rect.clone(), next);
                (next, true)
            }
        };
        let id = format!("goniofit-clip-{DOCUMENT_TOKEN}-{n}");
        let definition = if new {
            format!("<clipPath id=\"{id}\"><rect {rect}/></clipPath>\n")
        } else {
            String::new()
        };
        (definition, format!(" clip-path=\"url(#{id})\""))
    }
}

/// A colour as the SVG paint attribute `name` (`fill` or `stroke`), with its opacity when
/// it is translucent.
fn paint(name: &str, c: BackendColor) -> String {
    let (r, g, b) = c.rgb;
    let mut s = format!("{name}=\"#{r:02X}{g:02X}{b:02X}\"");
    if c.alpha < 1.0 {
        let _ = write!(s, " {name}-opacity=\"{}\"", c.alpha);
    }
    s
}

/// The offset that puts a stroke `width` pixels wide through plotters' integer coordinates
/// on whole pixels: half a pixel for an odd width (centred on the pixel's centre), none for
/// an even one (centred on the pixel's edge).
fn pixel_offset(width: u32) -> f64 {
    if width % 2 == 1 {
        0.5
    } else {
        0.0
    }
}

/// The stroke attributes of a plotters style: colour, width, and square caps for a 1-pixel
/// line (plotters' own 1-pixel lines include both end pixels).
fn stroke_attributes(c: BackendColor, width: u32) -> String {
    let cap = if width == 1 {
        " stroke-linecap=\"square\""
    } else {
        ""
    };
    format!(
        "fill=\"none\" {} stroke-width=\"{width}\"{cap}",
        paint("stroke", c)
    )
}

/// `pts` as an SVG points list, each moved by `offset` in x and y.
fn points<I: IntoIterator<Item = (f64, f64)>>(pts: I, offset: f64) -> String {
    let mut out = String::new();
    for (x, y) in pts {
        let _ = write!(out, "{},{} ", x + offset, y + offset);
    }
    out.trim_end().to_string()
}

impl Canvas for SvgCanvas<'_> {
    /// The polyline with its vertices to 0.01 px, round joins and butt caps; a stroke that
    /// reaches outside `clip` is clipped to it.
    fn stroke_polyline(
        &mut self,
        pts: &[(f64, f64)],
        width: f64,
        color: RGBColor,
        clip: Rect,
    ) -> DrawResult<Self::ErrorType> {
        let finite: Vec<(f64, f64)> = pts
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        let drawable = width > 0.0 && width.is_finite() && clip.w > 0.0 && clip.h > 0.0;
        if finite.len() < 2 || !drawable {
            return Ok(());
        }
        let r = 0.5 * width;
        let inside = finite.iter().all(|p| {
            p.0 - r >= clip.x
                && p.0 + r <= clip.x + clip.w
                && p.1 - r >= clip.y
                && p.1 + r <= clip.y + clip.h
        });
        let (definition, attribute) = if inside {
            (String::new(), String::new())
        } else {
            self.clip_path(clip)
        };
        let mut list = String::new();
        for p in &finite {
            let _ = write!(list, "{:.2},{:.2} ", p.0, p.1);
        }
        let (r, g, b) = (color.0, color.1, color.2);
        self.element(format!(
            "{definition}<polyline fill=\"none\" stroke=\"#{r:02X}{g:02X}{b:02X}\" \
             stroke-width=\"{width}\" stroke-linejoin=\"round\"{attribute} points=\"{}\"/>",
            list.trim_end()
        ))
    }
}

/// A text style at `scale` times the size of `inner`.
struct Scaled<'s, T> {
    inner: &'s T,
    scale: f64,
}

impl<T: BackendTextStyle> BackendTextStyle for Scaled<'_, T> {
    type FontError = T::FontError;
    fn color(&self) -> BackendColor {
        self.inner.color()
    }
    fn size(&self) -> f64 {
        self.inner.size() * self.scale
    }
    fn transform(&self) -> FontTransform {
        self.inner.transform()
    }
    fn style(&self) -> FontStyle {
        self.inner.style()
    }
    fn anchor(&self) -> Pos {
        self.inner.anchor()
    }
    fn family(&self) -> FontFamily<'_> {
        self.inner.family()
    }
    fn layout_box(&self, text: &str) -> Result<((i32, i32), (i32, i32)), Self::FontError> {
        self.inner.layout_box(text)
    }
    fn draw<E, F: FnMut(i32, i32, BackendColor) -> Result<(), E>>(
        &self,
        text: &str,
        pos: BackendCoord,
        draw: F,
    ) -> Result<Result<(), E>, Self::FontError> {
        self.inner.draw(text, pos, draw)
    }
}

/// How much larger than plotters' SVG backend writes it text must be set to have the size
/// plotters measures and lays it out with: the backend writes `font-size` = size / 1.24,
/// while plotters' ab_glyph fonts set a size-`s` text with ascent − descent = `s`, an em of
/// `s` · em / (ascent − descent) in the bundled font's own units.
fn text_scale() -> f64 {
    use ab_glyph::Font;
    static SCALE: std::sync::OnceLock<f64> = std::sync::OnceLock::new();
    *SCALE.get_or_init(|| {
        // The font is bundled and parses; were it not to, text keeps the backend's size.
        let em_per_height = ab_glyph::FontRef::try_from_slice(super::FONT_BYTES)
            .ok()
            .and_then(|font| {
                let em = f64::from(font.units_per_em()?);
                Some(em / f64::from(font.ascent_unscaled() - font.descent_unscaled()))
            })
            .unwrap_or(1.0);
        SVG_BACKEND_SHRINK * em_per_height
    })
}

/// The factor by which plotters' SVG backend divides a text's size when it writes
/// `font-size` (plotters-svg 0.3).
const SVG_BACKEND_SHRINK: f64 = 1.24;

impl DrawingBackend for SvgCanvas<'_> {
    type ErrorType = <SVGBackend<'static> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }
    fn ensure_prepared(&mut self) -> DrawResult<Self::ErrorType> {
        self.inner.ensure_prepared()
    }
    fn present(&mut self) -> DrawResult<Self::ErrorType> {
        self.inner.present()
    }
    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> DrawResult<Self::ErrorType> {
        self.inner.draw_pixel(point, color)
    }
    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> DrawResult<Self::ErrorType> {
        self.draw_path([from, to], style)
    }
    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> DrawResult<Self::ErrorType> {
        let (c, width) = (style.color(), style.stroke_width());
        if fill || c.alpha == 0.0 || width == 0 {
            return self.inner.draw_rect(upper_left, bottom_right, style, fill);
        }
        let o = pixel_offset(width);
        let (x0, y0) = (
            upper_left.0.min(bottom_right.0),
            upper_left.1.min(bottom_right.1),
        );
        let (x1, y1) = (
            upper_left.0.max(bottom_right.0),
            upper_left.1.max(bottom_right.1),
        );
        self.element(format!(
            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" {}/>",
            x0 as f64 + o,
            y0 as f64 + o,
            x1 - x0,
            y1 - y0,
            stroke_attributes(c, width).replace(" stroke-linecap=\"square\"", "")
        ))
    }
    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> DrawResult<Self::ErrorType> {
        let (c, width) = (style.color(), style.stroke_width());
        let path: Vec<(f64, f64)> = path
            .into_iter()
            .map(|(x, y)| (x as f64, y as f64))
            .collect();
        if c.alpha == 0.0 || width == 0 || path.is_empty() {
            return Ok(());
        }
        self.element(format!(
            "<polyline {} points=\"{}\"/>",
            stroke_attributes(c, width),
            points(path, pixel_offset(width))
        ))
    }
    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> DrawResult<Self::ErrorType> {
        let (c, width) = (style.color(), style.stroke_width());
        if c.alpha == 0.0 {
            return Ok(());
        }
        // plotters' disc of radius r fills the pixels whose centres lie within r of its
        // centre pixel's centre, and blends the next pixel out: a disc of radius r + ½.
        let (r, paint) = if fill {
            (
                radius as f64 + 0.5,
                format!("{} stroke=\"none\"", paint("fill", c)),
            )
        } else {
            (
                radius as f64,
                format!(
                    "fill=\"none\" {} stroke-width=\"{width}\"",
                    paint("stroke", c)
                ),
            )
        };
        self.element(format!(
            "<circle cx=\"{}\" cy=\"{}\" r=\"{r}\" {paint}/>",
            center.0 as f64 + 0.5,
            center.1 as f64 + 0.5
        ))
    }
    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> DrawResult<Self::ErrorType> {
        self.inner.fill_polygon(vert, style)
    }
    fn draw_text<T: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> DrawResult<Self::ErrorType> {
        let scaled = Scaled {
            inner: style,
            scale: text_scale(),
        };
        self.inner.draw_text(text, &scaled, pos)
    }
    fn estimate_text_size<T: BackendTextStyle>(
        &self,
        text: &str,
        style: &T,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        self.inner.estimate_text_size(text, style)
    }
    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> DrawResult<Self::ErrorType> {
        self.inner.blit_bitmap(pos, size, src)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::RefCell;
    use std::rc::Rc;

    /// The document of a 100 × 60 canvas after `draw`.
    fn document(draw: impl Fn(&mut SvgCanvas<'_>)) -> String {
        let mut buf = String::new();
        let elements = Rc::new(RefCell::new(Vec::new()));
        {
            let mut canvas = SvgCanvas::new(&mut buf, (100, 60), elements.clone());
            draw(&mut canvas);
            canvas.present().unwrap();
        }
        let elements = elements.borrow();
        SvgCanvas::finish(&buf, &elements)
    }

    const AREA: Rect = Rect {
        x: 10.0,
        y: 5.0,
        w: 80.0,
        h: 50.0,
    };

    #[test]
    fn a_polyline_inside_its_clip_keeps_its_sub_pixel_vertices_unclipped() {
        let svg = document(|c| {
            c.stroke_polyline(&[(15.0, 20.304), (60.0, 20.25)], 2.0, BLACK, AREA)
                .unwrap()
        });
        assert!(
            svg.contains(
                "<polyline fill=\"none\" stroke=\"#000000\" stroke-width=\"2\" \
                 stroke-linejoin=\"round\" points=\"15.00,20.30 60.00,20.25\"/>"
            ),
            "{svg}"
        );
        assert!(!svg.contains("clip") && !svg.contains(&PLACEHOLDER_Y.to_string()));
    }

    #[test]
    fn polylines_reaching_outside_their_clip_share_one_clip_path_per_rectangle() {
        // Half the stroke's width past the area's bottom edge is enough to need the clip.
        let draw = |c: &mut SvgCanvas<'_>| {
            for y in [54.5, 40.0, 54.0] {
                c.stroke_polyline(&[(15.0, y), (85.0, y)], 3.0, BLACK, AREA)
                    .unwrap();
            }
        };
        let svg = document(draw);
        assert_eq!(svg.matches("<clipPath").count(), 1, "{svg}");
        assert!(svg.contains("<rect x=\"10\" y=\"5\" width=\"80\" height=\"50\"/></clipPath>"));
        let id = svg.split("<clipPath id=\"").nth(1).unwrap();
        let id = &id[..id.find('"').unwrap()];
        assert!(
            id.starts_with("goniofit-clip-") && !id.contains(DOCUMENT_TOKEN),
            "{id}"
        );
        // Two of the three reach outside, and the ids are the same in the same document.
        assert_eq!(
            svg.matches(&format!("clip-path=\"url(#{id})\"")).count(),
            3 - 1
        );
        assert_eq!(document(draw), svg);
        // Another picture has other ids.
        let other = document(|c| {
            c.stroke_polyline(&[(15.0, 54.9), (95.0, 54.9)], 3.0, BLACK, AREA)
                .unwrap()
        });
        assert!(!other.contains(id));
    }

    #[test]
    fn one_pixel_strokes_and_discs_sit_on_pixel_centres() {
        let svg = document(|c| {
            c.draw_line((10, 20), (50, 20), &Color::stroke_width(&BLACK, 1))
                .unwrap();
            c.draw_line((10, 30), (50, 30), &Color::stroke_width(&BLACK, 2))
                .unwrap();
            c.draw_circle((40, 40), 4, &BLACK.filled(), true).unwrap();
            c.draw_rect((5, 5), (20, 15), &Color::stroke_width(&BLACK, 1), false)
                .unwrap();
        });
        assert!(svg.contains(
            "<polyline fill=\"none\" stroke=\"#000000\" stroke-width=\"1\" \
             stroke-linecap=\"square\" points=\"10.5,20.5 50.5,20.5\"/>"
        ));
        assert!(svg.contains("stroke-width=\"2\" points=\"10,30 50,30\"/>"));
        assert!(svg.contains("<circle cx=\"40.5\" cy=\"40.5\" r=\"4.5\" fill=\"#000000\""));
        assert!(svg.contains("<rect x=\"5.5\" y=\"5.5\" width=\"15\" height=\"10\" fill=\"none\""));
    }

    #[test]
    fn text_is_written_at_the_size_plotters_measures() {
        // A size-20 text as ab_glyph sets it spans ascent − descent = 20: DejaVu Sans'
        // (1901 + 483) / 2048 em, so an em of 20 · 2048 / 2384.
        crate::plot::ensure_font().unwrap();
        let svg = document(|c| {
            c.draw_text("x", &crate::plot::font(20.0).color(&BLACK), (5, 5))
                .unwrap()
        });
        let size: f64 = svg
            .split("font-size=\"")
            .nth(1)
            .unwrap()
            .split('"')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        assert!((size - 20.0 * 2048.0 / 2384.0).abs() < 1e-9, "{size}");
    }
}
