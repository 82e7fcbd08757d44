//! Solve: one Levenberg–Marquardt run of a problem from a point in parameter space.

use nalgebra::{DMatrix, DVector};

use super::problem::{FitInput, FitProblem};
use goniofit_lm as lm;
use goniofit_lm::{LeastSquaresProblem, LmConfig, Stop};

/// An LM run in parameter space.
pub(super) struct Run {
    pub lm: lm::LmReport,
    /// The solver's final point in parameter space (layout order).
    pub values: Vec<f64>,
    /// The run came within [`JOIN_TOL`] of an earlier run's path ([`Trail`]) and was ended
    /// there: it would have followed that run to its optimum.
    pub joined: bool,
}

impl Run {
    /// A converged run kept while a stop request cut the other starts short ends with the
    /// stop's termination: it is the best point found, not the fit's answer.
    pub(super) fn mark_cut(&mut self, config: &LmConfig) {
        let why = config.stop.as_ref().and_then(Stop::requested);
        if let Some(why) = why.filter(|_| self.lm.termination.converged()) {
            self.lm.termination = why;
        }
    }
}

/// Minimise `problem` from `p0` (parameter space, layout order): the solver works in the
/// transformed space x of the layout, and the result is mapped back.
pub(super) fn run_lm(problem: &FitProblem, p0: &[f64], config: &LmConfig) -> Run {
    run_lm_in(problem, p0, config, None, None)
}

/// [`run_lm`], with the trial points whose σ leaves `range` rejected as failed steps (no
/// model evaluation), and with `trail` the run's path recorded there and the run ended
/// (`joined`) where it meets the path of an earlier run on the same trail.
pub(super) fn run_lm_in(
    problem: &FitProblem,
    p0: &[f64],
    config: &LmConfig,
    range: Option<&SigmaRange>,
    trail: Option<&Trail>,
) -> Run {
    let x0 = problem.layout.to_x(p0);
    let layout = &problem.layout;
    let lm = match (&config.stop, range, trail) {
        (None, None, None) => super::problem::bounds::minimize(layout, problem, x0, config),
        (stop, range, trail) => {
            let guarded = Guarded::new(problem, stop.as_ref(), range, trail);
            super::problem::bounds::minimize(layout, &guarded, x0, config)
        }
    };
    problem.forget_cached();
    let joined = trail.is_some_and(Trail::finish_run);
    let mut lm = lm;
    canonicalise(problem, &mut lm);
    let values = problem.layout.from_x(&lm.x);
    Run { lm, values, joined }
}

/// [`run_lm_in`] of a fit with free Fresnel parameters (`n`, `kappa`: [`FACTOR_PARAMS`])
/// in two stages: the lobe settles with those parameters held at `p0`'s values, then all
/// are free from the settled point (the work of both counted in the run). A free index
/// absorbs a lobe's misfit (σ and T off their optimum), so that a solve started away from
/// the lobe's optimum runs to n → ∞ (the plain lobe's valley, a local minimum at infinity)
/// or crawls along the valley n and the lobe share; settled first, the index only moves to
/// its own optimum at that lobe. The settled solve records no trail: only the free one's
/// path is one a later solve can join. A stop request during the settled solve ends the
/// run at its point, with the stop's termination and the Jacobian's columns of the held
/// parameters not evaluated (NaN). Without free Fresnel parameters, or when the settled
/// solve has no finite cost, the plain [`run_lm_in`].
pub(super) fn run_lm_settled(
    problem: &FitProblem,
    input: &FitInput,
    p0: &[f64],
    config: &LmConfig,
    range: Option<&SigmaRange>,
    trail: Option<&Trail>,
) -> Run {
    let Some((lobe, _)) = factors_held(problem, input, p0) else {
        return run_lm_in(problem, p0, config, range, trail);
    };
    let settled = run_lm_in(&lobe, p0, config, range, None);
    if !settled.lm.cost.is_finite() {
        return run_lm_in(problem, p0, config, range, trail);
    }
    if config.stop.as_ref().is_some_and(Stop::is_requested) {
        return lifted(problem, &lobe, settled, config);
    }
    let mut run = run_lm_in(problem, &settled.values, config, range, trail);
    run.add_counts(&settled.lm);
    run
}

