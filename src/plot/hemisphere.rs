//! The measured hemisphere beside the fitted one and the residuals, one picture per
//! incidence angle: three discs side by side (measured values, fitted values, standardized
//! residuals), each sample drawn as a dot at its view direction, coloured by its value.
//! Nothing is interpolated: a dot is a measurement (or the fit at it).
//!
//! Projection: the view direction (θr, φr) goes to x = sin θr cos φr, y = sin θr sin φr
//! (its component in the surface plane, as seen from above): the normal at the centre,
//! grazing views on the unit circle, φr = 0 (the mirror side of the plane of incidence) to
//! the right, φr = 90° up. Rings mark θr = 30°, 60° and 90°. The source direction
//! (θi, φr = 180°) and the mirror direction (θi, 0°) are marked.
//!
//! Measured and fitted share one colour scale (logarithmic when the positive values span
//! more than a decade, as BRDFs and radiances do); the residuals have a diverging scale
//! symmetric about 0 (blue: fitted below measured, red: above).

use super::fit::input::{checked_groups, group_label, quantity_desc, FitPlotInput, Group};
use super::legend::{sequential_color, text_width, Entry, Glyph, Marker};
use super::stroke::{draw_polyline, Canvas, Pen};
use super::ticks::{linear_ticks, log_ticks, nice_step};
use super::{fmt_num, fmt_tick, font, DrawError, Picture};
use crate::error::Result;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use std::f64::consts::PI;

/// At most this many incidence angles get a hemisphere picture (those with the most
/// samples).
pub(crate) const MAX_HEMISPHERES: usize = 4;

/// The projected position of the view direction (θr, φr) (radians):
/// (sin θr cos φr, sin θr sin φr), inside the unit disc for θr ∈ [0, 90°].
pub(crate) fn project(theta_r: f64, phi_r: f64) -> (f64, f64) {
    let s = theta_r.sin();
    (s * phi_r.cos(), s * phi_r.sin())
}

/// A colour scale for values: linear or logarithmic over [lo, hi].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ValueScale {
    /// The value at the scale's dark (purple) end, in the values' unit; > 0 on a log scale.
    pub lo: f64,
    /// The value at the scale's light (yellow-green) end, in the values' unit.
    pub hi: f64,
    /// Colours by ln v between `lo` and `hi` (values ≤ 0 take the `lo` colour); false:
    /// linearly in v.
    pub log: bool,
}

impl ValueScale {
    /// The scale of `values` (non-finite ones ignored): logarithmic over the positive
    /// values when they span more than a factor 10 (the lowest kept at ≥ 1e-6 × the
    /// highest), else linear over all of them. A constant or empty set gets a unit range.
    pub(crate) fn of(values: impl Iterator<Item = f64>) -> ValueScale {
        let v: Vec<f64> = values.filter(|v| v.is_finite()).collect();
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let pos_lo = v
            .iter()
            .copied()
            .filter(|&x| x > 0.0)
            .fold(f64::INFINITY, f64::min);
        if hi > 0.0 && pos_lo.is_finite() && hi > 10.0 * pos_lo {
            return ValueScale {
                lo: pos_lo.max(1e-6 * hi),
                hi,
                log: true,
            };
        }
        if !(lo.is_finite() && hi.is_finite()) {
            return ValueScale {
                lo: 0.0,
                hi: 1.0,
                log: false,
            };
        }
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo - 0.5, hi + 0.5)
        };
        ValueScale { lo, hi, log: false }
    }

    /// Where `v` lies on the scale, clamped to [0, 1] (values ≤ 0 on a log scale: 0).
    pub(crate) fn fraction(&self, v: f64) -> f64 {
        let f = if self.log {
            if v <= 0.0 {
                return 0.0;
            }
            (v / self.lo).ln() / (self.hi / self.lo).ln()
        } else {
            (v - self.lo) / (self.hi - self.lo)
        };
        if f.is_finite() {
            f.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }

    /// Nice tick values inside the range ([`log_ticks`] or [`linear_ticks`]).
    pub(crate) fn ticks(&self) -> Vec<f64> {
        if self.log {
            log_ticks(self.lo, self.hi)
        } else {
            linear_ticks(self.lo, self.hi, 5)
        }
    }
}

