//! Reduce: when the data determines only a regime's combinations (rough: T/σ and
//! s·(T/σ)²; smooth: T and s·σ²), refit the reduced problem with σ held at its estimate,
//! so that T and the scales carry the determined combinations with a finite covariance.
//!
//! That covariance is the *marginal* one of the combinations, σ free
//! ([`marginal_uncertainty`]): the reduced problem's own covariance is conditional on σ
//! being exactly its estimate, and where the data still weakly tie σ to T (the smooth
//! regime's O(g) corrections) it is too narrow (its ±2 s.e. cover 0.73 of smooth-verdict
//! truths in `goniofit recover`).

use super::config::FitConfig;
use super::identify::{log_covariance, uncertainty_of, Identified, RANK_THRESHOLD};
use super::prepare::rough_by_construction;
use super::problem::{FitInput, FitProblem, ParamLayout};
use super::result::{Solved, Verdict};
use super::solve::{run_lm, Run};
use super::stats::covariance;
use crate::error::Result;
use crate::model::Model;
use nalgebra::DMatrix;

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
        unusable: None,
    };
    if rough_by_construction(model, config) {
        // σ is held from the start: nothing to reduce.
        solved.notes.push(ROUGH_MODEL_NOTE.to_string());
        return Ok(solved);
    }
    let (Some(g_median), true) = (
        id.g_median,
        !matches!(id.verdict, Verdict::Full | Verdict::NotComputed),
    ) else {
        return Ok(solved);
    };
    let sig = solved.problem.layout.find("sigma")[0];
    let regime = matches!(id.verdict, Verdict::Rough | Verdict::Smooth);
    // After a stop request the first solve's point is the best so far: no refit.
    let mut stopped = config.stop_requested();
    if regime && !stopped && solved.problem.layout.params[sig].fixed.is_none() {
        let mut reduced = solved.problem.layout.clone();
        reduced.params[sig].fixed = Some(solved.run.values[sig]);
        let p_start = solved.run.values.clone();
        let floor = solved.problem.floor;
        let problem_red =
            FitProblem::new(model, reduced, input, config.residual, floor)?.with_loss(config.loss);
        let mut red = run_lm(&problem_red, &p_start, &config.lm);
        let finite = red.lm.cost.is_finite() && red.lm.jacobian.iter().all(|v| v.is_finite());
        if !finite && config.stop_requested() {
            // Stopped before the refit had a point with its Jacobian: the first solve stays.
            stopped = true;
        } else {
            red.add_counts(&solved.run.lm);
            let conditional = uncertainty_of(&problem_red, &red);
            // The full problem's Jacobian at the reduced optimum; after a stop request it
            // is not evaluated (NaN), and the conditional uncertainty stays.
            let x = solved.problem.layout.to_x(&red.values);
            let jac = solved.problem.jacobian_until(&x, config.lm.stop.as_ref());
            if !jac.iter().all(|v| v.is_finite()) && config.stop_requested() {
                solved.notes.push(MARGINAL_NOT_COMPUTED.to_string());
            }
            solved.unc = marginal_uncertainty(&solved.problem, &jac, &red, id.verdict, conditional);
            solved.run = red;
            solved.problem = problem_red;
        }
    }
    if stopped && regime {
        // The unreduced point is the best found, not the fit's answer.
        solved.run.mark_cut(&config.lm);
    }
    solved.notes.push(if stopped && regime {
        format!("the fit was stopped before the reduced refit (median g = {g_median:.3e}): the data determines only a regime's combinations, and σ, T, scale are those of the unreduced fit")
    } else {
        regime_note(id.verdict, g_median)
    });
    Ok(solved)
}

/// The note of a reduced refit stopped before the full problem's Jacobian at its optimum
/// was evaluated.
const MARGINAL_NOT_COMPUTED: &str = "the fit was stopped before the marginal uncertainty (σ free) of the determined combinations was computed: their standard errors are those with σ held at its estimate, which can be too narrow";

/// The note of a `kbs-rough` fit (σ held by construction, see
/// [`rough_by_construction`]).
const ROUGH_MODEL_NOTE: &str = "kbs-rough (the paper's rough approximation, eq. 43) depends on σ and T only through T/σ: the data determines the slope T/σ (Beckmann's α = 2σ/T) and the lobe amplitude s·(T/σ)², but not σ and T separately; σ was held and σ, T are reported as undetermined (fit kbs for σ and T, which the full model can separate only where the lobe is not fully rough)";

