//! The reports of one dataset's [`Outcome`]: the chosen fit's report, with the model
//! comparison when several candidates ran (`auto`), and in JSON the `replay` block that
//! `goniofit plot` redraws from. The CLI and the Python package both print these.

use super::{json, text, RunInfo};
use crate::fit::dataset::Outcome;
use crate::fit::driver::FitResult;
use serde_json::Value;

/// The outcome's report as one JSON object: [`json::to_json`] of the chosen fit, `replay`
/// (see [`replay_json`]) and, for several candidates, `comparison` (model, bic, aic, cost,
/// converged per candidate). `args` are the fit's command-line arguments (without the
/// program name) that `goniofit plot` parses again.
pub fn to_json(o: &Outcome, info: &RunInfo, args: &[String]) -> Value {
    let mut v = json::to_json(&o.result, info);
    v["replay"] = replay_json(&o.result, args);
    if o.candidates.len() > 1 {
        v["comparison"] = serde_json::json!(o
            .candidates
            .iter()
            .map(|r| serde_json::json!({"model": r.model, "bic": r.bic, "aic": r.aic, "cost": r.cost, "converged": r.converged()}))
            .collect::<Vec<_>>());
    }
    v
}

/// The outcome's report as text: the model comparison (lowest BIC wins) when several
/// candidates ran, then [`text::render`] of the chosen fit.
pub fn to_text(o: &Outcome, info: &RunInfo) -> String {
    let mut s = String::new();
    if o.candidates.len() > 1 {
        s += "[[Model comparison]] (lowest BIC wins)\n";
        for r in &o.candidates {
            s += &format!(
                "    {:<17} BIC = {:>14.4}  AIC = {:>14.4}  cost = {:.6e}{}\n",
                r.model,
                r.bic,
                r.aic,
                r.cost,
                if r.model == o.result.model {
                    "  <- chosen"
                } else {
                    ""
                }
            );
        }
    }
    s + &text::render(&o.result, info)
}

/// What `goniofit plot` needs to redraw a fit from its JSON report: the fit's command-line
/// arguments and the fitted values of every parameter (layout order).
pub fn replay_json(r: &FitResult, args: &[String]) -> Value {
    serde_json::json!({
        "args": args,
        "model": r.model,
        "names": r.layout.params.iter().map(|p| p.name.clone()).collect::<Vec<_>>(),
        "values": r.values,
        "n_free": r.n_free,
    })
}

/// Where a fit's setting came from, beside the dataset and the fit input: what the caller
/// (the CLI's arguments, the Python keywords) decided.
#[derive(Debug, Clone, Default)]
pub struct SettingSource {
    /// The input file (absolute path, checksum), or empty for arrays.
    pub file: super::setting::InputInfo,
    /// `--channel` as given.
    pub channel: Option<String>,
    /// The quantity fitted and where it came from (`--quantity`, `stated by the file`,
    /// `default`).
    pub quantity: crate::geometry::Quantity,
    pub quantity_source: String,
    pub residual: crate::fit::problem::ResidualKind,
    /// The floor asked for (None: 1e-6 × max |L|).
    pub floor: Option<f64>,
    /// The unit of λ and where λ came from (`--wavelength`, `channel name`, `wavelength
    /// column`, `none`).
    pub wavelength_unit: Option<String>,
    pub wavelength_source: String,
    /// The robust loss (`linear` = plain least squares; scipy's names) and its scale C
    /// (None for linear).
    pub loss: String,
    pub f_scale: Option<f64>,
    pub absolute_sigma: bool,
}

/// The whole setting of one dataset's fit for the report: the caller's `source`, the
/// floor and how many values it raised, the weights as transformed for the residual, the
/// distinct wavelengths of the samples, and the units.
pub fn setting(
    ds: &crate::io::Dataset,
    input: &crate::fit::driver::FitInput,
    source: &SettingSource,
) -> super::Setting {
    use crate::fit::problem::ResidualKind;
    use crate::fit::weights::{floor_raised, residual_weights};
    let residual = source.residual;
    let floor = crate::fit::dataset::floor_for(source.floor, &input.y);
    let (_, weights) = residual_weights(
        ds.weight.as_deref().filter(|_| ds.sigma_l.is_none()),
        ds.sigma_l.as_deref(),
        &input.y,
        residual,
        floor,
    );
    let mut values: Vec<f64> = Vec::new();
    if source.wavelength_source != "none" {
        for l in input.geo.wavelength.iter() {
            if !values.contains(&l) {
                values.push(l);
            }
        }
    }
    let unit = source.wavelength_unit.clone();
    super::Setting {
        input: source.file.clone(),
        wavelength: super::setting::WavelengthInfo {
            values,
            unit: unit.clone(),
            source: source.wavelength_source.clone(),
        },
        channel: source.channel.clone(),
        quantity: source.quantity,
        quantity_source: source.quantity_source.clone(),
        residual,
        floor: super::setting::FloorInfo {
            value: floor,
            raised: floor_raised(&input.y, residual, floor),
            used: residual != ResidualKind::Absolute,
        },
        weights,
        loss: source.loss.clone(),
        f_scale: source.f_scale,
        absolute_sigma: source.absolute_sigma,
        units: super::Units {
            length: unit,
            quantity: source.quantity,
            radiance: None,
        },
    }
}
