//! Anti-aliased lines at sub-pixel positions.
//!
//! plotters' backends take integer pixel coordinates, so a curve sampled every pixel or two
//! and drawn through them is stair-stepped (each vertex moved by up to half a pixel). Here a
//! polyline is stroked at `f64` pixel positions instead.
//!
//! Pixel convention: pixel (i, j) is the unit square [i, i+1) × [j, j+1), its centre at
//! (i + ½, j + ½). A stroke of width w is the set of points within w/2 of the polyline
//! (round caps and joins). A pixel's coverage is estimated from the distance d of its
//! centre to the polyline as clamp(w/2 + ½ − d, 0, 1): exact for an edge parallel to a
//! pixel side, within about 0.1 of the covered area at any other angle, and, summed across
//! a straight stroke of w ≥ 1, the stroke's width exactly. The colour is blended into the
//! bitmap with that coverage as its alpha, once per pixel and polyline (joints are not
//! blended twice).
//!
//! Backends: the PNG bitmap blends per pixel; an SVG file gets the polyline itself with its
//! vertices at their `f64` positions (rounded to 0.01 px) and round joins, drawn by the
//! viewer's own anti-aliasing ([`SvgCanvas`]). Pictures draw through the [`Canvas`] trait,
//! which both implement.

use super::marks::Rect;
use super::DrawError;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingErrorKind,
};

/// A backend that can stroke polylines at sub-pixel positions.
pub trait Canvas: DrawingBackend {
    /// Stroke `pts` (backend pixels, f64) `width` pixels wide in `color`, only inside
    /// `clip` (backend pixels).
    fn stroke_polyline(
        &mut self,
        pts: &[(f64, f64)],
        width: f64,
        color: RGBColor,
        clip: Rect,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>>;
}

impl Canvas for BitMapBackend<'_> {
    fn stroke_polyline(
        &mut self,
        pts: &[(f64, f64)],
        width: f64,
        color: RGBColor,
        clip: Rect,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let rgb = (color.0, color.1, color.2);
        for (p, alpha) in coverage(pts, width, clip) {
            self.draw_pixel(p, BackendColor { alpha, rgb })?;
        }
        Ok(())
    }
}

/// An SVG backend that writes sub-pixel polylines: plotters' [`SVGBackend`] (every other
/// drawing call is passed on unchanged), where each [`Canvas::stroke_polyline`] leaves a
/// one-point placeholder polyline that [`SvgCanvas::finish`] replaces by the real one.
pub struct SvgCanvas<'a> {
    inner: SVGBackend<'a>,
    strokes: std::rc::Rc<std::cell::RefCell<Vec<String>>>,
}

/// The y coordinate of the placeholders: no picture is drawn there.
const PLACEHOLDER_Y: i32 = -7777;

impl<'a> SvgCanvas<'a> {
    /// A canvas writing into `buf`; `strokes` collects the polylines for [`Self::finish`].
    pub fn new(
        buf: &'a mut String,
        size: (u32, u32),
        strokes: std::rc::Rc<std::cell::RefCell<Vec<String>>>,
    ) -> Self {
        SvgCanvas {
            inner: SVGBackend::with_string(buf, size),
            strokes,
        }
    }