/// A run of `lobe` (`problem` with some free parameters held) as a run of `problem`: the
/// solver's point in `problem`'s variables, the held parameters' Jacobian columns not
/// evaluated (NaN), and a converged run's termination that of the stop request that cut
/// the solve after it ([`Run::mark_cut`]).
fn lifted(problem: &FitProblem, lobe: &FitProblem, mut run: Run, config: &LmConfig) -> Run {
    let free = problem.layout.free();
    let lobe_free = lobe.layout.free();
    let mut jacobian = DMatrix::from_element(run.lm.jacobian.nrows(), free.len(), f64::NAN);
    for (j, k) in free.iter().enumerate() {
        if let Some(i) = lobe_free.iter().position(|q| q == k) {
            jacobian.set_column(j, &run.lm.jacobian.column(i));
        }
    }
    run.lm.jacobian = jacobian;
    run.lm.x = problem.layout.to_x(&run.values);
    run.mark_cut(config);
    run
}

/// The Fresnel factor's parameters, held while a lobe settles ([`run_lm_settled`] and the
/// start search's refinement).
pub(in crate::fit) const FACTOR_PARAMS: [&str; 2] = ["n", "kappa"];

/// `problem` on the samples of `input`, with the same loss, with its free Fresnel
/// parameters ([`FACTOR_PARAMS`]) held at `p`'s values (layout order), and the layout
/// indices of those parameters; None when it has none free or the held problem cannot be
/// built.
pub(in crate::fit) fn factors_held<'m>(
    problem: &FitProblem<'m>,
    input: &FitInput,
    p: &[f64],
) -> Option<(FitProblem<'m>, Vec<usize>)> {
    let specs = problem.model.params();
    let mut layout = problem.layout.clone();
    let mut held = Vec::new();
    for (k, fp) in layout.params.iter_mut().enumerate() {
        if fp.fixed.is_none() && FACTOR_PARAMS.contains(&specs[fp.spec].name) {
            fp.fixed = Some(p[k]);
            held.push(k);
        }
    }
    if held.is_empty() {
        return None;
    }
    let (kind, floor) = (problem.kind(), problem.floor);
    let lobe = FitProblem::new(problem.model, layout, input, kind, floor).ok()?;
    Some((lobe.with_loss(problem.loss()), held))
}

/// Largest relative difference, in every parameter, between a point of a run and a point
/// of an earlier run's path at which the later run counts as having joined the earlier
/// one (when its cost there is no lower). Two starts that fall into the same valley then
/// do not both crawl down it (Cornell acryl_blue 610 nm: three solves of ~190 iterations
/// each ended at the same optimum).
pub(super) const JOIN_TOL: f64 = 0.01;

/// The paths of a fit's solves from its several starts: every point evaluated on the whole
/// data (parameter space) with its cost, by run.
#[derive(Default)]
pub(super) struct Trail {
    earlier: std::sync::Mutex<Vec<(Vec<f64>, f64)>>,
    current: std::sync::Mutex<Vec<(Vec<f64>, f64)>>,
    joined: std::sync::atomic::AtomicBool,
}

impl Trail {
    /// Record the current run's point `p` with cost `cost`; true (and from then on) when it
    /// lies within [`JOIN_TOL`] of an earlier run's point whose cost is no higher.
    fn visit(&self, p: Vec<f64>, cost: f64) -> bool {
        use std::sync::atomic::Ordering::Relaxed;
        if self.joined.load(Relaxed) {
            return true;
        }
        let near = |q: &[f64]| {
            p.iter()
                .zip(q)
                .all(|(a, b)| (a - b).abs() <= JOIN_TOL * b.abs())
        };
        let joined = self
            .earlier
            .lock()
            .is_ok_and(|e| e.iter().any(|(q, c)| *c <= cost && near(q)));
        if let Ok(mut cur) = self.current.lock() {
            cur.push((p, cost));
        }
        self.joined.store(joined, Relaxed);
        joined
    }

    /// Whether the run now ending had joined an earlier one; its path becomes an earlier one.
    fn finish_run(&self) -> bool {
        if let (Ok(mut e), Ok(mut c)) = (self.earlier.lock(), self.current.lock()) {
            e.append(&mut c);
        }
        self.joined
            .swap(false, std::sync::atomic::Ordering::Relaxed)
    }