/// The report's note on a verdict other than [`Verdict::Full`].
fn regime_note(verdict: Verdict, g_median: f64) -> String {
    match verdict {
        Verdict::Rough => format!("rough regime (median g = {g_median:.3e}): the data determines only T/σ and the amplitude s·(T/σ)²; σ was held at its estimate and σ, T, scale are reported as undetermined"),
        Verdict::Smooth => format!("smooth regime (median g = {g_median:.3e}): the data determines only T and the amplitude s·σ²; σ was held at its estimate and σ, scale are reported as undetermined"),
        _ => "some parameter combinations are not determined by the data: see the singular values and correlations".to_string(),
    }
}

/// The direction of a regime's ridge in (ln p) over the layout's parameters, normalised so
/// that its σ component is 1: rough, σ and T together (T/σ and s·(T/σ)² held); smooth, σ
/// against every scale as s ∝ σ⁻² (s·σ² held). Parameters off the ridge get 0.
fn ridge_direction(layout: &ParamLayout, verdict: Verdict) -> Vec<f64> {
    layout
        .params
        .iter()
        .map(|fp| {
            let base = fp.name.split('[').next().unwrap_or("");
            match (verdict, base) {
                (_, "sigma") => 1.0,
                (Verdict::Rough, "T") => 1.0,
                (Verdict::Smooth, "scale") => -2.0,
                _ => 0.0,
            }
        })
        .collect()
}

/// The reduced problem's uncertainty with its covariance replaced by the marginal one of
/// the determined combinations, σ free: the full problem's covariance at the reduced
/// optimum (from `jac`, its Jacobian there with the σ column; pseudo-inverse as everywhere) is mapped along the
/// regime's ridge ([`ridge_direction`]) to σ = its held value, i.e. in log space
/// y_k = ln p_k − d_k ln σ for each reduced free parameter k, and C_red = B C_full Bᵀ.
/// Every combination the regime determines is constant along the ridge, so its variance
/// from C_red is its variance with σ free (a Schur complement); the conditional covariance
/// of `conditional` (σ held) is kept when the full Jacobian is not finite. The singular
/// values, rank and null space stay those of the reduced problem.
fn marginal_uncertainty(
    full: &FitProblem,
    jac: &DMatrix<f64>,
    red: &Run,
    verdict: Verdict,
    mut conditional: covariance::Uncertainty,
) -> covariance::Uncertainty {
    let layout = &full.layout;
    let unc = covariance::uncertainty(jac, red.lm.cost, full.len(), RANK_THRESHOLD);
    let c_full = log_covariance(layout, &unc, &red.values);
    let free = layout.free();
    let Some(i_sigma) = free.iter().position(|&k| layout.params[k].name == "sigma") else {
        return conditional;
    };
    if !c_full.iter().all(|v| v.is_finite()) {
        return conditional;
    }
    let d = ridge_direction(layout, verdict);
    let kept: Vec<usize> = free
        .iter()
        .copied()
        .filter(|&k| k != free[i_sigma])
        .collect();
    let b = DMatrix::from_fn(kept.len(), free.len(), |r, c| {
        let k = kept[r];
        f64::from(u8::from(free[c] == k)) - if c == i_sigma { d[k] } else { 0.0 }
    });
    let c_log = &b * c_full * b.transpose();
    // Back from ln p to the reduced problem's solver variables x: dx = p/(dp/dx) d ln p.
    let to_x: Vec<f64> = kept
        .iter()
        .map(|&k| {
            let t = layout.params[k].transform;
            red.values[k] / t.dp_dx(t.to_x(red.values[k]))
        })
        .collect();
    let cov = DMatrix::from_fn(kept.len(), kept.len(), |i, j| {
        c_log[(i, j)] * to_x[i] * to_x[j]
    });
    if !cov.iter().all(|v| v.is_finite()) || cov.nrows() != conditional.covariance.nrows() {
        return conditional;
    }
    let se = nalgebra::DVector::from_iterator(
        cov.nrows(),
        (0..cov.nrows()).map(|i| cov[(i, i)].max(0.0).sqrt()),
    );
    conditional.correlation = covariance::correlation(&cov, &se);
    conditional.stderr = se;
    conditional.covariance = cov;
    conditional.residual_variance = unc.residual_variance;
    conditional
}