    /// The finished document `svg` with each placeholder replaced by its polyline
    /// (`strokes`, in drawing order).
    pub fn finish(svg: &str, strokes: &[String]) -> String {
        let mut out =
            String::with_capacity(svg.len() + strokes.iter().map(String::len).sum::<usize>());
        let mut rest = svg;
        for (k, tag) in strokes.iter().enumerate() {
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
}

/// The SVG polyline of a stroke: vertices to 0.01 px, round joins, butt caps.
fn svg_polyline(pts: &[(f64, f64)], width: f64, color: RGBColor) -> String {
    use std::fmt::Write;
    let mut points = String::new();
    for p in pts {
        let _ = write!(points, "{:.2},{:.2} ", p.0, p.1);
    }
    format!(
        "<polyline fill=\"none\" stroke=\"#{:02X}{:02X}{:02X}\" stroke-width=\"{width}\" \
         stroke-linejoin=\"round\" points=\"{}\"/>",
        color.0,
        color.1,
        color.2,
        points.trim_end()
    )
}

impl Canvas for SvgCanvas<'_> {
    fn stroke_polyline(
        &mut self,
        pts: &[(f64, f64)],
        width: f64,
        color: RGBColor,
        _clip: Rect,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let finite: Vec<(f64, f64)> = pts
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        if finite.len() < 2 {
            return Ok(());
        }
        let k = {
            let mut strokes = self.strokes.borrow_mut();
            strokes.push(svg_polyline(&finite, width, color));
            strokes.len() - 1
        };
        self.inner
            .draw_path([(k as i32, PLACEHOLDER_Y)], &Color::stroke_width(&BLACK, 1))
    }
}

impl DrawingBackend for SvgCanvas<'_> {
    type ErrorType = <SVGBackend<'static> as DrawingBackend>::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.inner.get_size()
    }
    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.ensure_prepared()
    }
    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.present()
    }
    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_pixel(point, color)
    }
    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_line(from, to, style)
    }
    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_rect(upper_left, bottom_right, style, fill)
    }
    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_path(path, style)
    }
    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_circle(center, radius, style, fill)
    }
    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.fill_polygon(vert, style)
    }
    fn draw_text<T: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &T,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.draw_text(text, style, pos)
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
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.inner.blit_bitmap(pos, size, src)
    }
}

/// The pixels a stroke of `width` along `pts` covers inside `clip`, each with its coverage
/// in (0, 1] (see the module's doc), in row-major order. Points that are not finite are
/// skipped (joining their neighbours).
pub fn coverage(pts: &[(f64, f64)], width: f64, clip: Rect) -> Vec<(BackendCoord, f64)> {
    let r = if width.is_finite() {
        0.5 * width.max(0.0)
    } else {
        0.0
    };
    let reach = r + 0.5;
    let finite: Vec<(f64, f64)> = pts
        .iter()
        .copied()
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .collect();
    if finite.is_empty() || r <= 0.0 {
        return Vec::new();
    }
    // Pixels whose centres lie in the clip rectangle: i from ⌈x − ½⌉ to ⌊x + w − ½⌋.
    let lo_x = (clip.x - 0.5).ceil().max(i32::MIN as f64 / 2.0) as i64;
    let hi_x = (clip.x + clip.w - 0.5).floor().min(i32::MAX as f64 / 2.0) as i64;
    let lo_y = (clip.y - 0.5).ceil().max(i32::MIN as f64 / 2.0) as i64;
    let hi_y = (clip.y + clip.h - 0.5).floor().min(i32::MAX as f64 / 2.0) as i64;
    let (bx0, bx1, by0, by1) = finite.iter().fold(
        (
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ),
        |(a, b, c, d), p| (a.min(p.0), b.max(p.0), c.min(p.1), d.max(p.1)),
    );
    let range = |lo: f64, hi: f64, clo: i64, chi: i64| {
        let a = ((lo - reach - 0.5).floor() as i64).max(clo);
        let b = ((hi + reach - 0.5).ceil() as i64).min(chi);
        (a, b)
    };
    let (x0, x1) = range(bx0, bx1, lo_x, hi_x);
    let (y0, y1) = range(by0, by1, lo_y, hi_y);
    if x1 < x0 || y1 < y0 {
        return Vec::new();
    }
    let (w, h) = ((x1 - x0 + 1) as usize, (y1 - y0 + 1) as usize);
    let mut alpha = vec![0.0f64; w * h];
    let segments: Vec<((f64, f64), (f64, f64))> = if finite.len() == 1 {
        vec![(finite[0], finite[0])]
    } else {
        finite.windows(2).map(|s| (s[0], s[1])).collect()
    };
    for (a, b) in segments {
        let (sx0, sx1) = range(a.0.min(b.0), a.0.max(b.0), x0, x1);
        let (sy0, sy1) = range(a.1.min(b.1), a.1.max(b.1), y0, y1);
        for j in sy0..=sy1 {
            for i in sx0..=sx1 {
                let d = distance_to_segment((i as f64 + 0.5, j as f64 + 0.5), a, b);
                let c = (reach - d).clamp(0.0, 1.0);
                let k = (j - y0) as usize * w + (i - x0) as usize;
                if c > alpha[k] {
                    alpha[k] = c;
                }
            }
        }
    }
    let mut out = Vec::new();
    for (k, &c) in alpha.iter().enumerate() {
        if c > 0.0 {
            let (i, j) = (x0 + (k % w) as i64, y0 + (k / w) as i64);
            out.push(((i as i32, j as i32), c));
        }
    }
    out
}

