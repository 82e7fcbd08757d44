//! The fit layer's view of a problem, and the driver: [`minimize`] runs the solver through
//! argmin's Executor and returns an [`LmReport`].

use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::{Duration, Instant};

#[cfg(feature = "progress")]
use argmin::core::observers::ObserverMode;
use argmin::core::{
    Error as ArgminError, Executor, Jacobian, Operator, OptimizationResult, State,
    TerminationReason,
};
use nalgebra::{DMatrix, DVector};

use super::norm::enorm;
#[cfg(feature = "progress")]
use super::progress::ProgressObserver;
use super::reduced::Reduced;
use super::stop::Stop;
use super::{LevenbergMarquardt, LmState, Termination};

/// A least-squares problem in the form the fit layer supplies. Residuals are already
/// weighted (`r̃ᵢ = √wᵢ rᵢ`), so `cost = ½ Σ r̃ᵢ²`.
pub trait LeastSquaresProblem {
    /// Weighted residuals at `x`. May contain NaN or ±∞ (e.g. outside the model's domain):
    /// such a trial point is rejected and the trust region shrinks.
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64>;
    /// Jacobian `∂r̃ᵢ/∂xⱼ` (`m × n`), analytic; see [`super::finite_difference_jacobian`] otherwise.
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64>;
    /// The residuals the step's linear model uses at `x`, when they are not
    /// [`Self::residuals`]. With a robust loss (IRLS), `residuals` are the
    /// cost residuals (½‖r‖² is the cost, which the ratio test and stopping rules need) and
    /// `jacobian` is the IRLS-corrected `J̃`, whose step needs the corrected residuals `f̃`
    /// (`J̃ᵀf̃` is the gradient of the cost, `J̃ᵀJ̃` its Gauss–Newton Hessian). None, the
    /// default: `jacobian` is the Jacobian of `residuals`. The solver asks right after
    /// `jacobian(x)`, at the same `x`.
    fn step_residuals(&self, _x: &DVector<f64>) -> Option<DVector<f64>> {
        None
    }
    /// The Jacobian at `x` reduced to its triangular factor with the residuals at `x`
    /// transformed alike ([`Reduced`]), evaluated in row blocks so that the `m × n`
    /// Jacobian is never held: what a problem of many residuals supplies. The solver asks
    /// for it first wherever it needs the Jacobian, and takes [`Self::jacobian`] when it
    /// is None (the default). A problem with [`Self::step_residuals`] supplies none (its
    /// step is solved with the full Jacobian).
    fn reduced_jacobian(&self, _x: &DVector<f64>) -> Option<Reduced> {
        None
    }
    /// Takes back residuals the solver is done with (a rejected trial point's, or those of
    /// the point it moved away from), so that a problem of many residuals can evaluate its
    /// next point into their storage rather than into new memory. The default drops them.
    fn recycle(&self, _spent: DVector<f64>) {}
}

impl<P: LeastSquaresProblem + ?Sized> LeastSquaresProblem for &P {
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
        (**self).residuals(x)
    }
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        (**self).jacobian(x)
    }
    fn step_residuals(&self, x: &DVector<f64>) -> Option<DVector<f64>> {
        (**self).step_residuals(x)
    }
    fn reduced_jacobian(&self, x: &DVector<f64>) -> Option<Reduced> {
        (**self).reduced_jacobian(x)
    }
    fn recycle(&self, spent: DVector<f64>) {
        (**self).recycle(spent)
    }
}

/// What the solver asks of its operator beyond argmin's [`Operator`] and [`Jacobian`]: the
/// step residuals of [`LeastSquaresProblem::step_residuals`], the reduced Jacobian of
/// [`LeastSquaresProblem::reduced_jacobian`] and [`LeastSquaresProblem::recycle`].
pub trait StepResiduals {
    /// See [`LeastSquaresProblem::step_residuals`].
    fn step_residuals(&self, x: &DVector<f64>) -> Option<DVector<f64>>;
    /// See [`LeastSquaresProblem::reduced_jacobian`]; None by default.
    fn reduced_jacobian(&self, _x: &DVector<f64>) -> Option<Reduced> {
        None
    }
    /// See [`LeastSquaresProblem::recycle`]; drops `spent` by default.
    fn recycle(&self, _spent: DVector<f64>) {}
}

impl<P: LeastSquaresProblem + ?Sized> StepResiduals for ArgminAdapter<'_, P> {
    fn step_residuals(&self, x: &DVector<f64>) -> Option<DVector<f64>> {
        self.0.step_residuals(x)
    }
    fn reduced_jacobian(&self, x: &DVector<f64>) -> Option<Reduced> {
        self.0.reduced_jacobian(x)
    }
    fn recycle(&self, spent: DVector<f64>) {
        self.0.recycle(spent)
    }
}

