//! Prepare: the fit's parameter layout from the model, the data and the user's `--fix` and
//! `--init` values, and the refusal of data that cannot be fitted at all.

use super::config::FitConfig;
use super::problem::{FitInput, ParamLayout};
use crate::error::{Error, Result};
use crate::model::Model;

/// The parameter layout of the fit with the `--fix` values held, and the values the user
/// gave (`--fix` and `--init`, layout order). Refuses data that cannot be fitted: no more
/// samples than free parameters, or every value zero.
pub(super) fn prepare(
    model: &dyn Model,
    input: &FitInput,
    config: &FitConfig,
) -> Result<(ParamLayout, Vec<Option<f64>>)> {
    let n = input.geo.len();
    let mut layout = ParamLayout::new(model, &input.channel_names);
    layout.set_amplitude_units(&input.y, &input.channel);
    let mut fixed = vec![None; layout.len()];
    assign(&layout, &config.fix, &mut fixed)?;
    for (k, f) in fixed.iter().enumerate() {
        layout.params[k].fixed = *f;
    }
    let n_free = layout.free().len();
    if n <= n_free {
        return Err(Error::Usage(format!(
            "{n} samples for {n_free} free parameters: a fit needs more samples than free parameters"
        )));
    }
    if input.y.iter().all(|&v| v == 0.0) {
        return Err(Error::Usage(
            "every measured value is zero: nothing to fit".into(),
        ));
    }
    let mut given = fixed;
    assign(&layout, &config.init, &mut given)?;
    if rough_by_construction(model, config) {
        hold_rough_sigma(&mut layout, &mut given, input);
    }
    Ok((layout, given))
}

/// Whether the fit is in the rough approximation's own parameters by construction: the
/// `kbs-rough` model (eq. 43, ⟨|ρ|²⟩ ≈ πT²F²/(A g) · e^{−a/g}) depends on σ and T only
/// through T/σ (g ∝ σ², a ∝ T²), so σ and T cannot both be fitted; unless the user fixes
/// σ, the fit holds it (see [`hold_rough_sigma`]) and reports T/σ, the amplitude s(T/σ)²
/// and s, with σ and T not determined.
pub(super) fn rough_by_construction(model: &dyn Model, config: &FitConfig) -> bool {
    model.name() == "kbs-rough"
        && !config
            .fix
            .iter()
            .any(|(name, _)| name.eq_ignore_ascii_case("sigma"))
}

/// Hold σ of a `kbs-rough` fit at its `--init` value, or else at the median wavelength
/// (any value gives the same model values at the same T/σ; σ = λ keeps g ≈ 40–160, well
/// inside the fit's domain). T then carries T/σ.
fn hold_rough_sigma(layout: &mut ParamLayout, given: &mut [Option<f64>], input: &FitInput) {
    let Some(&ks) = layout.find("sigma").first() else {
        return;
    };
    let held = given[ks].unwrap_or_else(|| input.geo.wavelength.median());
    layout.params[ks].fixed = Some(held);
    given[ks] = Some(held);
}

/// Resolve (name, value) pairs against a layout: a bare per-channel name applies to every
/// channel.
fn assign(layout: &ParamLayout, pairs: &[(String, f64)], out: &mut [Option<f64>]) -> Result<()> {
    for (name, v) in pairs {
        let ks = layout.find(name);
        if ks.is_empty() {
            return Err(Error::Param {
                name: name.clone(),
                message: format!(
                    "not a parameter of this fit (it has: {})",
                    layout
                        .params
                        .iter()
                        .map(|p| p.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            });
        }
        for k in ks {
            let fp = &layout.params[k];
            if !v.is_finite()
                || (fp.transform.is_log() && *v <= fp.transform.lower())
                || *v < 0.0 && fp.transform.is_non_negative()
            {
                return Err(Error::Param {
                    name: name.clone(),
                    message: format!("value {v} is outside its domain"),
                });
            }
            out[k] = Some(*v);
        }
    }
    Ok(())
}
