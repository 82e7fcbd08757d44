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
use super::legend::{ColorKey, Entry, Glyph};
use super::marks::Beyond;
use super::smooth::{draw_data_polyline, Pen, PixelMap};
use super::xy::{Kind, Series, XyPlot};
use super::{fmt_num, font, series_color, write_png_svg, DrawError, Picture};
use crate::error::{Error, Result};
use crate::geometry::{Geometry, Quantity, Sample};
use crate::model::Model;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};

/// What the fit pictures need.
pub struct FitPlotInput<'a> {
    /// Model name and fitted parameters.
    pub title: String,
    /// The fit's status under the title: T/σ, the verdict, converged or why not; empty for
    /// none.
    pub subtitle: String,
    pub model: &'a dyn Model,
    pub params: &'a [f64],
    /// Sample geometry (radians), quantity, wavelength.
    pub geo: &'a Geometry,
    pub measured: &'a [f64],
    pub fitted: &'a [f64],
    pub std_residuals: &'a [f64],
    /// The unit of λ (`nm`, `µm`), shown with the wavelengths; `None` for a bare number.
    pub wavelength_unit: Option<&'a str>,
    /// The channels of a joint fit (each with its own parameters); default: one.
    pub channels: Channels<'a>,
}

/// The channels of a joint fit: every channel is drawn with its own parameters.
#[derive(Debug, Clone, Copy, Default)]
pub struct Channels<'a> {
    /// Per sample, its channel (an index into `params` and `names`); empty: one channel,
    /// whose parameters are [`FitPlotInput::params`].
    pub of_sample: &'a [usize],
    /// Per channel, the model's parameters.
    pub params: &'a [Vec<f64>],
    /// Per channel, its name (for the legend when channels share a wavelength).
    pub names: &'a [String],
}

impl FitPlotInput<'_> {
    /// The model parameters of channel `c`.
    fn params_of(&self, c: usize) -> &[f64] {
        self.channels
            .params
            .get(c)
            .map_or(self.params, |p| p.as_slice())
    }

    /// " [channel NAME]" for a joint fit's channel `c`, else "".
    fn channel_note(&self, c: usize) -> String {
        match self.channels.names.get(c) {
            Some(name) if self.channels.names.len() > 1 => format!(" [channel {name}]"),
            _ => String::new(),
        }
    }
}

/// Tolerance on φr (radians) for a sample to count as in the plane of incidence.
const PLANE_TOL: f64 = PI / 180.0;

/// Samples sharing an incidence angle, wavelength and channel.
#[derive(Debug, Clone)]
pub struct Group {
    pub theta_i: f64,
    pub wavelength: f64,
    /// The joint fit's channel (0 for a single fit).
    pub channel: usize,
    pub idx: Vec<usize>,
}