/// Adapts a [`LeastSquaresProblem`] to argmin's [`Operator`] (residuals) and [`Jacobian`].
#[derive(Debug, Clone, Copy)]
pub struct ArgminAdapter<'a, P: ?Sized>(pub &'a P);

impl<P: LeastSquaresProblem + ?Sized> Operator for ArgminAdapter<'_, P> {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, x: &DVector<f64>) -> Result<DVector<f64>, ArgminError> {
        Ok(self.0.residuals(x))
    }
}

impl<P: LeastSquaresProblem + ?Sized> Jacobian for ArgminAdapter<'_, P> {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, x: &DVector<f64>) -> Result<DMatrix<f64>, ArgminError> {
        Ok(self.0.jacobian(x))
    }
}

/// Options for a run through argmin's Executor. Construct with `..Default::default()` so
/// that fields added later do not break callers.
#[derive(Debug, Clone)]
pub struct LmConfig {
    /// See [`LevenbergMarquardt::with_ftol`]. Default `1e-10`.
    pub ftol: f64,
    /// See [`LevenbergMarquardt::with_xtol`]. Default `1e-10`.
    pub xtol: f64,
    /// See [`LevenbergMarquardt::with_gtol`]. Default `1e-12`.
    pub gtol: f64,
    /// Trial steps (argmin iterations). Default 1000.
    pub max_iters: u64,
    /// Residual evaluations, including the one at the start. Default 2000.
    pub max_evals: u64,
    /// Wall-clock limit of this run (ignored with [`Self::stop`], which carries its own
    /// deadline). Default none.
    pub timeout: Option<Duration>,
    /// Show a progress line on the terminal (stderr, via indicatif; with the crate's
    /// `progress` feature, ignored without it). Default false.
    pub progress: bool,
    /// Stop when this flag becomes true (in addition to the host's signals). Default none.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// The stop request of the whole piece of work this run belongs to (a fit's start
    /// search, solves and refits share one, so that a signal or the fit's deadline ends them
    /// all). Default none: the run makes its own from `timeout` and the signals.
    pub stop: Option<Stop>,
    /// Gauss–Newton polishing after convergence, see [`LevenbergMarquardt::with_polish`].
    /// Default false: with measurement noise, parameters converged to `ftol = 1e-10` are
    /// already far more precise than their standard errors; turn it on when the last digits
    /// matter (the NIST suite runs with it).
    pub polish: bool,
    /// See [`LevenbergMarquardt::with_predicted_stop`]. Default false (MINPACK's rules);
    /// ignored with `polish`.
    pub predicted_stop: bool,
}

impl Default for LmConfig {
    fn default() -> Self {
        LmConfig {
            ftol: 1e-10,
            xtol: 1e-10,
            gtol: 1e-12,
            max_iters: 1000,
            max_evals: 2000,
            timeout: None,
            progress: false,
            interrupt: None,
            stop: None,
            polish: false,
            predicted_stop: false,
        }
    }
}

impl LmConfig {
    /// A stop request from this configuration: `timeout` from now, the `interrupt` flag,
    /// and the host's signals (see [`super::stop::interrupt`]).
    pub fn new_stop(&self) -> Stop {
        Stop::new(self.timeout, self.interrupt.clone())
    }
}

/// The result of a run: never an error for non-convergence.
#[derive(Debug, Clone)]
pub struct LmReport {
    /// Final (best) parameters.
    pub x: DVector<f64>,
    /// Weighted residuals at `x`.
    pub residuals: DVector<f64>,
    /// Jacobian at `x` (evaluated once more at the end if the last step was accepted); for
    /// a problem that supplies [`LeastSquaresProblem::reduced_jacobian`], the reduced
    /// matrix `A` instead (`n` columns, a few rows, `AᵀA = JᵀJ`): what the covariance
    /// needs.
    pub jacobian: DMatrix<f64>,
    /// `½ ‖residuals‖²`.
    pub cost: f64,
    /// Why the run stopped (converged by a tolerance, or not: see [`Termination`]).
    pub termination: Termination,
    /// argmin iterations = trial steps.
    pub iterations: u64,
    /// Residual evaluations (including the start).
    pub evaluations: u64,
    /// Jacobian evaluations, including one more at the end when the solver holds none at
    /// `x`.
    pub jacobian_evaluations: u64,
    /// Wall-clock seconds of the run.
    pub seconds: f64,
}

