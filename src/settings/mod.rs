//! What a fit is asked to do besides its data and its outputs: one [`Settings`] value.
//! The command line builds it from the flags of `goniofit fit`, the Python package from
//! the keywords of its fit functions, and the JSON report keeps it (`replay.settings`) for
//! `goniofit plot` and `goniofit design --from` to rebuild the fit. From it the library
//! makes what a fit runs on: the read options of a file ([`Settings::read_options`]), the
//! fit's configuration ([`Settings::dataset_fit`], [`Settings::fit_config`]), the quantity
//! and unit of λ the report names, and the equivalent command line
//! ([`Settings::command_line`]); [`crate::report::outcome::setting`] says in the report
//! where each choice came from.
//!
//! Every value is checked by [`Settings::check`] before any work starts, with messages that
//! name the option as the caller spells it ([`Front`]); [`check`]'s functions are the
//! checks of single values that other commands share.

pub mod check;
mod command;
mod run;

pub use check::{
    f_scale, floor, length, model_options, scenes, threads, timeout, tol, Front, MAX_SCENES,
    MAX_TIMEOUT_SECONDS,
};

use crate::fit::problem::loss::LossKind;
use crate::fit::problem::ResidualKind;
use crate::geometry::Quantity;
use crate::model::fresnel::Fresnel;
use crate::model::shadowing::Shadowing;
use crate::model::EvalMode;
use serde::{Deserialize, Serialize};