/// A diverging colour (blue – white – red) for `t` ∈ [−1, 1] (clamped; NaN: white).
pub(crate) fn diverging_color(t: f64) -> RGBColor {
    const BLUE: [f64; 3] = [33.0, 102.0, 172.0];
    const RED: [f64; 3] = [178.0, 24.0, 43.0];
    let t = if t.is_finite() {
        t.clamp(-1.0, 1.0)
    } else {
        0.0
    };
    let end = if t < 0.0 { BLUE } else { RED };
    let a = t.abs();
    let mix = |j: usize| (247.0 + a * (end[j] - 247.0)).round() as u8;
    RGBColor(mix(0), mix(1), mix(2))
}

/// One incidence angle's hemisphere: the samples' projected positions and their measured,
/// fitted and standardized residual values.
#[derive(Debug, Clone)]
pub(crate) struct HemispherePlot {
    /// The first title line: the fit's title and this incidence angle.
    pub title: String,
    /// A second title line (the fit's status); empty for none.
    pub subtitle: String,
    /// Which incidence angle this is, and of how many.
    pub caption: String,
    /// The incidence angle (radians).
    pub theta_i: f64,
    /// Per sample, its position from [`project`].
    pub points: Vec<(f64, f64)>,
    /// Per sample, the measured value (the fit's quantity, in the data's unit), the left
    /// disc's colours.
    pub measured: Vec<f64>,
    /// Per sample, the fitted model's value there (same unit), the middle disc's colours.
    pub fitted: Vec<f64>,
    /// Per sample, its standardized residual ([`FitPlotInput::std_residuals`]; unitless),
    /// the right disc's colours: red where the fit lies above the measurement, blue below.
    pub residuals: Vec<f64>,
    /// The scale shared by measured and fitted values.
    pub scale: ValueScale,
    /// The residual scale runs from −limit to +limit.
    pub residual_limit: f64,
    /// What the values are (for the colour bar).
    pub value_desc: String,
    /// Per sample, its dot's radius in pixels.
    pub dots: Vec<f64>,
}

/// The groups to draw: up to [`MAX_HEMISPHERES`] with the most samples (ties: lower θi
/// first), in the order of `gs` (by θi).
pub(crate) fn chosen_groups(gs: &[Group]) -> Vec<&Group> {
    let mut order: Vec<usize> = (0..gs.len()).collect();
    order.sort_by(|&a, &b| gs[b].idx.len().cmp(&gs[a].idx.len()).then(a.cmp(&b)));
    order.truncate(MAX_HEMISPHERES);
    order.sort_unstable();
    order.into_iter().map(|k| &gs[k]).collect()
}

/// The hemisphere pictures of a fit: one per chosen incidence angle ([`chosen_groups`]).
pub(crate) fn hemisphere_plots(input: &FitPlotInput) -> Result<Vec<HemispherePlot>> {
    let gs = checked_groups(input)?;
    let multi = gs.iter().any(|g| g.wavelength != gs[0].wavelength);
    let chosen = chosen_groups(&gs);
    let capped = gs.len() > chosen.len();
    let which = |k: usize| {
        if capped {
            format!(
                "one of the {} incidence angles with the most samples, of {}",
                chosen.len(),
                gs.len()
            )
        } else {
            format!("incidence angle {} of {}", k + 1, gs.len())
        }
    };
    Ok(chosen
        .iter()
        .enumerate()
        .map(|(k, g)| {
            let label = group_label(g, multi, input);
            let caption = format!("{label} ({} samples; {})", g.idx.len(), which(k));
            one_hemisphere(input, g, caption)
        })
        .collect())
}

/// The picture of group `g`.
fn one_hemisphere(input: &FitPlotInput, g: &Group, caption: String) -> HemispherePlot {
    let geo = input.geo;
    let pick = |v: &[f64]| g.idx.iter().map(|&k| v[k]).collect::<Vec<f64>>();
    let points: Vec<(f64, f64)> = g
        .idx
        .iter()
        .map(|&k| project(geo.theta_r[k], geo.phi_r[k]))
        .collect();
    let (measured, fitted, residuals) = (
        pick(input.measured),
        pick(input.fitted),
        pick(input.std_residuals),
    );
    let scale = ValueScale::of(measured.iter().chain(&fitted).copied());
    let dots = dot_radii(&points, DISC_R);
    HemispherePlot {
        title: format!(
            "{} — hemisphere at θi = {}°",
            input.title,
            fmt_num(g.theta_i.to_degrees())
        ),
        subtitle: input.subtitle.clone(),
        caption,
        theta_i: g.theta_i,
        residual_limit: residual_limit(&residuals),
        points,
        measured,
        fitted,
        residuals,
        scale,
        value_desc: quantity_desc(geo.quantity).to_string(),
        dots,
    }
}

