//! The pictures of a finished fit: measured vs fitted (linear and log), standardized
//! residuals over θr and φr, the fitted lobe as a polar plot, and the fitted model as a
//! contour map over (θr, φr) with the sample positions.
//!
//! In-plane views use the signed view angle: θr for |φr| ≤ 90° (the forward side), −θr for
//! |φr| > 90° (toward the source). A sample is in the plane of incidence when its φr is
//! within 1° of 0° or 180°; an incidence angle with no such sample shows its samples
//! nearest to the plane instead.

use super::contour::{linspace, Grid};
use super::figures::{ContourPlot, LEVELS};
use super::xy::{Kind, LegendAt, Series, XyPlot};
use super::{fmt_num, font, series_color, write_png_svg, DrawError, Picture};
use crate::error::{Error, Result};
use crate::geometry::{Geometry, Quantity, Sample};
use crate::model::Model;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// What the fit pictures need.
pub struct FitPlotInput<'a> {
    /// Model name and fitted parameters.
    pub title: String,
    pub model: &'a dyn Model,
    pub params: &'a [f64],
    /// Sample geometry (radians), quantity, wavelength.
    pub geo: &'a Geometry,
    pub measured: &'a [f64],
    pub fitted: &'a [f64],
    pub std_residuals: &'a [f64],
}

/// Tolerance on φr (radians) for a sample to count as in the plane of incidence.
const PLANE_TOL: f64 = PI / 180.0;

/// Samples sharing an incidence angle (and wavelength).
#[derive(Debug, Clone)]
pub struct Group {
    pub theta_i: f64,
    pub wavelength: f64,
    pub idx: Vec<usize>,
}

/// Group samples by θi (to 1e-4°) and wavelength (to 1e-9 relative), sorted by θi.
pub fn groups(geo: &Geometry) -> Vec<Group> {
    let mut out: Vec<Group> = Vec::new();
    for k in 0..geo.len() {
        let (ti, wl) = (geo.theta_i[k], geo.wavelength[k]);
        let same = |g: &Group| {
            (g.theta_i - ti).abs().to_degrees() < 1e-4
                && (g.wavelength - wl).abs() <= 1e-9 * wl.abs()
        };
        match out.iter_mut().find(|g| same(g)) {
            Some(g) => g.idx.push(k),
            None => out.push(Group {
                theta_i: ti,
                wavelength: wl,
                idx: vec![k],
            }),
        }
    }
    out.sort_by(|a, b| {
        a.theta_i
            .total_cmp(&b.theta_i)
            .then(a.wavelength.total_cmp(&b.wavelength))
    });
    out
}

/// Signed view angle in degrees: θr on the forward side (|φr| ≤ 90°), −θr otherwise.
pub fn signed_theta_r_deg(theta_r: f64, phi_r: f64) -> f64 {
    if phi_r.abs() > 0.5 * PI {
        -theta_r.to_degrees()
    } else {
        theta_r.to_degrees()
    }
}

/// Distance of φr (wrapped) from the plane of incidence, radians.
fn plane_distance(phi_r: f64) -> f64 {
    let a = crate::geometry::wrap_phi(phi_r).abs();
    a.min(PI - a)
}

/// The samples of `g` in the plane of incidence, or, when there are none, those nearest
/// to it; and whether they are truly in the plane.
pub fn plane_samples(geo: &Geometry, g: &Group) -> (Vec<usize>, bool) {
    let dmin = g
        .idx
        .iter()
        .map(|&k| plane_distance(geo.phi_r[k]))
        .fold(f64::INFINITY, f64::min);
    let in_plane = dmin <= PLANE_TOL;
    let limit = if in_plane {
        PLANE_TOL
    } else {
        dmin + PLANE_TOL
    };
    let idx = g
        .idx
        .iter()
        .copied()
        .filter(|&k| plane_distance(geo.phi_r[k]) <= limit)
        .collect();
    (idx, in_plane)
}

/// The measured quantity of `model` at `samples` (one wavelength), 0 where not finite.
fn eval_at(
    model: &dyn Model,
    params: &[f64],
    samples: &[Sample],
    wavelength: f64,
    quantity: Quantity,
) -> Result<Vec<f64>> {
    let geo = Geometry::new(samples, &[wavelength], quantity)?;
    let mut out = vec![0.0; samples.len()];
    model.eval(&geo, params, &mut out, None);
    Ok(out)
}

