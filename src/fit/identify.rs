//! Identify: what the data determines at the optimum — the covariance of the free
//! parameters, and for KBS models whether the weakest direction of (ln σ, ln T, ln s) is
//! a known regime's ridge (rough: σ and T together at fixed T/σ; smooth: s σ² fixed).

use super::problem::{FitInput, FitProblem, ParamLayout};
use super::result::Verdict;
use super::solve::Run;
use super::stats::covariance;
use nalgebra::{DMatrix, DVector};

/// Largest standard error of ln p for a parameter to count as determined.
pub(crate) const DETERMINED_MAX_LOG_SE: f64 = 1.0;

/// Standard error of ln σ above which a ridge along a regime's known direction counts as
/// undetermined (see `kbs_verdict`).
pub(crate) const LOOSE_LOG_SE: f64 = 0.05;

/// Alignment |cos| of the weakest direction with a regime's known direction.
pub(crate) const ALIGN: f64 = 0.98;

/// Median g above which the rough regime's ridge is expected.
pub(crate) const ROUGH_G: f64 = 3.0;

/// Median g below which the smooth regime's ridge is expected.
pub(crate) const SMOOTH_G: f64 = 0.3;

/// Relative singular-value threshold below which a direction is undetermined.
pub(crate) const RANK_THRESHOLD: f64 = 1e-9;

/// The identifiability of one solved problem.
pub(super) struct Identified {
    pub unc: covariance::Uncertainty,
    pub verdict: Verdict,
    /// Median g over the samples at the fitted σ (KBS models, when the verdict was asked).
    pub g_median: Option<f64>,
}

/// Uncertainty and verdict of `run` on `problem`. The KBS regime verdict is only sought
/// when `seek_verdict` (the fit may reduce); otherwise the verdict is [`Verdict::Full`].
pub(super) fn identify(
    input: &FitInput,
    problem: &FitProblem,
    run: &Run,
    seek_verdict: bool,
) -> Identified {
    let unc = uncertainty_of(problem, run);
    let has_kbs = problem.model.params().iter().any(|s| s.name == "sigma");
    let mut verdict = Verdict::Full;
    let mut g_median = None;
    if has_kbs && seek_verdict {
        let sig = problem.layout.find("sigma")[0];
        let g = input.geo.median_g(run.values[sig]);
        g_median = Some(g);
        if let Some(v) = kbs_verdict(&problem.layout, &unc, &run.values, g) {
            verdict = v;
        }
    }
    Identified {
        unc,
        verdict,
        g_median,
    }
}

/// Uncertainty in the solver's variables (free parameters), from the Jacobian at the
/// optimum. An amplitude held at its bound by the solve's active set (x = 0 exactly:
/// [`super::problem::bounds`]) is a constraint the optimum meets, not a direction the data leaves
/// open: the uncertainty is that of the other parameters with it held, and its own
/// standard error and covariances are 0 (the report says it is at its bound).
pub(super) fn uncertainty_of(problem: &FitProblem, run: &Run) -> covariance::Uncertainty {
    let layout = &problem.layout;
    let free = layout.free();
    let at_bound: Vec<usize> = (0..free.len())
        .filter(|&j| layout.params[free[j]].transform.is_non_negative() && run.lm.x[j] == 0.0)
        .collect();
    let jac = &run.lm.jacobian;
    if at_bound.is_empty() || jac.ncols() != free.len() {
        return covariance::uncertainty(jac, run.lm.cost, problem.len(), RANK_THRESHOLD);
    }
    let kept: Vec<usize> = (0..free.len()).filter(|j| !at_bound.contains(j)).collect();
    let sub = jac.select_columns(&kept);
    let u = covariance::uncertainty(&sub, run.lm.cost, problem.len(), RANK_THRESHOLD);
    let p = free.len();
    let spread = |m: &DMatrix<f64>| {
        let mut out = DMatrix::zeros(p, p);
        for (a, &ja) in kept.iter().enumerate() {
            for (b, &jb) in kept.iter().enumerate() {
                out[(ja, jb)] = m[(a, b)];
            }
        }
        out
    };
    let mut stderr = DVector::zeros(p);
    for (a, &ja) in kept.iter().enumerate() {
        stderr[ja] = u.stderr[a];
    }
    covariance::Uncertainty {
        covariance: spread(&u.covariance),
        correlation: spread(&u.correlation),
        stderr,
        undetermined: u
            .undetermined
            .iter()
            .map(|v| {
                let mut w = DVector::zeros(p);
                for (a, &ja) in kept.iter().enumerate() {
                    w[ja] = v[a];
                }
                w
            })
            .collect(),
        rank: u.rank + at_bound.len(),
        ..u
    }
}