/// The residual scale's half-width: a nice number (1, 2, 2.5, 5 × 10ᵏ) at or above the
/// 98th percentile of |r|, at least 2 (so a good fit looks pale).
pub(crate) fn residual_limit(r: &[f64]) -> f64 {
    let mut a: Vec<f64> = r
        .iter()
        .map(|v| v.abs())
        .filter(|v| v.is_finite())
        .collect();
    if a.is_empty() {
        return 2.0;
    }
    a.sort_by(f64::total_cmp);
    let q = a[((a.len() - 1) as f64 * 0.98).round() as usize];
    nice_step(q.max(2.0))
}

/// Dot radii (pixels) for points in a disc of `disc_r` pixels: a third of the median
/// distance to the nearest other point (between 2.5 and 9 pixels), smaller for a point
/// whose nearest neighbour is closer (0.45 × that distance, at least 1.5 pixels), so that
/// dense spots do not hide their samples.
fn dot_radii(points: &[(f64, f64)], disc_r: f64) -> Vec<f64> {
    if points.len() < 2 {
        return vec![7.0; points.len()];
    }
    let nn: Vec<f64> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let d = points
                .iter()
                .enumerate()
                .filter(|&(j, _)| j != i)
                .map(|(_, q)| (p.0 - q.0).hypot(p.1 - q.1))
                .fold(f64::INFINITY, f64::min);
            d * disc_r
        })
        .collect();
    let mut sorted = nn.clone();
    sorted.sort_by(f64::total_cmp);
    let global = (sorted[sorted.len() / 2] / 3.0).clamp(2.5, 9.0);
    nn.iter().map(|d| (0.45 * d).clamp(1.5, global)).collect()
}

/// Radius of each disc (pixels).
pub(crate) const DISC_R: f64 = 165.0;
/// Width of each panel (pixels).
const PANEL_W: u32 = 430;
/// Colour bar size (pixels).
const BAR_W: i32 = 300;
const BAR_H: i32 = 14;
const SOURCE: RGBColor = RGBColor(230, 120, 0);
const GRID: RGBColor = RGBColor(170, 170, 170);
const RING: RGBColor = RGBColor(200, 200, 200);

impl HemispherePlot {
    /// The legend line under the titles.
    pub(crate) fn legend_entries(&self) -> Vec<Entry> {
        let ti = fmt_num(self.theta_i.to_degrees());
        vec![
            Entry {
                glyph: Glyph::Point {
                    color: RGBColor(90, 90, 90),
                    marker: Marker::Filled,
                    r: 5,
                },
                label: format!("a measured sample ({} here)", self.points.len()),
            },
            Entry {
                glyph: Glyph::Point {
                    color: SOURCE,
                    marker: Marker::Triangle,
                    r: 6,
                },
                label: format!("source direction (θr = {ti}°, φr = 180°)"),
            },
            Entry {
                glyph: Glyph::Point {
                    color: BLACK,
                    marker: Marker::Open,
                    r: 6,
                },
                label: format!("mirror direction (θr = {ti}°, φr = 0°)"),
            },
        ]
    }

    /// The colour of each dot of panel `k` (0 measured, 1 fitted, 2 residual).
    fn colors(&self, k: usize) -> Vec<RGBColor> {
        match k {
            0 | 1 => {
                let v = if k == 0 { &self.measured } else { &self.fitted };
                v.iter()
                    .map(|&x| sequential_color(self.scale.fraction(x)))
                    .collect()
            }
            _ => self
                .residuals
                .iter()
                .map(|&r| diverging_color(r / self.residual_limit))
                .collect(),
        }
    }
}

impl Picture for HemispherePlot {
    fn size(&self) -> (u32, u32) {
        (3 * PANEL_W, 600)
    }