    fn has_joined(&self) -> bool {
        self.joined.load(std::sync::atomic::Ordering::Relaxed)
    }
}

/// Take the solver's end point to the canonical x of its parameters, `to_x(from_x(x))`:
/// a non-negative amplitude's x = ±√(p(p + 2)) may end negative, and there its Jacobian
/// column is that of −x. Flipping both keeps every later use (covariance, null
/// directions, their log-space form through dp/dx at `to_x(p)`) consistent in sign.
fn canonicalise(problem: &FitProblem, lm: &mut lm::LmReport) {
    let free = problem.layout.free();
    for (j, &k) in free.iter().enumerate() {
        let t = problem.layout.params[k].transform;
        if lm.x[j] < 0.0 && t.to_x(t.from_x(lm.x[j])) > 0.0 {
            lm.x[j] = -lm.x[j];
            lm.jacobian.column_mut(j).neg_mut();
        }
    }
}

/// Median g up to which the first solve follows the rough ridge: the fit's own limit
/// ([`super::problem::G_FIT_MAX`]). The ridge can be long (Cornell acryl_blue 440 nm
/// follows it to σ ~ 70 λ in 95 iterations and 6 s, the series costing O(√g) per sample),
/// but a tighter cap such as g = 1e3 stops noiseless synthetic rough data short of its σ,
/// where the O(1/g) correction still determines it, and the rejected steps end the solve
/// without convergence.
pub(super) const RIDGE_G: f64 = super::problem::G_FIT_MAX;

/// Median g below which the first solve does not follow the smooth ridge (σ → 0 at fixed
/// T and s·σ²): there KBS is its smooth limit (eq. 42) but for tails far below the data
/// (Cornell acryl_blue 550 nm: 4·10⁻⁷ of the cost between median g ≈ 10⁻⁶ and σ → 0), and
/// the data determines T and the amplitude only. Following the ridge took 420 iterations.
pub(super) const SMOOTH_RIDGE_G: f64 = 1e-6;

/// The σ values a solve may visit: `min..=max` (layout indices of σ, T and the lobe's
/// scale).
pub(super) struct SigmaRange {
    pub sigma: usize,
    pub t: usize,
    pub scale: Option<usize>,
    pub min: f64,
    pub max: f64,
}

impl SigmaRange {
    /// The range of a single-channel KBS fit with σ and T free: σ from where the median g
    /// over the samples is [`SMOOTH_RIDGE_G`] up to where it reaches [`RIDGE_G`]; None for
    /// other fits.
    pub(super) fn rough_ridge(problem: &FitProblem, input: &FitInput) -> Option<Self> {
        let layout = &problem.layout;
        let free = |name: &str| -> Option<usize> {
            match layout.find(name)[..] {
                [k] if layout.params[k].fixed.is_none() => Some(k),
                _ => None,
            }
        };
        let (sigma, t) = (free("sigma")?, free("T")?);
        let g1 = input.geo.median_g(1.0);
        let (min, max) = ((SMOOTH_RIDGE_G / g1).sqrt(), (RIDGE_G / g1).sqrt());
        let scale = free("scale");
        (min.is_normal() && max.is_finite()).then_some(SigmaRange {
            sigma,
            t,
            scale,
            min,
            max,
        })
    }

    /// `p` (layout order) moved along a ridge into the range: above `max` along the rough
    /// ridge (T scaled with σ, so T/σ and the amplitude s·(T/σ)² stay), below `min` along
    /// the smooth one (T and s·σ² stay). The limit's cost is unchanged; the exact model's
    /// changes by the limit's error (O(1/g), O(g)).
    pub(super) fn project(&self, p: &[f64]) -> Vec<f64> {
        let mut q = p.to_vec();
        let sigma = p[self.sigma];
        if sigma > self.max {
            q[self.t] = p[self.t] * (self.max / sigma);
            q[self.sigma] = self.max;
        } else if sigma < self.min {
            if let Some(k) = self.scale {
                q[k] = p[k] * (sigma / self.min).powi(2);
            }
            q[self.sigma] = self.min;
        }
        q
    }

    fn contains(&self, p: &[f64]) -> bool {
        (self.min..=self.max).contains(&p[self.sigma])
    }
}