/// Samples along the plane of incidence at θi, signed θr from −90° to 90°.
fn plane_curve_samples(theta_i: f64, n: usize) -> (Vec<f64>, Vec<Sample>) {
    let xs = linspace(-90.0, 90.0, n);
    let samples = xs
        .iter()
        .map(|&s| Sample {
            theta_i,
            theta_r: s.abs().to_radians(),
            phi_r: if s < 0.0 { PI } else { 0.0 },
        })
        .collect();
    (xs, samples)
}

fn quantity_desc(q: Quantity) -> &'static str {
    match q {
        Quantity::Radiance => "radiance L (data units)",
        Quantity::Brdf => "BRDF (data units)",
    }
}

fn group_label(g: &Group, multi_wavelength: bool) -> String {
    let mut s = format!("θi = {}°", fmt_num(g.theta_i.to_degrees()));
    if multi_wavelength {
        s.push_str(&format!(", λ = {}", fmt_num(g.wavelength)));
    }
    s
}

/// Validate the slices against the geometry.
fn check(input: &FitPlotInput) -> Result<()> {
    let n = input.geo.len();
    for (name, len) in [
        ("measured", input.measured.len()),
        ("fitted", input.fitted.len()),
        ("std_residuals", input.std_residuals.len()),
    ] {
        if len != n {
            return Err(Error::Usage(format!(
                "fit plots: {name} has {len} values for {n} samples"
            )));
        }
    }
    crate::model::check_param_count(input.model, input.params)?;
    if n == 0 {
        return Err(Error::Usage("fit plots: no samples".into()));
    }
    Ok(())
}

/// The input checked, and its samples grouped by (θi, λ).
fn checked_groups(input: &FitPlotInput) -> Result<Vec<Group>> {
    check(input)?;
    Ok(groups(input.geo))
}

/// Measured vs fitted over signed θr for each θi (in-plane samples). `log_y` for the
/// logarithmic version.
pub fn fit_chart(input: &FitPlotInput, log_y: bool) -> Result<XyPlot> {
    let gs = checked_groups(input)?;
    let geo = input.geo;
    let multi = gs.iter().any(|g| g.wavelength != gs[0].wavelength);
    let mut plot = XyPlot::new(
        format!(
            "{} — measured vs fitted{}",
            input.title,
            if log_y { " (log scale)" } else { "" }
        ),
        "signed θr (degrees; θr < 0: φr = 180°, the source side)",
        quantity_desc(geo.quantity),
    );
    plot.x_range = (-90.0, 90.0);
    plot.log_y = log_y;
    plot.legend_at = LegendAt::UpperLeft;
    let mut any_near = false;
    let mut yvals = Vec::new();
    for (c, g) in gs.iter().enumerate() {
        let color = series_color(c);
        let (idx, in_plane) = plane_samples(geo, g);
        any_near |= !in_plane;
        // (signed θr in degrees, value) along the plane, in order of angle.
        let along = |values: &[f64]| {
            let mut pts: Vec<(f64, f64)> = idx
                .iter()
                .map(|&k| (signed_theta_r_deg(geo.theta_r[k], geo.phi_r[k]), values[k]))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            pts
        };
        let meas = along(input.measured);
        let fit_pts = along(input.fitted);
        yvals.extend(meas.iter().chain(&fit_pts).map(|p| p.1));
        // A smooth model curve along the plane when the samples are in it and the model
        // reproduces the fitted values there; otherwise the fitted values joined.
        let curve = if in_plane {
            dense_plane_curve(input, g, &idx)?
        } else {
            None
        };
        plot.series.push(Series {
            label: Some(group_label(g, multi)),
            color,
            kind: Kind::Line(2),
            points: curve.unwrap_or(fit_pts),
        });
        plot.series.push(Series {
            label: None,
            color,
            kind: Kind::Points(4),
            points: meas,
        });
    }
    plot.series.push(Series {
        label: Some("measured (points)".into()),
        color: BLACK,
        kind: Kind::Points(4),
        points: vec![],
    });
    plot.series.push(Series {
        label: Some(if any_near {
            "fitted (lines; nearest-to-plane samples)".into()
        } else {
            "fitted model (lines)".into()
        }),
        color: BLACK,
        kind: Kind::Line(2),
        points: vec![],
    });
    // The y range covers the data, not the model's far tails.
    let keep = |y: &f64| y.is_finite() && (!log_y || *y > 0.0);
    let ys: Vec<f64> = yvals.into_iter().filter(keep).collect();
    let lo = ys.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = ys.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if lo.is_finite() && hi.is_finite() {
        if log_y {
            let (lo, hi) = if hi > lo {
                (lo, hi)
            } else {
                (lo / 2.0, hi * 2.0)
            };
            let pad = (hi / lo).powf(0.08);
            plot.y_range = (lo / pad, hi * pad.powi(2));
        } else {
            let lo = lo.min(0.0);
            let span = if hi > lo { hi - lo } else { 1.0 };
            plot.y_range = (lo, hi + 0.1 * span);
        }
    } else if log_y {
        plot.y_range = (1e-3, 1.0);
    }
    Ok(plot)
}