/// The distance from `p` to the segment `a`–`b`.
fn distance_to_segment(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let len2 = dx * dx + dy * dy;
    let t = if len2 > 0.0 {
        (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (qx, qy) = (a.0 + t * dx - p.0, a.1 + t * dy - p.1);
    (qx * qx + qy * qy).sqrt()
}

/// The dashes of `pts`: pieces `on` pixels long, `off` pixels apart, measured along the
/// polyline from its start. `on` ≤ 0 or `off` ≤ 0 gives the whole polyline.
pub fn dashes(pts: &[(f64, f64)], on: f64, off: f64) -> Vec<Vec<(f64, f64)>> {
    if !(on > 0.0 && off > 0.0) || pts.len() < 2 {
        return vec![pts.to_vec()];
    }
    let period = on + off;
    let mut out = Vec::new();
    let mut cur: Vec<(f64, f64)> = vec![pts[0]];
    // Arc length at the start of the current segment, within the period.
    let mut s = 0.0f64;
    for seg in pts.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        let len = ((b.0 - a.0).powi(2) + (b.1 - a.1).powi(2)).sqrt();
        let at = |t: f64| {
            let f = if len > 0.0 { t / len } else { 0.0 };
            (a.0 + f * (b.0 - a.0), a.1 + f * (b.1 - a.1))
        };
        let mut t = 0.0;
        while t < len {
            let phase = (s + t) % period;
            let drawing = phase < on;
            let next_edge = if drawing { on - phase } else { period - phase };
            let step = next_edge.min(len - t);
            t += step;
            if drawing {
                cur.push(at(t));
                if step >= next_edge {
                    out.push(std::mem::take(&mut cur));
                }
            } else if step >= next_edge {
                cur = vec![at(t)];
            }
        }
        s = (s + len) % period;
    }
    if cur.len() >= 2 {
        out.push(cur);
    }
    out
}

/// The map from a chart's values to sub-pixel positions in its plotting area (pixels from
/// the area's top-left corner, f64), for linear or logarithmic axes. It is plotters' own
/// map before rounding, placed so that its rounding is centred: plotters draws value v in
/// column ⌊X⌋ with X = (w − 1)·t and row ⌈Y⌉ with Y = (h − 1)·(1 − t) (t the fraction
/// along the axis), and this map puts v at (X, Y + 1), which lies inside that column and
/// row, at most half a pixel from its centre. Grid lines and ticks (plotters') and curves
/// (ours) therefore agree to within half a pixel, with no bias; a curve on an axis' end
/// value lies on the plotting area's edge (half of its stroke clipped).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelMap {
    /// Width and height of the plotting area in pixels.
    pub size: (u32, u32),
    pub x_range: (f64, f64),
    pub y_range: (f64, f64),
    /// Logarithmic x and y axes.
    pub log: (bool, bool),
}

impl PixelMap {
    /// The fraction along an axis: 0 at its start, 1 at its end.
    fn fraction(v: f64, (a, b): (f64, f64), log: bool) -> f64 {
        if log {
            (v.ln() - a.ln()) / (b.ln() - a.ln())
        } else {
            (v - a) / (b - a)
        }
    }

    /// The pixel position of the value (x, y) (not finite for values a log axis cannot
    /// show, or a zero-length range).
    pub fn to_pixel(&self, (x, y): (f64, f64)) -> (f64, f64) {
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        let tx = Self::fraction(x, self.x_range, self.log.0);
        let ty = Self::fraction(y, self.y_range, self.log.1);
        ((w - 1.0) * tx, (h - 1.0) * (1.0 - ty) + 1.0)
    }

