//! What a fit's pictures are drawn from: the fit's input ([`FitPlotInput`]), its groups of
//! samples (one per incidence angle and channel), the samples in or nearest to the plane
//! of incidence, and the model evaluated along it.

use crate::error::{Error, Result};
use crate::geometry::{Geometry, Quantity, Sample};
use crate::model::Model;
use crate::plot::contour::linspace;
use crate::plot::fmt_num;
use std::f64::consts::PI;

/// What the fit pictures need.
pub(crate) struct FitPlotInput<'a> {
    /// Model name and fitted parameters.
    pub title: String,
    /// The fit's status under the title: T/σ, the verdict, converged or why not; empty for
    /// none.
    pub subtitle: String,
    /// The fitted model, evaluated along the plane of incidence for the fit curves and on
    /// the (θr, φr) grid of the contour map.
    pub model: &'a dyn Model,
    /// The model's fitted parameters, in the model's order; used for every sample when
    /// [`Channels::params`] is empty.
    pub params: &'a [f64],
    /// Sample geometry (radians), quantity, wavelength.
    pub geo: &'a Geometry,
    /// Per sample (the order of `geo`), the measured value of `geo`'s quantity in the
    /// data's unit (a radiance L in the file's unit, or a BRDF in sr⁻¹).
    pub measured: &'a [f64],
    /// Per sample, the fitted model's value, in the unit of `measured`.
    pub fitted: &'a [f64],
    /// Per sample, the standardized residual, unitless: √w·r, r the residual (fitted against
    /// measured, as the fit's residual kind defines it), divided by s = √(χ²/(n − p))
    /// unless the weights are uncertainties.
    pub std_residuals: &'a [f64],
    /// The unit of λ (`nm`, `µm`), shown with the wavelengths; `None` for a bare number.
    pub wavelength_unit: Option<&'a str>,
    /// The channels of a joint fit (each with its own parameters); default: one.
    pub channels: Channels<'a>,
}

/// The channels of a joint fit: every channel is drawn with its own parameters.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Channels<'a> {
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
    pub(super) fn channel_note(&self, c: usize) -> String {
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
pub(crate) struct Group {
    /// The shared incidence angle, radians (of the group's first sample; the others lie
    /// within 1e-4° of it).
    pub theta_i: f64,
    /// The shared wavelength, in the data's unit of λ (see
    /// [`FitPlotInput::wavelength_unit`]).
    pub wavelength: f64,
    /// The joint fit's channel (0 for a single fit).
    pub channel: usize,
    /// The group's samples: indices into the fit's samples (`geo`, `measured`, …), in
    /// increasing order.
    pub idx: Vec<usize>,
}

/// Group samples by θi (to 1e-4°), wavelength (to 1e-9 relative) and channel (`channel`
/// per sample; empty: all 0), sorted by θi, λ, channel.
pub(crate) fn groups(geo: &Geometry, channel: &[usize]) -> Vec<Group> {
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
pub(crate) fn signed_theta_r_deg(theta_r: f64, phi_r: f64) -> f64 {
    if phi_r.abs() > 0.5 * PI {
        -theta_r.to_degrees()
    } else {
        theta_r.to_degrees()
    }
}

/// Distance of φr (wrapped) from the plane of incidence, radians.
pub(super) fn plane_distance(phi_r: f64) -> f64 {
    let a = crate::geometry::wrap_phi(phi_r).abs();
    a.min(PI - a)
}

/// The samples of `g` in the plane of incidence, or, when there are none, those nearest
/// to it; and whether they are truly in the plane.
pub(crate) fn plane_samples(geo: &Geometry, g: &Group) -> (Vec<usize>, bool) {
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
pub(super) fn eval_at(
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
pub(super) fn plane_curve_samples(theta_i: f64, n: usize) -> (Vec<f64>, Vec<Sample>) {
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

pub(crate) fn quantity_desc(q: Quantity) -> &'static str {
    match q {
        Quantity::Radiance => "radiance L (the file's unit)",
        Quantity::Brdf => "BRDF (sr⁻¹)",
    }
}

/// The model's values for group `g` (its channel's parameters, its wavelength) at `samples`.
pub(super) fn eval_group(input: &FitPlotInput, g: &Group, samples: &[Sample]) -> Result<Vec<f64>> {
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
pub(crate) fn group_label(g: &Group, multi_wavelength: bool, input: &FitPlotInput) -> String {
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
pub(super) fn wavelength_text(w: f64, input: &FitPlotInput) -> String {
    match input.wavelength_unit {
        Some(u) => format!("{} {u}", fmt_num(w)),
        None => fmt_num(w),
    }
}

/// Validate the slices against the geometry.
pub(super) fn check(input: &FitPlotInput) -> Result<()> {
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
pub(crate) fn checked_groups(input: &FitPlotInput) -> Result<Vec<Group>> {
    check(input)?;
    Ok(groups(input.geo, input.channels.of_sample))
}

/// The group with the most samples (the first such by θi).
pub(super) fn busiest(gs: &[Group]) -> &Group {
    let mut best = &gs[0];
    for g in gs {
        if g.idx.len() > best.idx.len() {
            best = g;
        }
    }
    best
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
        let gs = groups(&geo, &[]);
        assert_eq!(gs.len(), 2);
        assert_eq!(gs[0].idx, vec![0, 1]);
        let (idx, in_plane) = plane_samples(&geo, &gs[1]);
        assert!(!in_plane);
        assert_eq!(idx, vec![2, 3]);
        assert_eq!(busiest(&gs).idx.len(), 3);
    }
}