    fn draw<DB: Canvas>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError<DB>> {
        let root = super::xy::draw_titles(root, &self.title, &self.subtitle)?;
        let (top, root) = root.split_vertically(2 * super::legend::LINE_H + 4);
        super::legend::draw_rows(&top, &self.legend_entries())?;
        let (w, _) = top.dim_in_pixel();
        top.draw_text(
            &self.caption,
            &font(14.0)
                .color(&RGBColor(60, 60, 60))
                .pos(Pos::new(HPos::Center, VPos::Center)),
            (w as i32 / 2, super::legend::LINE_H as i32 * 3 / 2),
        )?;
        let panels = root.split_evenly((1, 3));
        let heads = [
            "measured",
            "fitted (same colour scale)",
            "standardized residual (fitted − measured) / u",
        ];
        for (k, panel) in panels.iter().enumerate() {
            self.draw_panel(panel, heads[k], k)?;
        }
        Ok(())
    }
}

impl HemispherePlot {
    /// One disc with its heading, grid, dots, direction marks and colour bar.
    fn draw_panel<DB: Canvas>(
        &self,
        area: &DrawingArea<DB, Shift>,
        head: &str,
        k: usize,
    ) -> std::result::Result<(), DrawError<DB>> {
        let (w, _) = area.dim_in_pixel();
        let centre = (w as f64 / 2.0, 24.0 + DISC_R + 22.0);
        let px = |p: (f64, f64)| (centre.0 + DISC_R * p.0, centre.1 - DISC_R * p.1);
        area.draw_text(
            head,
            &font(15.0)
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Top)),
            (w as i32 / 2, 2),
        )?;
        draw_disc_grid(area, centre)?;
        let colors = self.colors(k);
        for ((p, c), r) in self.points.iter().zip(colors).zip(&self.dots) {
            let (x, y) = px(*p);
            let at = (x.round() as i32, y.round() as i32);
            let r = r.round() as u32;
            area.draw(&Circle::new(at, r, c.filled()))?;
            if r >= 4 {
                area.draw(&Circle::new(at, r, RGBColor(80, 80, 80).stroke_width(1)))?;
            }
        }
        self.draw_directions(area, &px)?;
        let bar_top = (centre.1 + DISC_R + 34.0) as i32;
        let x0 = (w as i32 - BAR_W) / 2;
        if k < 2 {
            let s = self.scale;
            let desc = format!(
                "{}{}",
                self.value_desc,
                if s.log { ", log scale" } else { "" }
            );
            let fraction = |v: f64| s.fraction(v);
            draw_bar(
                area,
                (x0, bar_top),
                &|t| sequential_color(t),
                &s.ticks(),
                &fraction,
                &desc,
            )
        } else {
            let m = self.residual_limit;
            let ticks = linear_ticks(-m, m, 4);
            let fraction = |v: f64| (v + m) / (2.0 * m);
            let desc = format!("beyond ±{} drawn at the ends", fmt_num(m));
            draw_bar(
                area,
                (x0, bar_top),
                &|t| diverging_color(2.0 * t - 1.0),
                &ticks,
                &fraction,
                &desc,
            )
        }
    }

    /// The source and mirror directions.
    fn draw_directions<DB: Canvas>(
        &self,
        area: &DrawingArea<DB, Shift>,
        px: &dyn Fn((f64, f64)) -> (f64, f64),
    ) -> std::result::Result<(), DrawError<DB>> {
        let (sx, sy) = px(project(self.theta_i, PI));
        let (mx, my) = px(project(self.theta_i, 0.0));
        let (sx, sy, mx, my) = (
            sx.round() as i32,
            sy.round() as i32,
            mx.round() as i32,
            my.round() as i32,
        );
        area.draw(&Polygon::new(
            vec![(sx, sy - 8), (sx - 7, sy + 5), (sx + 7, sy + 5)],
            SOURCE.filled(),
        ))?;
        area.draw(&Circle::new((mx, my), 8, BLACK.stroke_width(2)))?;
        Ok(())
    }
}