/// Group samples by θi (to 1e-4°), wavelength (to 1e-9 relative) and channel (`channel`
/// per sample; empty: all 0), sorted by θi, λ, channel.
pub fn groups(geo: &Geometry, channel: &[usize]) -> Vec<Group> {
    let mut out: Vec<Group> = Vec::new();
    for k in 0..geo.len() {
        let (ti, wl) = (geo.theta_i[k], geo.wavelength[k]);
        let c = channel.get(k).copied().unwrap_or(0);
        let same = |g: &Group| {
            (g.theta_i - ti).abs().to_degrees() < 1e-4
                && (g.wavelength - wl).abs() <= 1e-9 * wl.abs()
                && g.channel == c
        };
        match out.iter_mut().find(|g| same(g)) {
            Some(g) => g.idx.push(k),
            None => out.push(Group {
                theta_i: ti,
                wavelength: wl,
                channel: c,
                idx: vec![k],
            }),
        }
    }
    out.sort_by(|a, b| {
        a.theta_i
            .total_cmp(&b.theta_i)
            .then(a.wavelength.total_cmp(&b.wavelength))
            .then(a.channel.cmp(&b.channel))
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
        Quantity::Radiance => "radiance L (the file's unit)",
        Quantity::Brdf => "BRDF (sr⁻¹)",
    }
}

/// The model's values for group `g` (its channel's parameters, its wavelength) at `samples`.
fn eval_group(input: &FitPlotInput, g: &Group, samples: &[Sample]) -> Result<Vec<f64>> {
    eval_at(
        input.model,
        input.params_of(g.channel),
        samples,
        g.wavelength,
        input.geo.quantity,
    )
}

/// "θi = 30°", with ", λ = 0.532 µm" when the groups' wavelengths differ, or the channel's
/// name when channels share one.
fn group_label(g: &Group, multi_wavelength: bool, input: &FitPlotInput) -> String {
    let mut s = format!("θi = {}°", fmt_num(g.theta_i.to_degrees()));
    if multi_wavelength {
        s.push_str(&format!(", λ = {}", wavelength_text(g.wavelength, input)));
    } else if input.channels.names.len() > 1 {
        if let Some(name) = input.channels.names.get(g.channel) {
            s.push_str(&format!(", {name}"));
        }
    }
    s
}

/// A wavelength with its unit when known ("0.532 µm").
fn wavelength_text(w: f64, input: &FitPlotInput) -> String {
    match input.wavelength_unit {
        Some(u) => format!("{} {u}", fmt_num(w)),
        None => fmt_num(w),
    }
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
    for p in input.channels.params {
        crate::model::check_param_count(input.model, p)?;
    }
    let channels = input.channels.params.len().max(1);
    if let Some(c) = input.channels.of_sample.iter().find(|&&c| c >= channels) {
        return Err(Error::Usage(format!(
            "fit plots: channel {c} of {channels} channels"
        )));
    }
    if !input.channels.of_sample.is_empty() && input.channels.of_sample.len() != n {
        return Err(Error::Usage(format!(
            "fit plots: {} channel indices for {n} samples",
            input.channels.of_sample.len()
        )));
    }
    if n == 0 {
        return Err(Error::Usage("fit plots: no samples".into()));
    }
    Ok(())
}

/// The input checked, and its samples grouped by (θi, λ).
fn checked_groups(input: &FitPlotInput) -> Result<Vec<Group>> {
    check(input)?;
    Ok(groups(input.geo, input.channels.of_sample))
}

/// How the groups of a chart are told apart. Up to [`super::PALETTE`] groups: a palette
/// colour each, named in the legend. More: colour by θi on a continuous scale (a colour bar
/// in the legend) and, when there are several wavelengths, the wavelength by line style
/// and marker (named in the legend; the four styles repeat beyond four wavelengths).
pub struct GroupStyles {
    pub colors: Vec<RGBColor>,
    /// Index into [`Kind::LINES`] / [`Kind::POINTS`] per group.
    pub style: Vec<usize>,
    /// The colour scale, when colour shows θi.
    pub key: Option<ColorKey>,
    /// The distinct wavelengths with their style index, when style shows the wavelength.
    pub wavelengths: Vec<(f64, usize)>,
}

/// The styles of `gs` (see [`GroupStyles`]).
pub fn group_styles(gs: &[Group]) -> GroupStyles {
    if gs.len() <= super::PALETTE {
        return GroupStyles {
            colors: (0..gs.len()).map(series_color).collect(),
            style: vec![0; gs.len()],
            key: None,
            wavelengths: Vec::new(),
        };
    }
    let mut wls: Vec<f64> = gs.iter().map(|g| g.wavelength).collect();
    wls.sort_by(f64::total_cmp);
    wls.dedup_by(|a, b| (*a - *b).abs() <= 1e-9 * b.abs());
    let mut thetas: Vec<f64> = gs.iter().map(|g| g.theta_i.to_degrees()).collect();
    thetas.dedup_by(|a, b| (*a - *b).abs() < 1e-4);
    let range = (thetas[0], *thetas.last().unwrap_or(&thetas[0]));
    let key = ColorKey {
        label: "θi (degrees)".into(),
        range,
        values: thetas,
    };
    let style_of = |wl: f64| {
        wls.iter()
            .position(|w| (w - wl).abs() <= 1e-9 * w.abs())
            .unwrap_or(0)
            % Kind::LINES.len()
    };
    GroupStyles {
        colors: gs
            .iter()
            .map(|g| key.color(g.theta_i.to_degrees()))
            .collect(),
        style: gs.iter().map(|g| style_of(g.wavelength)).collect(),
        wavelengths: if wls.len() > 1 {
            wls.iter().map(|&w| (w, style_of(w))).collect()
        } else {
            Vec::new()
        },
        key: Some(key),
    }
}

impl GroupStyles {
    /// A group's legend label, or `None` when colour and style name it instead.
    fn label(&self, g: &Group, multi_wavelength: bool, input: &FitPlotInput) -> Option<String> {
        self.key
            .is_none()
            .then(|| group_label(g, multi_wavelength, input))
    }

    /// The legend lines of the wavelength styles (`lines`: the line style, else the
    /// marker; `what` follows the wavelength: " fitted", " measured", "").
    fn wavelength_entries(&self, lines: bool, what: &str, input: &FitPlotInput) -> Vec<Entry> {
        let grey = RGBColor(60, 60, 60);
        self.wavelengths
            .iter()
            .map(|&(w, k)| Entry {
                glyph: if lines {
                    Kind::LINES[k](2).glyph(grey)
                } else {
                    Kind::POINTS[k](4).glyph(grey)
                },
                label: format!("λ = {}{what}", wavelength_text(w, input)),
            })
            .collect()
    }
}

/// The top of a linear chart of `data` under fitted curves reaching `curve_max`: the
/// data's top, unless a few points far above the curves would crush the rest (Cornell
/// paints at grazing angles, 50× the lobe): then 1.15 × the larger of the curves' top and
/// the data's 95th percentile, and the points above are drawn as arrows at the top.
pub fn linear_top(curve_max: f64, data: &[f64]) -> f64 {
    let mut d: Vec<f64> = data.iter().copied().filter(|v| v.is_finite()).collect();
    d.sort_by(f64::total_cmp);
    let Some(&max) = d.last() else {
        return curve_max;
    };
    let q95 = d[((d.len() - 1) as f64 * 0.95).round() as usize];
    let robust = if curve_max.is_finite() {
        curve_max.max(q95)
    } else {
        q95
    };
    if max <= 1.5 * robust {
        max.max(robust)
    } else {
        1.15 * robust
    }
}

/// Measured vs fitted over signed θr for each θi (in-plane samples). `log_y` for the
/// logarithmic version; the linear one chooses its top with [`linear_top`].
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
    plot.subtitle = input.subtitle.clone();
    plot.x_range = (-90.0, 90.0);
    plot.log_y = log_y;
    let styles = group_styles(&gs);
    let mut any_near = false;
    let (mut data, mut curves) = (Vec::new(), Vec::new());
    for (c, g) in gs.iter().enumerate() {
        let color = styles.colors[c];
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
        data.extend(meas.iter().map(|p| p.1));
        // A smooth model curve along the plane when the samples are in it and the model
        // reproduces the fitted values there; otherwise the fitted values joined.
        let curve = if in_plane {
            dense_plane_curve(input, g, &idx)?
        } else {
            None
        };
        let line = curve.unwrap_or(fit_pts);
        curves.extend(line.iter().map(|p| p.1));
        plot.series.push(Series {
            label: styles.label(g, multi, input),
            color,
            kind: Kind::LINES[styles.style[c]](2),
            points: line,
        });
        plot.series.push(Series {
            label: None,
            color,
            kind: Kind::POINTS[styles.style[c]](4),
            points: meas,
        });
    }
    plot.legend_extra.push(Entry {
        glyph: Kind::Points(4).glyph(BLACK),
        label: "measured (points)".into(),
    });
    plot.legend_extra.push(Entry {
        glyph: Kind::Line(2).glyph(BLACK),
        label: if any_near {
            "fitted (lines; nearest-to-plane samples)".into()
        } else {
            "fitted model (lines)".into()
        },
    });
    plot.legend_extra
        .extend(styles.wavelength_entries(true, " fitted", input));
    plot.legend_extra
        .extend(styles.wavelength_entries(false, " measured", input));
    plot.color_key = styles.key;
    plot.y_range = fit_y_range(&data, &curves, log_y);
    Ok(plot)
}