fn dense_plane_curve(
    input: &FitPlotInput,
    g: &Group,
    idx: &[usize],
) -> Result<Option<Vec<(f64, f64)>>> {
    let geo = input.geo;
    let at: Vec<Sample> = idx
        .iter()
        .map(|&k| Sample {
            theta_i: geo.theta_i[k],
            theta_r: geo.theta_r[k],
            phi_r: geo.phi_r[k],
        })
        .collect();
    let here = eval_at(input.model, input.params, &at, g.wavelength, geo.quantity)?;
    let scale = idx
        .iter()
        .map(|&k| input.fitted[k].abs())
        .fold(0.0, f64::max);
    let agrees = idx
        .iter()
        .zip(&here)
        .all(|(&k, v)| (v - input.fitted[k]).abs() <= 1e-6 * scale.max(f64::MIN_POSITIVE));
    if !agrees {
        return Ok(None);
    }
    let (xs, samples) = plane_curve_samples(g.theta_i, 361);
    let ys = eval_at(
        input.model,
        input.params,
        &samples,
        g.wavelength,
        geo.quantity,
    )?;
    Ok(Some(xs.into_iter().zip(ys).collect()))
}

/// Standardized residuals over θr (`over_phi` false) or φr (true), coloured by θi.
pub fn residual_chart(input: &FitPlotInput, over_phi: bool) -> Result<XyPlot> {
    let gs = checked_groups(input)?;
    let geo = input.geo;
    let multi = gs.iter().any(|g| g.wavelength != gs[0].wavelength);
    let mut plot = XyPlot::new(
        format!(
            "{} — standardized residuals over {}",
            input.title,
            if over_phi { "φr" } else { "θr" }
        ),
        if over_phi {
            "φr, azimuth from the plane of incidence (degrees; 0 = forward)"
        } else {
            "θr, view angle from the surface normal (degrees)"
        },
        "standardized residual (fitted − measured) / u",
    );
    plot.x_range = if over_phi {
        (-180.0, 180.0)
    } else {
        (0.0, 90.0)
    };
    for (c, g) in gs.iter().enumerate() {
        let pts = g
            .idx
            .iter()
            .map(|&k| {
                let x = if over_phi {
                    geo.phi_r[k].to_degrees()
                } else {
                    geo.theta_r[k].to_degrees()
                };
                (x, input.std_residuals[k])
            })
            .collect();
        plot.series.push(Series {
            label: Some(group_label(g, multi)),
            color: series_color(c),
            kind: Kind::Points(4),
            points: pts,
        });
    }
    plot.hlines = vec![-2.0, 0.0, 2.0];
    plot.fit_y_range();
    let m = plot.y_range.0.abs().max(plot.y_range.1.abs()).max(3.0);
    plot.y_range = (-m, m * 1.35);
    plot.series.push(Series {
        label: Some("±2 and 0 (grey lines)".into()),
        color: RGBColor(150, 150, 150),
        kind: Kind::Line(1),
        points: vec![],
    });
    Ok(plot)
}