/// The disc's outline (θr = 90°), the rings at θr = 30° and 60°, the φr axes and their
/// labels, around pixel `c`.
fn draw_disc_grid<DB: Canvas>(
    area: &DrawingArea<DB, Shift>,
    c: (f64, f64),
) -> std::result::Result<(), DrawError<DB>> {
    let ring = |deg: f64| -> Vec<(f64, f64)> {
        let r = DISC_R * deg.to_radians().sin();
        (0..=180)
            .map(|k| {
                let a = k as f64 * 2.0 * PI / 180.0;
                (c.0 + r * a.cos(), c.1 - r * a.sin())
            })
            .collect()
    };
    draw_polyline(area, &ring(90.0), Pen::solid(RGBColor(90, 90, 90), 1.5))?;
    for deg in [30.0, 60.0] {
        draw_polyline(area, &ring(deg), Pen::solid(RING, 1.0))?;
    }
    let axis = |a: f64| {
        let (dx, dy) = (a.cos(), -a.sin());
        [
            (c.0 - DISC_R * dx, c.1 - DISC_R * dy),
            (c.0 + DISC_R * dx, c.1 + DISC_R * dy),
        ]
    };
    draw_polyline(area, &axis(0.0), Pen::solid(GRID, 1.0))?;
    draw_polyline(area, &axis(0.5 * PI), Pen::solid(GRID, 1.0))?;
    let grey = RGBColor(90, 90, 90);
    let style = |h, v| font(12.0).color(&grey).pos(Pos::new(h, v));
    let at = |x: f64, y: f64| (x.round() as i32, y.round() as i32);
    // θr labels outside each ring, 30° and 60° along the lower-left diagonal, 90° (the
    // outline, too close to 60° there) further down; φr labels outside the disc.
    for (deg, angle) in [(30.0, -0.75 * PI), (60.0, -0.75 * PI), (90.0, -0.62 * PI)] {
        let d = f64::sin_cos(angle);
        let r = DISC_R * f64::to_radians(deg).sin() + 3.0;
        let (x, y) = (c.0 + r * d.1, c.1 - r * d.0);
        area.draw_text(
            &format!("θr {deg}°"),
            &style(HPos::Right, VPos::Top),
            at(x, y),
        )?;
    }
    let r = DISC_R + 4.0;
    area.draw_text("0°", &style(HPos::Left, VPos::Center), at(c.0 + r, c.1))?;
    area.draw_text("180°", &style(HPos::Right, VPos::Center), at(c.0 - r, c.1))?;
    area.draw_text(
        "φr = 90°",
        &style(HPos::Center, VPos::Bottom),
        at(c.0, c.1 - r),
    )?;
    area.draw_text("−90°", &style(HPos::Center, VPos::Top), at(c.0, c.1 + r))?;
    Ok(())
}