/// The y range of a fit chart: on a log axis every positive measured and fitted value
/// (the model's far tails left out) with a margin; on a linear one from 0 (or the lowest
/// value) to [`linear_top`].
fn fit_y_range(data: &[f64], curves: &[f64], log_y: bool) -> (f64, f64) {
    let keep = |y: &&f64| y.is_finite() && (!log_y || **y > 0.0);
    let lo = data
        .iter()
        .filter(keep)
        .copied()
        .fold(f64::INFINITY, f64::min);
    let data_hi = data
        .iter()
        .filter(keep)
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    let curve_hi = curves
        .iter()
        .filter(keep)
        .copied()
        .fold(f64::NEG_INFINITY, f64::max);
    if log_y {
        let (lo, hi) = (lo, data_hi.max(curve_hi.min(data_hi * 10.0)));
        if !(lo.is_finite() && hi.is_finite()) {
            return (1e-3, 1.0);
        }
        let (lo, hi) = if hi > lo {
            (lo, hi)
        } else {
            (lo / 2.0, hi * 2.0)
        };
        let pad = (hi / lo).powf(0.08);
        return (lo / pad, hi * pad.powi(2));
    }
    let curve_lo = curves
        .iter()
        .filter(keep)
        .copied()
        .fold(f64::INFINITY, f64::min);
    let lo = lo.min(curve_lo).min(0.0);
    let hi = linear_top(curve_hi, data);
    if !hi.is_finite() {
        return (0.0, 1.0);
    }
    let span = if hi > lo { hi - lo } else { 1.0 };
    (lo, hi + 0.08 * span)
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
    let here = eval_group(input, g, &at)?;
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
    let ys = eval_group(input, g, &samples)?;
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
    plot.subtitle = input.subtitle.clone();
    plot.x_range = if over_phi {
        phi_range(gs.iter().flat_map(|g| g.idx.iter().map(|&k| geo.phi_r[k])))
    } else {
        (0.0, 90.0)
    };
    let styles = group_styles(&gs);
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
            label: styles.label(g, multi, input),
            color: styles.colors[c],
            kind: Kind::POINTS[styles.style[c]](4),
            points: pts,
        });
    }
    plot.legend_extra
        .extend(styles.wavelength_entries(false, "", input));
    plot.color_key = styles.key;
    plot.hlines = vec![-2.0, 0.0, 2.0];
    plot.fit_y_range();
    let m = plot.y_range.0.abs().max(plot.y_range.1.abs()).max(3.0);
    plot.y_range = (-m, m);
    plot.legend_extra.push(Entry {
        glyph: Kind::Line(1).glyph(RGBColor(150, 150, 150)),
        label: "±2 and 0 (grey lines)".into(),
    });
    Ok(plot)
}

