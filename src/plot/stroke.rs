//! Lines at sub-pixel positions.
//!
//! plotters' backends take integer pixel coordinates, so a curve sampled every pixel or two
//! and drawn through them is stair-stepped (each vertex moved by up to half a pixel). Here a
//! polyline is stroked at `f64` pixel positions instead, through the [`Canvas`] trait
//! (implemented by [`super::svg::SvgCanvas`], which writes the polyline into the SVG
//! document; the PNG is that document rendered by resvg).
//!
//! Pixel convention: pixel (i, j) is the unit square [i, i+1) × [j, j+1), its centre at
//! (i + ½, j + ½); a stroke of width w is the set of points within w/2 of the polyline.

use super::marks::Rect;
use super::DrawError;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::element::{Drawable, PointCollection};
use plotters::prelude::*;
use plotters_backend::{BackendCoord, DrawingErrorKind};

/// A backend that can stroke polylines at sub-pixel positions.
pub(crate) trait Canvas: DrawingBackend {
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

/// The dashes of `pts`: pieces `on` pixels long, `off` pixels apart, measured along the
/// polyline from its start. `on` ≤ 0 or `off` ≤ 0 gives the whole polyline.
pub(crate) fn dashes(pts: &[(f64, f64)], on: f64, off: f64) -> Vec<Vec<(f64, f64)>> {
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
pub(crate) struct PixelMap {
    /// Width and height of the plotting area in pixels.
    pub size: (u32, u32),
    /// The data x at the plotting area's left and right edges (both > 0 on a log axis).
    pub x_range: (f64, f64),
    /// The data y at the plotting area's bottom and top edges (both > 0 on a log axis).
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
    pub(crate) fn to_pixel(self, (x, y): (f64, f64)) -> (f64, f64) {
        let (w, h) = (self.size.0 as f64, self.size.1 as f64);
        let tx = Self::fraction(x, self.x_range, self.log.0);
        let ty = Self::fraction(y, self.y_range, self.log.1);
        ((w - 1.0) * tx, (h - 1.0) * (1.0 - ty) + 1.0)
    }

    /// The map of a linear chart's plotting area (the chart's own ranges).
    pub(crate) fn of_linear<DB: DrawingBackend>(
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
pub(crate) struct Pen {
    /// The stroke's colour, opaque.
    pub color: RGBColor,
    /// The stroke's width in pixels (sub-pixel widths allowed).
    pub width: f64,
    /// Dashes `on` pixels long, `off` pixels apart, measured along the line (the pattern
    /// runs on across vertices); None: a solid line.
    pub dash: Option<(f64, f64)>,
}

impl Pen {
    /// A solid line.
    pub(crate) fn solid(color: RGBColor, width: f64) -> Pen {
        Pen {
            color,
            width,
            dash: None,
        }
    }

    /// A dashed line.
    pub(crate) fn dashed(color: RGBColor, width: f64, on: f64, off: f64) -> Pen {
        Pen {
            color,
            width,
            dash: Some((on, off)),
        }
    }
}

/// Stroke `pts` (pixels of `area`, f64) with `pen`, clipped to the area.
pub(crate) fn draw_polyline<DB: Canvas>(
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
pub(crate) fn draw_data_polyline<DB: Canvas, CT: CoordTranslate>(
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
        let mut svg = String::new();
        let root = SVGBackend::with_string(&mut svg, (300, 200)).into_drawing_area();
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
