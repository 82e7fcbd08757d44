//! Validate: whether the data can be fitted at all (before the fit), and what the
//! optimum's report must say about points that are not a usable optimum (after it).

use super::driver::{assign, FitConfig};
use super::lm::Termination;
use super::problem::{FitInput, FitParam, ParamLayout, Transform};
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
    Ok((layout, given))
}

/// Whether a free non-negative parameter at `value` with standard error `se` sits at its
/// lower bound 0 (within 10⁻³ standard errors, or exactly 0).
pub(super) fn at_lower_bound(fp: &FitParam, value: f64, se: Option<f64>) -> bool {
    fp.fixed.is_none()
        && fp.transform == Transform::NonNegative
        && se.is_some_and(|e| value <= 1e-3 * e.max(f64::MIN_POSITIVE) || value == 0.0)
}

/// The note for a parameter at its lower bound.
pub(super) fn lower_bound_note(fp: &FitParam) -> String {
    format!(
        "{} is at its lower bound 0: the data shows no such component",
        fp.name
    )
}

/// The note for a solver that stopped without converging, if it did.
pub(super) fn termination_note(termination: Termination) -> Option<String> {
    (!termination.converged()).then(|| {
        format!(
            "the solver stopped without converging: {}",
            termination.describe()
        )
    })
}