/// The φr axis (degrees) for azimuths `phi` (radians): 0…180 when none is negative (a file
/// measured on one side of the plane of incidence, as the Cornell and CUReT files), −180…0
/// when none is positive, else −180…180.
fn phi_range(phi: impl Iterator<Item = f64>) -> (f64, f64) {
    let tol = 1e-9;
    let (lo, hi) = phi.fold((0.0f64, 0.0f64), |(lo, hi), p| (lo.min(p), hi.max(p)));
    match (lo < -tol, hi > tol) {
        (false, _) => (0.0, 180.0),
        (true, false) => (-180.0, 0.0),
        (true, true) => (-180.0, 180.0),
    }
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
    /// A second title line; empty for none.
    pub subtitle: String,
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
/// The radius of the spoke labels (0°, ±30°, …): just outside the L_max ring, inside the
/// arrows at the rim (the 60° label touched them).
const POLAR_LABEL_R: f64 = 1.035;
/// The length (pixels) of the rim arrows: with about 340 px per unit of L / L_max they
/// reach in to r ≈ 1.09, clear of the spoke labels.
const POLAR_ARROW_PX: f64 = 20.0;

const POLAR_SOURCE: RGBColor = RGBColor(200, 120, 0);
const POLAR_MIRROR: RGBColor = RGBColor(120, 120, 120);

impl PolarPlot {
    /// The measured points beyond [`POLAR_RIM`]: (how many, the largest L / L_max).
    pub fn clipped(&self) -> (usize, f64) {
        let b = Beyond::above(self.measured.iter().map(|p| p.1), POLAR_RIM);
        (b.count, b.worst)
    }

    /// The legend's lines (drawn in rows above the plot).
    pub fn legend_entries(&self) -> Vec<Entry> {
        let line = |color, dash| Glyph::Line {
            color,
            width: 2,
            dash,
        };
        let ti = fmt_num(self.theta_i.to_degrees());
        let mut out = vec![
            Entry {
                glyph: line(POLAR_SOURCE, Some((8, 5))),
                label: format!("source direction (−{ti}°)"),
            },
            Entry {
                glyph: line(POLAR_MIRROR, Some((8, 5))),
                label: format!("mirror direction ({ti}°)"),
            },
            Entry {
                glyph: line(series_color(0), None),
                label: format!("fitted model (L_max = {})", fmt_num(self.l_max)),
            },
            Entry {
                glyph: Kind::Points(4).glyph(series_color(3)),
                label: "measured (in-plane samples)".into(),
            },
        ];
        let b = Beyond::above(self.measured.iter().map(|p| p.1), POLAR_RIM);
        if b.count > 0 {
            out.push(Entry {
                glyph: Glyph::Arrow {
                    color: series_color(3),
                },
                label: format!(
                    "{}, drawn at {POLAR_RIM}",
                    b.label("beyond the rim", "× L_max")
                ),
            });
        }
        out
    }
}

/// The polar plot of the fit at the θi with the most samples.
pub fn polar_plot(input: &FitPlotInput) -> Result<PolarPlot> {
    let gs = checked_groups(input)?;
    let geo = input.geo;
    let g = busiest(&gs);
    let (xs, samples) = plane_curve_samples(g.theta_i, 361);
    let ys = eval_group(input, g, &samples)?;
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
            "{} — fitted lobe in the plane of incidence, θi = {}°{}",
            input.title,
            fmt_num(g.theta_i.to_degrees()),
            input.channel_note(g.channel)
        ),
        subtitle: input.subtitle.clone(),
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
        (900, 620)
    }

    fn draw<DB: super::smooth::Canvas>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError<DB>> {
        let root = super::xy::draw_titles(root, &self.title, &self.subtitle)?;
        let (w0, _) = root.dim_in_pixel();
        let entries = self.legend_entries();
        let rows = super::legend::rows(&entries, w0.saturating_sub(40)).len() as u32;
        let (top, root) = root.split_vertically(rows * super::legend::LINE_H + 4);
        super::legend::draw_rows(&top, &entries)?;
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
        self.draw_grid(&mut chart)?;
        let map = PixelMap::of_linear(&chart);
        let ti = self.theta_i.to_degrees();
        for (angle, color) in [(-ti, POLAR_SOURCE), (ti, POLAR_MIRROR)] {
            let ray = [(0.0, 0.0), polar_xy(angle, 1.0)];
            draw_data_polyline(
                chart.plotting_area(),
                &map,
                &ray,
                Pen::dashed(color, 2.0, 8.0, 5.0),
            )?;
        }
        let curve: Vec<(f64, f64)> = self
            .curve
            .iter()
            .filter(|p| p.1.is_finite())
            .map(|&(t, r)| polar_xy(t, r.clamp(0.0, POLAR_RIM)))
            .collect();
        draw_data_polyline(
            chart.plotting_area(),
            &map,
            &curve,
            Pen::solid(series_color(0), 2.0),
        )?;
        let red = series_color(3);
        chart.draw_series(
            self.measured
                .iter()
                .filter(|p| p.1.is_finite() && p.1 <= POLAR_RIM)
                .map(|&(t, r)| Circle::new(polar_xy(t, r.max(0.0)), 4, red.filled())),
        )?;
        // Each point beyond the rim: a radial arrow ending at the rim (equal scales, so the
        // radial direction on screen is (sin θ, −cos θ)).
        chart.draw_series(
            self.measured
                .iter()
                .filter(|p| p.1.is_finite() && p.1 > POLAR_RIM)
                .map(|&(t, _)| {
                    let a = t.to_radians();
                    EmptyElement::at(polar_xy(t, POLAR_RIM))
                        + PathElement::new(
                            super::marks::arrow((a.sin(), -a.cos()), POLAR_ARROW_PX, 8.0),
                            red.stroke_width(2),
                        )
                }),
        )?;
        Ok(())
    }
}

