//! Reduce: when the data determines only a regime's combinations (rough: T/σ and
//! s·(T/σ)²; smooth: T and s·σ²), refit the reduced problem with σ held at its estimate,
//! so that T and the scales carry the determined combinations with a finite covariance.

use super::config::FitConfig;
use super::identify::{uncertainty_of, Identified};
use super::problem::{FitInput, FitProblem};
use super::result::Verdict;
use super::solve::{run_lm, Run};
use super::stats;
use crate::error::Result;
use crate::model::Model;

/// The problem and solver run a report describes (the first solve, or the reduced refit),
/// with its uncertainty, verdict and the notes that explain the verdict.
pub(super) struct Solved<'m> {
    pub problem: FitProblem<'m>,
    pub run: Run,
    pub unc: stats::Uncertainty,
    pub verdict: Verdict,
    pub notes: Vec<String>,
}

/// The reduced refit when the verdict is a known regime and σ is free; otherwise the first
/// solve as it is. The refit starts at the first solve's optimum, and its report counts the
/// iterations of both.
pub(super) fn reduce<'m>(
    model: &'m dyn Model,
    input: &FitInput,
    config: &FitConfig,
    problem: FitProblem<'m>,
    run: Run,
    id: Identified,
) -> Result<Solved<'m>> {
    let mut solved = Solved {
        problem,
        run,
        unc: id.unc,
        verdict: id.verdict,
        notes: Vec::new(),
    };
    if super::validate::rough_by_construction(model, config) {
        // σ is held from the start: nothing to reduce.
        solved.notes.push(ROUGH_MODEL_NOTE.to_string());
        return Ok(solved);
    }
    let (Some(g_median), true) = (id.g_median, id.verdict != Verdict::Full) else {
        return Ok(solved);
    };
    let sig = solved.problem.layout.find("sigma")[0];
    let regime = matches!(id.verdict, Verdict::Rough | Verdict::Smooth);
    // After a stop request the first solve's point is the best so far: no refit.
    let stopped = super::driver::stop_requested(config);
    if regime && !stopped && solved.problem.layout.params[sig].fixed.is_none() {
        let mut reduced = solved.problem.layout.clone();
        reduced.params[sig].fixed = Some(solved.run.values[sig]);
        let p_start = solved.run.values.clone();
        let floor = solved.problem.floor;
        let problem_red =
            FitProblem::new(model, reduced, input, config.residual, floor)?.with_loss(config.loss);
        let mut red = run_lm(&problem_red, &p_start, &config.lm);
        red.add_counts(&solved.run.lm);
        solved.unc = uncertainty_of(&problem_red, &red);
        solved.run = red;
        solved.problem = problem_red;
    }
    solved.notes.push(if stopped && regime {
        format!("the fit was stopped before the reduced refit (median g = {g_median:.3e}): the data determines only a regime's combinations, and σ, T, scale are those of the unreduced fit")
    } else {
        regime_note(id.verdict, g_median)
    });
    Ok(solved)
}

/// The note of a `kbs-rough` fit (σ held by construction, see
/// [`super::validate::rough_by_construction`]).
const ROUGH_MODEL_NOTE: &str = "kbs-rough (the paper's rough approximation, eq. 43) depends on σ and T only through T/σ: the data determines the slope T/σ (rms slope 2σ/T) and the lobe amplitude s·(T/σ)², but not σ and T separately; σ was held and σ, T are reported as undetermined (fit kbs for σ and T, which the full model can separate only where the lobe is not fully rough)";

/// The report's note on a verdict other than [`Verdict::Full`].
fn regime_note(verdict: Verdict, g_median: f64) -> String {
    match verdict {
        Verdict::Rough => format!("rough regime (median g = {g_median:.3e}): the data determines only T/σ and the amplitude s·(T/σ)²; σ was held at its estimate and σ, T, scale are reported as undetermined"),
        Verdict::Smooth => format!("smooth regime (median g = {g_median:.3e}): the data determines only T and the amplitude s·σ²; σ was held at its estimate and σ, scale are reported as undetermined"),
        _ => "some parameter combinations are not determined by the data: see the singular values and correlations".to_string(),
    }
}
