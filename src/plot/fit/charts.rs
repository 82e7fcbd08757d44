//! The x–y charts of a fit: measured vs fitted over the signed view angle, and the
//! standardized residuals over θr and φr.

use super::{
    checked_groups, eval_group, group_label, plane_curve_samples, plane_samples, quantity_desc,
    signed_theta_r_deg, wavelength_text, FitPlotInput, Group,
};
use crate::error::Result;
use crate::geometry::Sample;
use crate::plot::legend::{ColorKey, Entry};
use crate::plot::series_color;
use crate::plot::xy::{Kind, Series, XyPlot};
use plotters::prelude::*;

/// How the groups of a chart are told apart. Up to [`crate::plot::PALETTE`] groups: a palette
/// colour each, named in the legend. More: colour by θi on a continuous scale (a colour bar
/// in the legend) and, when there are several wavelengths, the wavelength by line style
/// and marker (named in the legend; the four styles repeat beyond four wavelengths).
pub(crate) struct GroupStyles {
    /// Per group (in the order of the groups given), the colour of its curve and points: a
    /// palette colour, or its θi's colour on [`GroupStyles::key`].
    pub colors: Vec<RGBColor>,
    /// Index into [`Kind::LINES`] / [`Kind::POINTS`] per group.
    pub style: Vec<usize>,
    /// The colour scale, when colour shows θi.
    pub key: Option<ColorKey>,
    /// The distinct wavelengths with their style index, when style shows the wavelength.
    pub wavelengths: Vec<(f64, usize)>,
}

/// The styles of `gs` (see [`GroupStyles`]).
pub(crate) fn group_styles(gs: &[Group]) -> GroupStyles {
    if gs.len() <= crate::plot::PALETTE {
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
pub(crate) fn linear_top(curve_max: f64, data: &[f64]) -> f64 {
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
pub(crate) fn fit_chart(input: &FitPlotInput, log_y: bool) -> Result<XyPlot> {
    let gs = checked_groups(input)?;
    let multi = gs.iter().any(|g| g.wavelength != gs[0].wavelength);
    let mut plot = fit_chart_frame(input, log_y);
    let styles = group_styles(&gs);
    let (mut any_near, mut any_plane) = (false, false);
    let (mut data, mut curves) = (Vec::new(), Vec::new());
    for (c, g) in gs.iter().enumerate() {
        let (in_plane, fitted, measured) = group_series(input, g, &styles, c, multi)?;
        any_plane |= in_plane;
        any_near |= !in_plane;
        data.extend(measured.points.iter().map(|p| p.1));
        curves.extend(fitted.points.iter().map(|p| p.1));
        plot.series.push(fitted);
        plot.series.push(measured);
    }
    fit_chart_legend(&mut plot, &styles, any_plane, any_near, input);
    plot.color_key = styles.key;
    plot.y_range = fit_y_range(&data, &curves, log_y);
    Ok(plot)
}

/// The empty fit chart: its title (with "(log scale)" for `log_y`), axis labels, subtitle,
/// x range −90°…90° and y scale; no series, legend or y range yet.
fn fit_chart_frame(input: &FitPlotInput, log_y: bool) -> XyPlot {
    let mut plot = XyPlot::new(
        format!(
            "{} — measured vs fitted{}",
            input.title,
            if log_y { " (log scale)" } else { "" }
        ),
        "signed θr (degrees; θr < 0: φr = 180°, the source side)",
        quantity_desc(input.geo.quantity),
    );
    plot.subtitle = input.subtitle.clone();
    plot.x_range = (-90.0, 90.0);
    plot.log_y = log_y;
    plot
}

/// The two series of group `g` (the `c`-th, styled by `styles`): (whether its samples lie
/// in the plane of incidence, the fitted series, the measured points), each over signed θr
/// in order of angle. In the plane the fitted series is a smooth model curve along it when
/// the model reproduces the fitted values there, else the fitted values joined. With no
/// sample in the plane it is the fitted values at the nearest samples as open rings around
/// the measured points (a line through off-plane samples at different φr would mean
/// nothing).
fn group_series(
    input: &FitPlotInput,
    g: &Group,
    styles: &GroupStyles,
    c: usize,
    multi: bool,
) -> Result<(bool, Series, Series)> {
    let geo = input.geo;
    let color = styles.colors[c];
    let (idx, in_plane) = plane_samples(geo, g);
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
    let (kind, line) = if in_plane {
        let curve = dense_plane_curve(input, g, &idx)?;
        (Kind::LINES[styles.style[c]](2), curve.unwrap_or(fit_pts))
    } else {
        (Kind::OpenPoints(7), fit_pts)
    };
    let fitted = Series {
        label: styles.label(g, multi, input),
        color,
        kind,
        points: line,
    };
    let measured = Series {
        label: None,
        color,
        kind: Kind::POINTS[styles.style[c]](4),
        points: meas,
    };
    Ok((in_plane, fitted, measured))
}

/// The fit chart's extra legend entries: measured points; fitted lines when a group lies in
/// the plane (`any_plane`); rings when one does not (`any_near`); then the wavelength
/// styles of the fitted and of the measured series.
fn fit_chart_legend(
    plot: &mut XyPlot,
    styles: &GroupStyles,
    any_plane: bool,
    any_near: bool,
    input: &FitPlotInput,
) {
    plot.legend_extra.push(Entry {
        glyph: Kind::Points(4).glyph(BLACK),
        label: "measured (points)".into(),
    });
    if any_plane {
        plot.legend_extra.push(Entry {
            glyph: Kind::Line(2).glyph(BLACK),
            label: "fitted model (lines)".into(),
        });
    }
    if any_near {
        plot.legend_extra.push(Entry {
            glyph: Kind::OpenPoints(7).glyph(BLACK),
            label: "fitted at nearest-to-plane samples (rings)".into(),
        });
    }
    plot.legend_extra
        .extend(styles.wavelength_entries(true, " fitted", input));
    plot.legend_extra
        .extend(styles.wavelength_entries(false, " measured", input));
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
pub(crate) fn residual_chart(input: &FitPlotInput, over_phi: bool) -> Result<XyPlot> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plot::series_color;

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
}