    /// The map of a linear chart's plotting area (the chart's own ranges).
    pub fn of_linear<DB: DrawingBackend>(
        chart: &ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    ) -> PixelMap {
        let area = chart.plotting_area();
        let (xr, yr) = (area.get_x_range(), area.get_y_range());
        PixelMap {
            size: area.dim_in_pixel(),
            x_range: (xr.start, xr.end),
            y_range: (yr.start, yr.end),
            log: (false, false),
        }
    }
}

/// A polyline element for [`DrawingArea::draw`]: points in pixels of the area (f64), its
/// clip rectangle in the same pixels.
struct Smooth<'p> {
    pts: &'p [(f64, f64)],
    width: f64,
    color: RGBColor,
    clip: Rect,
    /// The area's origin; plotters maps it to the area's base pixel on the backend.
    origin: BackendCoord,
}

impl<'a> PointCollection<'a, BackendCoord> for &'a Smooth<'_> {
    type Point = &'a BackendCoord;
    type IntoIter = std::iter::Once<&'a BackendCoord>;
    fn point_iter(self) -> Self::IntoIter {
        std::iter::once(&self.origin)
    }
}

impl<DB: Canvas> Drawable<DB> for Smooth<'_> {
    fn draw<I: Iterator<Item = BackendCoord>>(
        &self,
        mut pos: I,
        backend: &mut DB,
        _: (u32, u32),
    ) -> Result<(), DrawingErrorKind<DB::ErrorType>> {
        let Some(base) = pos.next() else {
            return Ok(());
        };
        let (bx, by) = (base.0 as f64, base.1 as f64);
        let pts: Vec<(f64, f64)> = self.pts.iter().map(|p| (p.0 + bx, p.1 + by)).collect();
        let clip = Rect {
            x: self.clip.x + bx,
            y: self.clip.y + by,
            ..self.clip
        };
        backend.stroke_polyline(&pts, self.width, self.color, clip)
    }
}

/// A line style: width in pixels, and a dash pattern (on, off pixels) or none.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pen {
    pub color: RGBColor,
    pub width: f64,
    pub dash: Option<(f64, f64)>,
}

impl Pen {
    /// A solid line.
    pub fn solid(color: RGBColor, width: f64) -> Pen {
        Pen {
            color,
            width,
            dash: None,
        }
    }

    /// A dashed line.
    pub fn dashed(color: RGBColor, width: f64, on: f64, off: f64) -> Pen {
        Pen {
            color,
            width,
            dash: Some((on, off)),
        }
    }
}

/// Stroke `pts` (pixels of `area`, f64) with `pen`, clipped to the area.
pub fn draw_polyline<DB: Canvas>(
    area: &DrawingArea<DB, Shift>,
    pts: &[(f64, f64)],
    pen: Pen,
) -> Result<(), DrawError<DB>> {
    let (w, h) = area.dim_in_pixel();
    let clip = Rect {
        x: 0.0,
        y: 0.0,
        w: w as f64,
        h: h as f64,
    };
    let pieces = match pen.dash {
        Some((on, off)) => dashes(pts, on, off),
        None => vec![pts.to_vec()],
    };
    for piece in pieces {
        area.draw(&Smooth {
            pts: &piece,
            width: pen.width,
            color: pen.color,
            clip,
            origin: (0, 0),
        })?;
    }
    Ok(())
}