/// The group with the most samples (the first such by θi).
fn busiest(gs: &[Group]) -> &Group {
    let mut best = &gs[0];
    for g in gs {
        if g.idx.len() > best.idx.len() {
            best = g;
        }
    }
    best
}

/// The fitted lobe in the plane of incidence at one θi, in polar form: radius L / L_max at
/// the signed view angle from the normal.
#[derive(Debug, Clone)]
pub struct PolarPlot {
    pub title: String,
    pub theta_i: f64,
    /// (signed θr in degrees, L / L_max) of the fitted model.
    pub curve: Vec<(f64, f64)>,
    /// (signed θr in degrees, measured / L_max) of the in-plane samples.
    pub measured: Vec<(f64, f64)>,
    /// The fitted maximum used to normalise, in data units.
    pub l_max: f64,
}

/// The radius (in L / L_max) of the polar plot's rim: values beyond it are drawn there as
/// arrows pointing outwards, counted in the legend.
pub const POLAR_RIM: f64 = 1.15;

impl PolarPlot {
    /// The measured points beyond [`POLAR_RIM`]: (how many, the largest L / L_max).
    pub fn clipped(&self) -> (usize, f64) {
        self.measured
            .iter()
            .filter(|p| p.1.is_finite() && p.1 > POLAR_RIM)
            .fold((0, 0.0f64), |(n, m), p| (n + 1, m.max(p.1)))
    }
}

/// The polar plot of the fit at the θi with the most samples.
pub fn polar_plot(input: &FitPlotInput) -> Result<PolarPlot> {
    let gs = checked_groups(input)?;
    let geo = input.geo;
    let g = busiest(&gs);
    let (xs, samples) = plane_curve_samples(g.theta_i, 361);
    let ys = eval_at(
        input.model,
        input.params,
        &samples,
        g.wavelength,
        geo.quantity,
    )?;
    let l_max = ys
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let norm = if l_max > 0.0 { 1.0 / l_max } else { 0.0 };
    let (idx, _) = plane_samples(geo, g);
    let measured = idx
        .iter()
        .map(|&k| {
            (
                signed_theta_r_deg(geo.theta_r[k], geo.phi_r[k]),
                input.measured[k] * norm,
            )
        })
        .collect();
    Ok(PolarPlot {
        title: format!(
            "{} — fitted lobe in the plane of incidence, θi = {}°",
            input.title,
            fmt_num(g.theta_i.to_degrees())
        ),
        theta_i: g.theta_i,
        curve: xs.into_iter().zip(ys.iter().map(|v| v * norm)).collect(),
        measured,
        l_max,
    })
}

fn polar_xy(theta_deg: f64, r: f64) -> (f64, f64) {
    let t = theta_deg.to_radians();
    (r * t.sin(), r * t.cos())
}