impl Run {
    /// Add an earlier run's iteration, evaluation and time counts to this one (the report of
    /// a refit counts the whole fit's work).
    pub(super) fn add_counts(&mut self, earlier: &lm::LmReport) {
        self.lm.iterations += earlier.iterations;
        self.lm.evaluations += earlier.evaluations;
        self.lm.jacobian_evaluations += earlier.jacobian_evaluations;
        self.lm.seconds += earlier.seconds;
    }
}

/// A fit problem whose trial evaluations end within one block of samples once `stop` is
/// requested (and whose Jacobian, when not cached, is then not evaluated), and whose trial
/// points outside `range` are rejected unevaluated (NaN residuals: a failed step). The first evaluation (the solver's start) is cut as well: a
/// run whose start was cut has no point to report (a non-finite cost; the fit then ends
/// with [`crate::error::Error::Stopped`]), never a number from a partial evaluation.
struct Guarded<'p, 'm> {
    problem: &'p FitProblem<'m>,
    stop: Option<&'p Stop>,
    range: Option<&'p SigmaRange>,
    trail: Option<&'p Trail>,
    started: std::sync::atomic::AtomicBool,
}

impl<'p, 'm> Guarded<'p, 'm> {
    fn new(
        problem: &'p FitProblem<'m>,
        stop: Option<&'p Stop>,
        range: Option<&'p SigmaRange>,
        trail: Option<&'p Trail>,
    ) -> Self {
        Guarded {
            problem,
            stop,
            range,
            trail,
            started: std::sync::atomic::AtomicBool::new(false),
        }
    }
}

impl LeastSquaresProblem for Guarded<'_, '_> {
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
        let first = !self
            .started
            .swap(true, std::sync::atomic::Ordering::Relaxed);
        // After joining an earlier run's path every trial fails unevaluated: the trust
        // region collapses within a few steps and the run ends at its point so far.
        if !first
            && (self.trail.is_some_and(Trail::has_joined)
                || self
                    .range
                    .is_some_and(|r| !r.contains(&self.problem.layout.from_x(x))))
        {
            return DVector::from_element(self.problem.len(), f64::NAN);
        }
        let r = self.problem.residuals_until(x, self.stop);
        if let Some(trail) = self.trail {
            let cost = 0.5 * r.norm_squared();
            if cost.is_finite() {
                trail.visit(self.problem.layout.from_x(x), cost);
            }
        }
        r
    }

    fn recycle(&self, spent: DVector<f64>) {
        self.problem.keep_spare(spent);
    }

    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        // After a stop request a Jacobian not cached is not evaluated (NaN): the solver
        // has stopped, and the fit reports its point without uncertainties.
        self.problem.jacobian_until(x, self.stop)
    }

    fn reduced_jacobian(&self, x: &DVector<f64>) -> Option<lm::Reduced> {
        // As the Jacobian: NaN after a stop request when not cached.
        self.problem
            .reduces()
            .then(|| self.problem.reduced_until(x, self.stop))
    }

    fn step_residuals(&self, x: &DVector<f64>) -> Option<DVector<f64>> {
        self.problem.step_residuals(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_run_joins_an_earlier_path_only_near_it_and_not_below_it() {
        let trail = Trail::default();
        assert!(!trail.visit(vec![100.0, 2000.0], 10.0));
        assert!(!trail.visit(vec![90.0, 1900.0], 9.0));
        assert!(!trail.finish_run(), "the first run joins nothing");
        // Within 1 % of (90, 1900) in both parameters, no lower in cost: joined, and stays so.
        assert!(!trail.visit(vec![50.0, 1900.0], 9.5), "σ 44 % away");
        assert!(
            !trail.visit(vec![90.5, 1900.0], 8.9),
            "lower than the earlier point"
        );
        assert!(!trail.visit(vec![90.5, 1925.0], 9.5), "T 1.3 % away");
        assert!(trail.visit(vec![90.5, 1915.0], 9.5));
        assert!(trail.visit(vec![10.0, 10.0], 100.0), "joined stays joined");
        assert!(trail.finish_run());
        // The next run starts unjoined, with both earlier paths to meet.
        assert!(!trail.has_joined());
        assert!(
            trail.visit(vec![50.2, 1901.0], 9.6),
            "the second run's path counts too"
        );
    }
}