impl PolarPlot {
    /// The rings at L / L_max = 0.25 … 1 and the spokes every 15° (labelled every 30°).
    fn draw_grid<DB: super::smooth::Canvas>(
        &self,
        chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    ) -> std::result::Result<(), DrawError<DB>> {
        let grey = Pen::solid(RGBColor(200, 200, 200), 1.0);
        let map = PixelMap::of_linear(chart);
        for r in [0.25, 0.5, 0.75, 1.0] {
            let arc: Vec<(f64, f64)> = (0..=180).map(|d| polar_xy(d as f64 - 90.0, r)).collect();
            draw_data_polyline(chart.plotting_area(), &map, &arc, grey)?;
        }
        for d in (-90..=90).step_by(15) {
            let spoke = [(0.0, 0.0), polar_xy(d as f64, 1.0)];
            draw_data_polyline(chart.plotting_area(), &map, &spoke, grey)?;
            if d % 30 == 0 {
                let p = polar_xy(d as f64, POLAR_LABEL_R);
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
    let z = eval_group(input, g, &samples)?;
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
            "{} — fitted model over (θr, φr), θi = {}°{}",
            input.title,
            fmt_num(g.theta_i.to_degrees()),
            input.channel_note(g.channel)
        ),
        subtitle: input.subtitle.clone(),
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

/// The names of [`write_fit_plots`]'s pictures without the extension (each as `.png` and
/// `.svg`), in the order written.
pub const PICTURES: [&str; 6] = [
    "fit_linear",
    "fit_log",
    "residuals_theta",
    "residuals_phi",
    "polar",
    "contour",
];

/// Writes into `dir` (PNG and SVG each, named by [`PICTURES`]): fit_linear, fit_log (measured vs fitted over
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
    let [linear, log, theta, phi, polar, contour] = PICTURES;
    let mut paths = write_png_svg(&fit_chart(input, false)?, dir, linear)?;
    paths.extend(write_png_svg(&fit_chart(input, true)?, dir, log)?);
    paths.extend(write_png_svg(&residual_chart(input, false)?, dir, theta)?);
    paths.extend(write_png_svg(&residual_chart(input, true)?, dir, phi)?);
    paths.extend(write_png_svg(&polar_plot(input)?, dir, polar)?);
    paths.extend(write_png_svg(&contour_plot(input)?, dir, contour)?);
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
    fn the_phi_axis_covers_the_side_the_data_is_on() {
        let deg = |v: &[f64]| v.iter().map(|d: &f64| d.to_radians()).collect::<Vec<_>>();
        assert_eq!(
            phi_range(deg(&[0.0, 90.0, 180.0]).into_iter()),
            (0.0, 180.0)
        );
        assert_eq!(phi_range(deg(&[-10.0, 0.0]).into_iter()), (-180.0, 0.0));
        assert_eq!(phi_range(deg(&[-10.0, 170.0]).into_iter()), (-180.0, 180.0));
    }

    #[test]
    fn linear_top_ignores_a_few_points_far_above_the_curves() {
        // 100 values under 1, three grazing spikes up to 28 (the garnet 550 nm case).
        let mut data: Vec<f64> = (0..100).map(|k| 0.01 * k as f64).collect();
        data.extend([6.4, 7.5, 28.0]);
        let top = linear_top(0.5, &data);
        // The 95th percentile of the 103 values is the 98th smallest, 0.97.
        assert!((top - 1.15 * 0.97).abs() < 1e-12, "{top}");
        // Data a little above the curves, or the curves above the data: all shown.
        assert_eq!(linear_top(0.5, &[0.1, 0.6, 0.7]), 0.7);
        assert_eq!(linear_top(2.0, &[0.1, 0.6, 0.7]), 2.0);
        assert_eq!(linear_top(1.0, &[]), 1.0);
    }

    #[test]
    fn more_groups_than_colours_are_coloured_by_theta_i() {
        let group = |ti: f64, wl: f64| Group {
            theta_i: ti.to_radians(),
            wavelength: wl,
            channel: 0,
            idx: vec![0],
        };
        let few: Vec<Group> = (0..10).map(|k| group(5.0 * k as f64, 1.0)).collect();
        let s = group_styles(&few);
        assert!(s.key.is_none() && s.wavelengths.is_empty());
        assert_eq!(s.colors[9], series_color(9));
        // The PTFE file: 6 incidence angles × 4 wavelengths.
        let mut many = Vec::new();
        for ti in [0.0, 15.0, 30.0, 45.0, 60.0, 75.0] {
            for wl in [0.351, 0.532, 0.633, 1.064] {
                many.push(group(ti, wl));
            }
        }
        let s = group_styles(&many);
        let key = s.key.as_ref().expect("a colour bar");
        assert_eq!(key.range, (0.0, 75.0));
        assert_eq!(key.values.len(), 6);
        assert_eq!(s.wavelengths.len(), 4);
        // Same θi, same colour; same λ, same style; the four λ get four styles.
        assert_eq!(s.colors[0], s.colors[3]);
        assert_ne!(s.colors[0], s.colors[4]);
        assert_eq!(s.style[1], s.style[5]);
        assert_eq!(&s.style[..4], &[0, 1, 2, 3]);
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
        let gs = groups(&geo, &[]);
        assert_eq!(gs.len(), 2);
        assert_eq!(gs[0].idx, vec![0, 1]);
        let (idx, in_plane) = plane_samples(&geo, &gs[1]);
        assert!(!in_plane);
        assert_eq!(idx, vec![2, 3]);
        assert_eq!(busiest(&gs).idx.len(), 3);
    }
}