/// Run LM via argmin's Executor on any [`LeastSquaresProblem`], with Ctrl-C handling (see the
/// module docs). Never fails: a run that does not converge returns a report saying why.
/// Invalid tolerances in `config` are clamped to 0 (the builders validate instead).
pub fn minimize<P: LeastSquaresProblem + ?Sized>(
    problem: &P,
    x0: DVector<f64>,
    config: &LmConfig,
) -> LmReport {
    let start = Instant::now();
    let exec = Executor::new(ArgminAdapter(problem), solver_for(config))
        .configure(|s| s.param(x0.clone()).max_iters(config.max_iters));
    #[cfg(feature = "progress")]
    let exec = if config.progress {
        exec.add_observer(ProgressObserver::new(), ObserverMode::Always)
    } else {
        exec
    };
    match exec.run() {
        Ok(result) => report_of(problem, &x0, result, start),
        // Unreachable with this adapter (it never fails) and the Executor's handler off.
        Err(_) => report_at_start(problem, &x0, Termination::NoProgress, start),
    }
}

/// The solver `config` describes (tolerances clamped to 0 when invalid).
fn solver_for(config: &LmConfig) -> LevenbergMarquardt {
    let tol = |v: f64| if v.is_finite() && v >= 0.0 { v } else { 0.0 };
    let solver = LevenbergMarquardt {
        ftol: tol(config.ftol),
        xtol: tol(config.xtol),
        gtol: tol(config.gtol),
        max_evals: config.max_evals.max(1),
        polish: config.polish,
        predicted_stop: config.predicted_stop,
        ..LevenbergMarquardt::new()
    };
    let stop = match &config.stop {
        Some(stop) => stop.clone(),
        None => config.new_stop(),
    };
    match &config.interrupt {
        Some(flag) => solver.with_interrupt(flag.clone()),
        None => solver,
    }
    .with_stop(stop)
}

/// The report of a finished Executor run: the solver's own termination, or argmin's
/// (iterations, time, interrupt); the Jacobian is evaluated once more when the last step
/// was accepted.
fn report_of<P, O>(
    problem: &P,
    x0: &DVector<f64>,
    result: OptimizationResult<O, LevenbergMarquardt, LmState>,
    start: Instant,
) -> LmReport
where
    P: LeastSquaresProblem + ?Sized,
{
    let state = &result.state;
    let mut solver = result.solver;
    let termination = solver
        .termination
        .unwrap_or(match state.get_termination_reason() {
            Some(TerminationReason::MaxItersReached) => Termination::MaxIterations,
            Some(TerminationReason::Timeout) => Termination::Timeout,
            Some(TerminationReason::Interrupt) => Termination::Interrupted,
            _ => Termination::NoProgress,
        });
    let (evaluations, mut jacobian_evaluations) =
        (solver.evaluations(), solver.jacobian_evaluations());
    let taken = solver.take_jacobian();
    // The point and its residuals moved out of the solver (no copy of a big fit's).
    let Some(work) = solver.work.take() else {
        return report_at_start(problem, x0, termination, start);
    };
    let (x, residuals) = match work.r.len() == work.m {
        true => (work.x, work.r),
        false => (work.x, work.r.rows(0, work.m).into_owned()),
    };
    let jacobian = match taken {
        Some(j) => j,
        None => {
            jacobian_evaluations += 1;
            jacobian_or_reduced(problem, &x)
        }
    };
    LmReport {
        cost: 0.5 * enorm(residuals.as_slice()).powi(2),
        x,
        residuals,
        jacobian,
        termination,
        iterations: state.get_iter(),
        evaluations,
        jacobian_evaluations,
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// A report at the starting point (when the solver holds no iterate).
fn report_at_start<P: LeastSquaresProblem + ?Sized>(
    problem: &P,
    x0: &DVector<f64>,
    termination: Termination,
    start: Instant,
) -> LmReport {
    let residuals = problem.residuals(x0);
    let jacobian = jacobian_or_reduced(problem, x0);
    LmReport {
        cost: 0.5 * residuals.norm_squared(),
        x: x0.clone(),
        residuals,
        jacobian,
        termination,
        iterations: 0,
        evaluations: 1,
        jacobian_evaluations: 1,
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// The reduced Jacobian's matrix `A` at `x` when the problem supplies one, else the
/// Jacobian.
fn jacobian_or_reduced<P: LeastSquaresProblem + ?Sized>(
    problem: &P,
    x: &DVector<f64>,
) -> DMatrix<f64> {
    match problem.reduced_jacobian(x) {
        Some(red) => red.a,
        None => problem.jacobian(x),
    }
}