/// The covariance of the free parameters in log space, from the solver's x-space
/// covariance: d ln p = (dp/dx) dx / p.
pub(super) fn log_covariance(
    layout: &ParamLayout,
    unc: &covariance::Uncertainty,
    p: &[f64],
) -> DMatrix<f64> {
    let free = layout.free();
    let f = log_factors(layout, p);
    DMatrix::from_fn(free.len(), free.len(), |i, j| {
        unc.covariance[(i, j)] * f[i] * f[j]
    })
}

/// Decide whether the (σ, T, scale) block is only partly determined, and which regime's
/// combination the weakly determined direction matches.
///
/// Rough (median g > [`ROUGH_G`]): the least determined direction of (ln σ, ln T, ln s)
/// is within [`ALIGN`] of (1, 1, 0) — σ and T move together at fixed T/σ and s(T/σ)² —
/// and σ's standard error exceeds [`LOOSE_LOG_SE`]. Smooth (median g < [`SMOOTH_G`]): the
/// direction is (1, 0, −2) — s σ² fixed. Past [`LOOSE_LOG_SE`] the linearised standard
/// error along such a ridge is not trustworthy (a fit 2× off can report ±28 %), so the
/// parameters are reported as undetermined rather than with a misleading error bar.
fn kbs_verdict(
    layout: &ParamLayout,
    unc: &covariance::Uncertainty,
    p: &[f64],
    g_median: f64,
) -> Option<Verdict> {
    let free = layout.free();
    let cov = log_covariance(layout, unc, p);
    let pos = |name: &str| -> Option<usize> {
        let k = *layout.find(name).first()?;
        free.iter().position(|&f| f == k)
    };
    let (i_s, i_t) = (pos("sigma")?, pos("T")?);
    let i_a = pos("scale");
    let rank_deficient = unc.rank < free.len();
    let sigma_se = cov[(i_s, i_s)].max(0.0).sqrt();
    if !rank_deficient && sigma_se.is_finite() && sigma_se <= LOOSE_LOG_SE {
        return None;
    }
    if rank_deficient && unc.undetermined.is_empty() {
        return None;
    }
    let idx: Vec<usize> = [Some(i_s), Some(i_t), i_a].into_iter().flatten().collect();
    let Some(dir) = weakest_direction(&cov, unc, &log_factors(layout, p), &idx, rank_deficient)
    else {
        return Some(Verdict::Partial);
    };
    let align = |v: &[f64]| -> f64 {
        let t = DVector::from_iterator(idx.len(), v.iter().take(idx.len()).copied());
        (t.dot(&dir) / t.norm()).abs()
    };
    let rough = align(&[1.0, 1.0, 0.0]);
    let smooth = align(&[1.0, 0.0, -2.0]);
    if rough > ALIGN && g_median > ROUGH_G {
        Some(Verdict::Rough)
    } else if smooth > ALIGN && g_median < SMOOTH_G {
        Some(Verdict::Smooth)
    } else if rank_deficient || !sigma_se.is_finite() || sigma_se > DETERMINED_MAX_LOG_SE {
        Some(Verdict::Partial)
    } else {
        None
    }
}

/// d ln p / dx of each free parameter at `p` (the solver's x to log space).
fn log_factors(layout: &ParamLayout, p: &[f64]) -> Vec<f64> {
    layout
        .free()
        .iter()
        .map(|&k| {
            let t = layout.params[k].transform;
            t.dp_dx(t.to_x(p[k])) / p[k]
        })
        .collect()
}

/// The least determined direction in the (ln σ, ln T, ln s) block `idx` of the log-space
/// covariance, normalised: the null direction when the Jacobian is rank deficient (a
/// direction in the solver's canonical x, taken to log space with `log_factor` =
/// d ln p/dx; see `solve::canonicalise` for the sign of an amplitude's x), else the
/// largest-variance eigenvector of that block; None when that has no finite direction.
/// `idx` holds the positions among the free parameters of σ, T and (when free) the scale.
fn weakest_direction(
    cov: &DMatrix<f64>,
    unc: &covariance::Uncertainty,
    log_factor: &[f64],
    idx: &[usize],
    rank_deficient: bool,
) -> Option<DVector<f64>> {
    let dir: DVector<f64> = if rank_deficient {
        let v = unc.undetermined.first()?; // the caller checked it exists
        DVector::from_iterator(idx.len(), idx.iter().map(|&i| v[i] * log_factor[i]))
    } else {
        let block = DMatrix::from_fn(idx.len(), idx.len(), |a, b| cov[(idx[a], idx[b])]);
        let eig = block.symmetric_eigen();
        let imax = eig.eigenvalues.imax();
        eig.eigenvectors.column(imax).into_owned()
    };
    let norm = dir.norm();
    (norm != 0.0 && norm.is_finite()).then(|| dir / norm)
}
