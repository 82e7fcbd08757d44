//! The SVG document of a picture: plotters' [`SVGBackend`], with every stroke put on the
//! pixels plotters means and curves at sub-pixel positions.
//!
//! plotters gives pixel coordinates as integers meaning pixels: a 1-pixel line at x = 143
//! fills pixel column 143, whose centre is at 143.5 in SVG coordinates (pixel (i, j) is the
//! unit square [i, i+1) × [j, j+1)). Its SVG backend writes the line at 143, across two
//! half-covered columns, which a renderer draws grey and two pixels wide. [`SvgCanvas`]
//! writes strokes of odd width (lines, paths, outlines) and circles half a pixel on instead,
//! so that they cover whole pixels, discs at the size plotters fills, and text at the size
//! plotters measures it with.
//! Filled rectangles, polygons and images are passed on unchanged (their integer corners
//! are pixel edges already).

use super::marks::Rect;
use super::stroke::Canvas;
use plotters::prelude::*;
use plotters::style::{FontFamily, FontStyle, FontTransform};
use plotters_backend::text_anchor::Pos;
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind,
};
use std::collections::HashSet;
use std::fmt::Write;

/// A backend writing an SVG document: plotters' [`SVGBackend`], where the elements this
/// canvas writes itself (sub-pixel polylines, pixel-aligned strokes and circles) are left
/// as one-point placeholder polylines that [`SvgCanvas::finish`] replaces by the real ones.
pub struct SvgCanvas<'a> {
    inner: SVGBackend<'a>,
    elements: std::rc::Rc<std::cell::RefCell<Vec<String>>>,
    /// The ids of the clip paths already defined in the document.
    clips: HashSet<String>,
}

/// The y coordinate of the placeholders: no picture is drawn there.
const PLACEHOLDER_Y: i32 = -7777;

type DrawResult<E> = Result<(), DrawingErrorKind<E>>;

impl<'a> SvgCanvas<'a> {
    /// A canvas writing into `buf`; `elements` collects the elements for [`Self::finish`].
    pub fn new(
        buf: &'a mut String,
        size: (u32, u32),
        elements: std::rc::Rc<std::cell::RefCell<Vec<String>>>,
    ) -> Self {
        SvgCanvas {
            inner: SVGBackend::with_string(buf, size),
            elements,
            clips: HashSet::new(),
        }
    }

    /// The finished document `svg` with each placeholder replaced by its element
    /// (`elements`, in drawing order).
    pub fn finish(svg: &str, elements: &[String]) -> String {
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
            out.push_str(tag);
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
    /// definition when the document does not have it yet. The id names the rectangle, so
    /// pictures inlined in one page that share an id share its rectangle too.
    fn clip_path(&mut self, clip: Rect) -> (String, String) {
        let Rect { x, y, w, h } = clip;
        let id = format!("goniofit-clip-{x}-{y}-{w}-{h}").replace('.', "_");
        let definition = if self.clips.insert(id.clone()) {
            format!(
                "<clipPath id=\"{id}\"><rect x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{h}\"/>\
                 </clipPath>\n"
            )
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
/// while plotters' ab_glyph fonts set a size-`s` text with ascent − descent = `s`, which
/// for DejaVu Sans ((1901 + 483) / 2048 em) is an em of `s` · 2048 / 2384.
pub const TEXT_SCALE: f64 = 1.24 * 2048.0 / 2384.0;

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
            scale: TEXT_SCALE,
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