impl Picture for PolarPlot {
    fn size(&self) -> (u32, u32) {
        (900, 580)
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError<DB>> {
        let title_size = super::xy::title_font_size(&self.title, self.size().0);
        let root = root.titled(&self.title, font(title_size))?;
        let (w, h) = root.dim_in_pixel();
        // Equal scales on both axes: the plotting area is (w − 2·16 − 70) × (h − 2·16 − 55).
        let (pw, ph) = (w as f64 - 102.0, h as f64 - 87.0);
        let x_half = 1.18;
        let y_span = 2.0 * x_half * ph / pw;
        let y0 = -0.08;
        let mut chart = ChartBuilder::on(&root)
            .margin(16)
            .x_label_area_size(55)
            .y_label_area_size(70)
            .build_cartesian_2d(-x_half..x_half, y0..y0 + y_span)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("(L / L_max) · sin θr  (signed θr; < 0 toward the source)")
            .y_desc("(L / L_max) · cos θr")
            .x_label_formatter(&|v| super::fmt_tick(*v))
            .y_label_formatter(&|v| super::fmt_tick(*v))
            .label_style(font(14.0))
            .axis_desc_style(font(16.0))
            .draw()?;
        let grey = RGBColor(200, 200, 200);
        for r in [0.25, 0.5, 0.75, 1.0] {
            let arc: Vec<(f64, f64)> = (0..=180).map(|d| polar_xy(d as f64 - 90.0, r)).collect();
            chart.draw_series(std::iter::once(PathElement::new(arc, grey.stroke_width(1))))?;
        }
        for d in (-90..=90).step_by(15) {
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(0.0, 0.0), polar_xy(d as f64, 1.0)],
                grey.stroke_width(1),
            )))?;
            if d % 30 == 0 {
                let p = polar_xy(d as f64, 1.08);
                chart.draw_series(std::iter::once(Text::new(
                    format!("{d}°"),
                    p,
                    font(13.0).color(&RGBColor(100, 100, 100)).pos(
                        plotters::style::text_anchor::Pos::new(
                            plotters::style::text_anchor::HPos::Center,
                            plotters::style::text_anchor::VPos::Center,
                        ),
                    ),
                )))?;
            }
        }
        let ti = self.theta_i.to_degrees();
        let src = RGBColor(200, 120, 0);
        let mir = RGBColor(120, 120, 120);
        chart
            .draw_series(DashedLineSeries::new(
                vec![(0.0, 0.0), polar_xy(-ti, 1.0)],
                8,
                5,
                src.stroke_width(2),
            ))?
            .label(format!("source direction (−{}°)", fmt_num(ti)))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], src.stroke_width(2)));
        chart
            .draw_series(DashedLineSeries::new(
                vec![(0.0, 0.0), polar_xy(ti, 1.0)],
                8,
                5,
                mir.stroke_width(2),
            ))?
            .label(format!("mirror direction ({}°)", fmt_num(ti)))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 24, y)], mir.stroke_width(2)));
        let blue = series_color(0);
        chart
            .draw_series(LineSeries::new(
                self.curve
                    .iter()
                    .filter(|p| p.1.is_finite())
                    .map(|&(t, r)| polar_xy(t, r.clamp(0.0, POLAR_RIM))),
                blue.stroke_width(2),
            ))?
            .label(format!("fitted model (L_max = {})", fmt_num(self.l_max)))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 24, y)], blue.stroke_width(2))
            });
        let red = series_color(3);
        let inside = |p: &&(f64, f64)| p.1.is_finite() && p.1 <= POLAR_RIM;
        chart
            .draw_series(
                self.measured
                    .iter()
                    .filter(inside)
                    .map(|&(t, r)| Circle::new(polar_xy(t, r.max(0.0)), 4, red.filled())),
            )?
            .label("measured (in-plane samples)")
            .legend(move |(x, y)| Circle::new((x + 12, y), 4, red.filled()));
        let (n_out, worst) = self.clipped();
        if n_out > 0 {
            // Each clipped point: a radial arrow from inside the rim to the rim.
            let arrows = self
                .measured
                .iter()
                .filter(|p| p.1.is_finite() && p.1 > POLAR_RIM)
                .map(|&(t, _)| {
                    let tip = polar_xy(t, POLAR_RIM);
                    let tail = polar_xy(t, POLAR_RIM - 0.12);
                    let side = |d: f64| polar_xy(t + d, POLAR_RIM - 0.05);
                    PathElement::new(
                        vec![tail, tip, side(2.5), tip, side(-2.5)],
                        red.stroke_width(2),
                    )
                });
            chart
                .draw_series(arrows)?
                .label(format!(
                    "{n_out} measured beyond the rim (up to {}× L_max), drawn at {POLAR_RIM}",
                    fmt_num(worst)
                ))
                .legend(move |(x, y)| {
                    PathElement::new(
                        vec![
                            (x, y),
                            (x + 22, y),
                            (x + 16, y - 4),
                            (x + 22, y),
                            (x + 16, y + 4),
                        ],
                        red.stroke_width(2),
                    )
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::UpperLeft)
            .margin(10)
            .legend_area_size(32)
            .label_font(font(14.0))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(120, 120, 120))
            .draw()?;
        Ok(())
    }
}