/// A horizontal colour bar at pixel `at` ([`BAR_W`] × [`BAR_H`]): `color` of the fraction
/// along it, a labelled tick at each of `ticks` (placed by `fraction`; labels closer than
/// their width left out), and `desc` under it.
fn draw_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x0, y0): (i32, i32),
    color: &dyn Fn(f64) -> RGBColor,
    ticks: &[f64],
    fraction: &dyn Fn(f64) -> f64,
    desc: &str,
) -> std::result::Result<(), DrawError<DB>> {
    // Steps of 4 pixels (75 colours) keep the SVG small; each step reaches 1 pixel into the
    // next, so that a viewer's anti-aliasing leaves no pale seam between them.
    for i in (0..BAR_W).step_by(4) {
        let t = (i as f64 + 2.0) / BAR_W as f64;
        let right = (i + 5).min(BAR_W);
        area.draw(&Rectangle::new(
            [(x0 + i, y0), (x0 + right, y0 + BAR_H)],
            color(t).filled(),
        ))?;
    }
    area.draw(&Rectangle::new(
        [(x0, y0), (x0 + BAR_W, y0 + BAR_H)],
        RGBColor(120, 120, 120).stroke_width(1),
    ))?;
    let label = font(12.0)
        .color(&BLACK)
        .pos(Pos::new(HPos::Center, VPos::Top));
    let mut right_of_last = i32::MIN;
    for &v in ticks {
        let x = x0 + (fraction(v) * BAR_W as f64).round() as i32;
        area.draw(&PathElement::new(
            vec![(x, y0 + BAR_H), (x, y0 + BAR_H + 4)],
            BLACK.stroke_width(1),
        ))?;
        let text = fmt_tick(v);
        let half = text_width(&text, 12.0) as i32 / 2;
        if x - half > right_of_last + 6 {
            area.draw_text(&text, &label, (x, y0 + BAR_H + 6))?;
            right_of_last = x + half;
        }
    }
    area.draw_text(
        desc,
        &font(13.0)
            .color(&RGBColor(60, 60, 60))
            .pos(Pos::new(HPos::Center, VPos::Top)),
        (x0 + BAR_W / 2, y0 + BAR_H + 24),
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn projection_closed_forms() {
        let close =
            |a: (f64, f64), b: (f64, f64)| (a.0 - b.0).abs() < 1e-15 && (a.1 - b.1).abs() < 1e-15;
        // The normal at the centre, whatever φr.
        assert!(close(project(0.0, 1.234), (0.0, 0.0)));
        // θr = 30°: radius sin 30° = 1/2; φr = 0 to the right, 90° up, 180° left.
        let t = 30f64.to_radians();
        assert!(close(project(t, 0.0), (0.5, 0.0)));
        assert!(close(project(t, 0.5 * PI), (0.0, 0.5)));
        assert!(close(project(t, PI), (-0.5, 0.0)));
        // θr = 60°, φr = −45°: radius √3/2, at (√3/2)(1/√2, −1/√2) = (√6/4, −√6/4).
        let p = project(60f64.to_radians(), -45f64.to_radians());
        let e = 6f64.sqrt() / 4.0;
        assert!((p.0 - e).abs() < 1e-15 && (p.1 + e).abs() < 1e-15, "{p:?}");
        // Grazing views on the unit circle.
        let g = project(0.5 * PI, 2.0);
        assert!((g.0.hypot(g.1) - 1.0).abs() < 1e-15);
    }

    #[test]
    fn value_scale_is_log_over_decades_and_linear_otherwise() {
        let s = ValueScale::of([1e-3, 0.5, 2.0, -0.01].into_iter());
        assert!(s.log && s.lo == 1e-3 && s.hi == 2.0);
        assert_eq!(s.fraction(1e-3), 0.0);
        assert_eq!(s.fraction(-0.01), 0.0);
        // √(1e-3 · 2) is half-way on a log scale.
        assert!((s.fraction((2e-3f64).sqrt()) - 0.5).abs() < 1e-12);
        let s = ValueScale::of([0.1, 0.3, 0.5].into_iter());
        assert!(!s.log);
        assert!((s.fraction(0.2) - 0.25).abs() < 1e-12);
        assert_eq!(s.ticks(), vec![0.1, 0.2, 0.3, 0.4, 0.5]);
        let s = ValueScale::of([f64::NAN, 3.0].into_iter());
        assert_eq!((s.lo, s.hi, s.log), (2.5, 3.5, false));
    }

    #[test]
    fn residual_limit_is_nice_and_at_least_two() {
        assert_eq!(residual_limit(&[0.1, -0.3]), 2.0);
        // 98th percentile of |r| = 3.1 → 5.
        let r: Vec<f64> = (0..100)
            .map(|k| if k % 2 == 0 { 3.1 } else { -1.0 })
            .collect();
        assert_eq!(residual_limit(&r), 5.0);
        assert_eq!(residual_limit(&[]), 2.0);
    }

    #[test]
    fn diverging_scale_is_white_at_zero() {
        assert_eq!(diverging_color(0.0), RGBColor(247, 247, 247));
        assert_eq!(diverging_color(-1.0), RGBColor(33, 102, 172));
        assert_eq!(diverging_color(5.0), RGBColor(178, 24, 43));
    }

    #[test]
    fn the_busiest_groups_are_kept_in_theta_order() {
        let g = |ti: f64, n: usize| Group {
            theta_i: ti,
            wavelength: 1.0,
            channel: 0,
            idx: (0..n).collect(),
        };
        let gs = vec![
            g(0.0, 3),
            g(0.1, 9),
            g(0.2, 5),
            g(0.3, 9),
            g(0.4, 1),
            g(0.5, 5),
        ];
        let kept: Vec<f64> = chosen_groups(&gs).iter().map(|g| g.theta_i).collect();
        assert_eq!(kept, vec![0.1, 0.2, 0.3, 0.5]);
    }
}