/// Everything a fit is asked to do that is neither data nor an output choice. Keys as the
/// Python package spells its keywords; in JSON, choices are their lowercase names, `init`
/// and `fix` objects name → value, `patch` a pair `[X, Y]`, and a key left out takes its
/// default ([`Settings::default`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The model: `kbs`, `kbs-smooth`, `kbs-rough`, `kbs+lambert`, `lambert`,
    /// `lambert-specular`, or `auto` (compares candidates by BIC). Default `kbs`.
    pub model: String,
    /// The wavelength λ, the unit of σ and T (> 0, within `crate::geometry::LENGTH_RANGE`);
    /// overrides the data's own. None: the data's (a wavelength column, an ASTM channel
    /// name), or 1 for models without λ.
    pub wavelength: Option<f64>,
    /// The unit of `wavelength` and so of σ, T and patch sizes (`nm`, `µm`); None: not
    /// stated (the data's unit, if any).
    pub wavelength_unit: Option<String>,
    /// Whether the measured value is a radiance or a BRDF. None: what the file states,
    /// else radiance.
    pub quantity: Option<Quantity>,
    /// Of a file, one channel: an ASTM channel (`550nm`), a CSV `group` label or a
    /// wavelength (`0.532` in the file's unit, or `532nm`); `all`: a joint fit of every
    /// channel. None: the file's only channel.
    pub channel: Option<String>,
    /// Of a file, every group fitted on its own (each ASTM channel, each `group` label, or
    /// each wavelength). Default false.
    pub by_group: bool,
    /// Angles of a CSV file (or of the Python package's arrays) in radians. Default false:
    /// degrees.
    pub radians: bool,
    /// An in-plane CSV with signed θr: θr < 0 is the back side (φr = 180°). Default false.
    pub signed_theta_r: bool,
    /// CSV column roles mapped to other header names, `role=name,...` (roles `theta_i`,
    /// `theta_r`, `phi_r`, `L`, `weight`, `sigma_L`, `wavelength`, `group`). None: the
    /// standard names.
    pub columns: Option<String>,
    /// MERL tables: every K-th θd and φd cell fitted, K in 1 ..= 90. Default 1: all.
    pub subsample: usize,
    /// What a sample's residual is: `absolute` f − y, `relative` (f − y)/|y| or `log`
    /// ln f − ln y. Default absolute.
    pub residual: ResidualKind,
    /// The robust loss on the weighted residuals (scipy's names: `linear`, `soft_l1`,
    /// `huber`, `cauchy`, `arctan`). Default linear: least squares.
    pub loss: LossKind,
    /// The loss scale C in the unit of the weighted residual, within [1e-100, 1e100]
    /// (unused by the linear loss). Default 1.
    pub f_scale: f64,
    /// The floor of relative and log residuals, in the unit of the measured value (finite,
    /// > 0). None: 1e-6 × the largest |L|.
    pub floor: Option<f64>,
    /// Starting values, parameter name → value (`scale[550nm]` names one channel's),
    /// overriding the automatic ones.
    #[serde(with = "pairs")]
    pub init: Vec<(String, f64)>,
    /// Parameters held fixed, name → value.
    #[serde(with = "pairs")]
    pub fix: Vec<(String, f64)>,
    /// How the KBS sum is evaluated: `auto` (per sample the cheapest evaluation meeting
    /// `tol`), `series`, `smooth` or `rough`. Default auto.
    pub mode: EvalMode,
    /// The relative accuracy target of the KBS evaluation, in [1e-16, 0.1]. Default 1e-10.
    pub tol: f64,
    /// Patch half-sizes (X, Y) in the unit of λ, each within
    /// `crate::geometry::LENGTH_RANGE`: the KBS lobe with its coherent term. None: without.
    pub patch: Option<(f64, f64)>,
    /// The Fresnel factor on the KBS lobe: `none`, `dielectric`, `conductor`, `schlick`.
    pub fresnel: Fresnel,
    /// The shadowing–masking factor on the KBS lobe: `none`, `smith`, `smith-correlated`.
    pub shadowing: Shadowing,
    /// The most solver iterations (0: the report of the starting point). Default 500.
    pub max_iter: u64,
    /// The time limit in seconds, 0 < t ≤ [`MAX_TIMEOUT_SECONDS`]. None: no limit.
    pub timeout: Option<f64>,
    /// Refit the reduced problem when the data determines only parameter combinations.
    /// Default true.
    pub reduce: bool,
    /// Standard errors and intervals from stated uncertainties as they are (scipy's
    /// `absolute_sigma=True`), not rescaled by the residual scatter. Default false.
    pub absolute_sigma: bool,
    /// Profile-likelihood intervals. None: for a single dataset's fit, not for many.
    pub intervals: Option<bool>,
    /// With several datasets, each fit started at the optimum of the one before it in the
    /// input's order when that serves. Default false.
    pub warm_start: bool,
    /// Threads (≥ 1; more than the machine's cores run on its cores). None: all cores.
    pub threads: Option<usize>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            model: "kbs".into(),
            wavelength: None,
            wavelength_unit: None,
            quantity: None,
            channel: None,
            by_group: false,
            radians: false,
            signed_theta_r: false,
            columns: None,
            subsample: 1,
            residual: ResidualKind::Absolute,
            loss: LossKind::Linear,
            f_scale: 1.0,
            floor: None,
            init: Vec::new(),
            fix: Vec::new(),
            mode: EvalMode::Auto,
            tol: 1e-10,
            patch: None,
            fresnel: Fresnel::None,
            shadowing: Shadowing::None,
            max_iter: 500,
            timeout: None,
            reduce: true,
            absolute_sigma: false,
            intervals: None,
            warm_start: false,
            threads: None,
        }
    }
}

/// `init` and `fix` in JSON: an object name → value, in the order given.
mod pairs {
    use serde::de::{MapAccess, Visitor};
    use serde::ser::SerializeMap;
    use serde::{Deserializer, Serializer};

    pub(super) fn serialize<S: Serializer>(
        pairs: &[(String, f64)],
        s: S,
    ) -> Result<S::Ok, S::Error> {
        let mut map = s.serialize_map(Some(pairs.len()))?;
        for (k, v) in pairs {
            map.serialize_entry(k, v)?;
        }
        map.end()
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(
        d: D,
    ) -> Result<Vec<(String, f64)>, D::Error> {
        struct Pairs;
        impl<'de> Visitor<'de> for Pairs {
            type Value = Vec<(String, f64)>;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("an object parameter name → number")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::new();
                while let Some(entry) = map.next_entry::<String, f64>()? {
                    out.push(entry);
                }
                Ok(out)
            }
        }
        d.deserialize_map(Pairs)
    }
}

#[cfg(test)]
mod tests;