/// The fitted model over (θr, φr) at the θi with the most samples, with that θi's sample
/// positions marked.
pub fn contour_plot(input: &FitPlotInput) -> Result<ContourPlot> {
    let gs = checked_groups(input)?;
    let geo = input.geo;
    let g = busiest(&gs);
    let xs = linspace(0.0, 90.0, 91);
    let ys = linspace(-180.0, 180.0, 181);
    let mut samples = Vec::with_capacity(xs.len() * ys.len());
    for &phi in &ys {
        for &tr in &xs {
            samples.push(Sample::from_degrees(g.theta_i.to_degrees(), tr, phi));
        }
    }
    let z = eval_at(
        input.model,
        input.params,
        &samples,
        g.wavelength,
        geo.quantity,
    )?;
    let grid = Grid { xs, ys, z };
    let (_, hi) = grid.range();
    let hi = if hi.is_finite() { hi } else { 0.0 };
    let marks: Vec<(f64, f64)> = g
        .idx
        .iter()
        .map(|&k| (geo.theta_r[k].to_degrees(), geo.phi_r[k].to_degrees()))
        .collect();
    Ok(ContourPlot {
        title: format!(
            "{} — fitted model over (θr, φr), θi = {}°",
            input.title,
            fmt_num(g.theta_i.to_degrees())
        ),
        x_desc: "θr, view angle from the surface normal (degrees)".into(),
        y_desc: "φr, azimuth from the plane of incidence (degrees)".into(),
        z_desc: format!("fitted {}", quantity_desc(geo.quantity)),
        size: (1000, 700),
        grid,
        levels: LEVELS.iter().map(|l| l * hi).collect(),
        levels_label: "contours at 0.05, 0.1, 0.2, …, 0.9 × max".into(),
        marks: vec![(
            format!(
                "samples at θi = {}° ({})",
                fmt_num(g.theta_i.to_degrees()),
                g.idx.len()
            ),
            marks,
            RGBColor(40, 110, 255),
        )],
    })
}

/// Writes into `dir` (PNG and SVG each): fit_linear, fit_log (measured vs fitted over
/// signed θr for each θi, in-plane samples only, or nearest-to-plane), residuals_theta
/// (standardized residuals vs θr), residuals_phi (vs φr), polar (fitted lobe at the θi with
/// most samples, in the plane of incidence), contour (fitted model over (θr, φr) at that
/// θi with sample positions marked). Creates `dir` if needed. Returns the written paths.
pub fn write_fit_plots(dir: &Path, input: &FitPlotInput) -> Result<Vec<PathBuf>> {
    check(input)?;
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let mut paths = write_png_svg(&fit_chart(input, false)?, dir, "fit_linear")?;
    paths.extend(write_png_svg(&fit_chart(input, true)?, dir, "fit_log")?);
    paths.extend(write_png_svg(
        &residual_chart(input, false)?,
        dir,
        "residuals_theta",
    )?);
    paths.extend(write_png_svg(
        &residual_chart(input, true)?,
        dir,
        "residuals_phi",
    )?);
    paths.extend(write_png_svg(&polar_plot(input)?, dir, "polar")?);
    paths.extend(write_png_svg(&contour_plot(input)?, dir, "contour")?);
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn signed_angle_and_plane() {
        assert_eq!(signed_theta_r_deg(0.5, 0.0), 0.5f64.to_degrees());
        assert_eq!(signed_theta_r_deg(0.5, PI), -(0.5f64.to_degrees()));
        assert!(plane_distance(PI - 0.001) < PLANE_TOL);
        assert!(plane_distance(-PI + 0.001) < PLANE_TOL);
        assert!(plane_distance(0.5 * PI) > 1.0);
    }

    #[test]
    fn grouping_and_nearest_plane() {
        let s: Vec<Sample> = [
            (30.0, 10.0, 0.0),
            (30.0, 20.0, 180.0),
            (60.0, 10.0, 20.0),
            (60.0, 40.0, 21.0),
            (60.0, 50.0, 90.0),
        ]
        .iter()
        .map(|&(a, b, c)| Sample::from_degrees(a, b, c))
        .collect();
        let geo = Geometry::new(&s, &[1.0], Quantity::Radiance).unwrap();
        let gs = groups(&geo);
        assert_eq!(gs.len(), 2);
        assert_eq!(gs[0].idx, vec![0, 1]);
        let (idx, in_plane) = plane_samples(&geo, &gs[1]);
        assert!(!in_plane);
        assert_eq!(idx, vec![2, 3]);
        assert_eq!(busiest(&gs).idx.len(), 3);
    }
}
