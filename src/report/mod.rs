//! Reporters for a finished fit: one per output format, and what they share (the setting
//! and units of a fit, the input's checksum).

pub mod batch_html;
pub mod checksum;
pub mod design;
pub mod html;
pub mod json;
pub mod outcome;
pub mod setting;
pub mod summary;
pub mod text;

pub use setting::{Setting, Units};

/// How the fit was run, for reproducing it.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct RunInfo {
    /// The input file (as named on the command line, with a `[group]` for a group).
    pub input: String,
    /// The full command line.
    pub command: String,
    /// goniofit version.
    pub version: String,
    /// The fit's setting: input path and checksum, wavelength and units, quantity,
    /// residual, floor, weights, loss.
    pub setting: Setting,
    /// Profile-likelihood intervals of the parameters and derived quantities (empty when
    /// not computed).
    #[serde(skip)]
    pub intervals: Vec<crate::fit::stats::profile::Interval>,
    /// Wall-clock seconds the intervals took (0 when not computed).
    pub interval_seconds: f64,
}

use crate::fit::driver::{Derived, FitResult};

/// For a BRDF, the reflectance factor π·s of every Lambertian term (`scale` of `lambert`
/// and `lambert-specular`, `scale_d` of `kbs+lambert`, per channel), added to the derived
/// quantities with the standard error scaled alike. A radiance has no reflectance factor
/// without the irradiance, so nothing is added then.
pub fn add_reflectance_factors(r: &mut FitResult, units: &Units) {
    if units.quantity != crate::geometry::Quantity::Brdf {
        return;
    }
    let lambert_term = match r.model.as_str() {
        "lambert" | "lambert-specular" => "scale",
        "kbs+lambert" => "scale_d",
        _ => return,
    };
    let pi = std::f64::consts::PI;
    let added: Vec<Derived> = r
        .params
        .iter()
        .filter(|p| setting::base_name(&p.name) == lambert_term)
        .map(|p| Derived {
            name: p.name.replacen(lambert_term, "reflectance_factor", 1),
            value: pi * p.value,
            stderr: p.stderr.map(|s| pi * s),
            determined: p.determined || p.fixed,
            doc: format!("π·{lambert_term}, the Lambertian term as a reflectance factor"),
        })
        .collect();
    r.derived.extend(added);
}

/// Standard errors from the stated uncertainties as they are (scipy's
/// `curve_fit(absolute_sigma=True)`): the fit's covariance s²(JᵀJ)⁺ with s² = 2·cost/(n − p)
/// (the reduced χ² for the linear loss) becomes (JᵀJ)⁺, so every standard error is divided
/// by s. Correlations do not change.
pub fn use_absolute_sigma(r: &mut FitResult) {
    let dof = r.n.saturating_sub(r.n_free).max(1) as f64;
    let s = (2.0 * r.cost / dof).sqrt();
    if !(s.is_finite() && s > 0.0) {
        return;
    }
    for p in &mut r.params {
        p.stderr = p.stderr.map(|e| e / s);
    }
    for d in &mut r.derived {
        d.stderr = d.stderr.map(|e| e / s);
    }
}