/// Stroke the data polyline `pts` on a chart's plotting area, through `map`, with `pen`.
/// Callers clip the polyline to the axes' ranges first ([`super::xy::clip_polyline`]).
pub fn draw_data_polyline<DB: Canvas, CT: CoordTranslate>(
    plotting_area: &DrawingArea<DB, CT>,
    map: &PixelMap,
    pts: &[(f64, f64)],
    pen: Pen,
) -> Result<(), DrawError<DB>> {
    let px: Vec<(f64, f64)> = pts.iter().map(|&p| map.to_pixel(p)).collect();
    draw_polyline(&plotting_area.strip_coord_spec(), &px, pen)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn clip(w: f64, h: f64) -> Rect {
        Rect {
            x: 0.0,
            y: 0.0,
            w,
            h,
        }
    }

    #[test]
    fn a_straight_stroke_covers_its_width() {
        // A horizontal line at y = 10.3, 2 px wide covers [9.3, 11.3]: rows 9, 10, 11 get
        // 0.7, 1, 0.3 and each column sums to the width.
        let cov = coverage(&[(5.0, 10.3), (45.0, 10.3)], 2.0, clip(60.0, 30.0));
        let col: Vec<f64> = cov
            .iter()
            .filter(|(p, _)| p.0 == 20)
            .map(|(_, a)| *a)
            .collect();
        assert_eq!(col.len(), 3);
        assert!((col[0] - 0.7).abs() < 1e-12 && (col[1] - 1.0).abs() < 1e-12);
        assert!((col[2] - 0.3).abs() < 1e-12);
        assert!((col.iter().sum::<f64>() - 2.0).abs() < 1e-12);
    }

    #[test]
    fn the_clip_rectangle_is_respected() {
        let cov = coverage(&[(-20.0, 5.0), (80.0, 5.0)], 3.0, clip(50.0, 10.0));
        assert!(cov
            .iter()
            .all(|((i, j), _)| (0..50).contains(i) && (0..10).contains(j)));
        assert!(cov.iter().any(|((i, _), _)| *i == 0) && cov.iter().any(|((i, _), _)| *i == 49));
    }

    #[test]
    fn dashes_follow_the_arc_length() {
        // 0 → 30 along x, 8 on 5 off: [0, 8], [13, 21], [26, 30].
        let d = dashes(&[(0.0, 0.0), (10.0, 0.0), (30.0, 0.0)], 8.0, 5.0);
        assert_eq!(d.len(), 3);
        let ends: Vec<(f64, f64)> = d.iter().map(|p| (p[0].0, p.last().unwrap().0)).collect();
        for (got, want) in ends.iter().zip([(0.0, 8.0), (13.0, 21.0), (26.0, 30.0)]) {
            assert!((got.0 - want.0).abs() < 1e-12 && (got.1 - want.1).abs() < 1e-12);
        }
        // The dash that crosses the vertex at x = 10 keeps it.
        assert_eq!(d[1].len(), 2);
        assert_eq!(dashes(&[(0.0, 0.0), (10.0, 0.0)], 8.0, 5.0)[0].len(), 2);
    }

    #[test]
    fn the_map_agrees_with_plotters_rounding() {
        // plotters puts a value in column ⌊X⌋ and row ⌈Y⌉; ours is within half a pixel of
        // that pixel's centre (plus plotters' own 1e-3 nudge), on linear and log axes, and
        // the offsets average to about zero.
        let mut buf = vec![0u8; 300 * 200 * 3];
        let root = BitMapBackend::with_buffer(&mut buf, (300, 200)).into_drawing_area();
        let chart = ChartBuilder::on(&root)
            .margin(7)
            .x_label_area_size(23)
            .y_label_area_size(31)
            .build_cartesian_2d(-1.5..2.25, (0.01..30.0).log_scale())
            .unwrap();
        let area = chart.plotting_area();
        let map = PixelMap {
            size: area.dim_in_pixel(),
            x_range: (-1.5, 2.25),
            y_range: (0.01, 30.0),
            log: (false, true),
        };
        let base = area.get_base_pixel();
        let mut mean = (0.0, 0.0);
        for k in 0..=200 {
            let x = -1.5 + 3.75 * k as f64 / 200.0;
            let y = 0.01 * 3000f64.powf(((k * 37) % 201) as f64 / 200.0);
            let ours = map.to_pixel((x, y));
            let theirs = chart.backend_coord(&(x, y));
            let centre = (
                (theirs.0 - base.0) as f64 + 0.5,
                (theirs.1 - base.1) as f64 + 0.5,
            );
            let d = (ours.0 - centre.0, ours.1 - centre.1);
            assert!(
                d.0.abs() <= 0.502 && d.1.abs() <= 0.502,
                "{x}, {y}: {ours:?} vs {centre:?}"
            );
            mean.0 += d.0 / 201.0;
            mean.1 += d.1 / 201.0;
        }
        assert!(mean.0.abs() < 0.1 && mean.1.abs() < 0.1, "{mean:?}");
    }
}
