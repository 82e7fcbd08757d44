//! Levenberg–Marquardt as an argmin [`Solver`]: Moré's scaled trust-region method, the
//! design of MINPACK's `lmder` (Moré 1978, "The Levenberg–Marquardt algorithm:
//! implementation and theory"; Moré, Garbow, Hillstrom 1980, ANL-80-74).
//!
//! # Problem and cost convention
//! Minimise `cost(x) = ½ Σᵢ r̃ᵢ(x)²` over `x ∈ ℝⁿ`, where the residuals are already weighted,
//! `r̃ᵢ = √wᵢ rᵢ` (the factor ½ as in MINPACK, scipy and Ceres; the gradient is `Jᵀr̃`).
//!
//! # The step
//! Each trial step `p` solves `min ½‖J p + r‖²` subject to `‖D p‖ ≤ Δ` (`D` diagonal scaling).
//! It is computed from a Householder QR factorisation of `J` with column pivoting
//! (`J P = Q R`, as MINPACK `qrfac`), and for a positive Levenberg parameter `λ` by
//! Givens-rotating `√λ D` into `R` (MINPACK `qrsolv`); `λ` is found by Moré's safeguarded
//! Newton iteration on `‖D p(λ)‖ = Δ` (MINPACK `lmpar`). `JᵀJ` is never formed or inverted.
//! A rank-deficient `R` (zero pivots) gives the minimum-length Gauss–Newton step of the
//! non-singular part, and for `λ > 0` the system is always regular.
//!
//! * `D = diag(max over iterations of the column norms of J)` (MINPACK `mode = 1`).
//! * `Δ₀ = stepbound · ‖D x₀‖` (or `stepbound` when that is zero); `stepbound = 100`.
//! * Ratio `ρ = actual / predicted reduction`; `ρ < 0.25` shrinks `Δ` (by a factor in
//!   `[0.1, 0.5]` from a quadratic interpolation), `ρ > 0.75` (or `λ = 0`) sets
//!   `Δ = 2‖D p‖`; the step is accepted when `ρ ≥ 10⁻⁴`.
//! * A trial point whose residual vector contains NaN or ±∞ is treated as a failed step of
//!   infinite cost: it is rejected and `Δ` shrinks by 10.
//! * Robust losses: when the problem supplies step residuals
//!   ([`LeastSquaresProblem::step_residuals`]), `r` (whose ½‖r‖² is the cost) serves the
//!   cost, the ratio and the stopping rules, and the step, the gradient `J̃ᵀf̃` and the
//!   `gtol` cosine use the step residuals `f̃` with the corrected Jacobian `J̃` (scipy's
//!   `trf` with a loss does the same: cost from ρ, step from the scaled `f` and `J`).
//!
//! # Iterations and the argmin state
//! One argmin iteration is one trial step (one residual evaluation), accepted or not — as
//! Ceres counts iterations; polishing steps count too. The Jacobian is evaluated after each accepted step only. In the
//! [`IterState`], `param` is the current (best) point, `cost` is `½‖r‖²` there, `gradient`
//! holds `Jᵀr` and `jacobian` holds `J`, both at the point where the Jacobian was last
//! evaluated (the current point, except right after an accepted step).
//!
//! # Stopping rules (MINPACK's, reported as [`Termination`])
//! * `Ftol`: both the actual and the predicted relative reductions of the cost are at most
//!   `ftol` (MINPACK info 1), or at most machine epsilon (info 6).
//! * `Xtol`: the trust radius is at most `xtol · ‖D x‖` (info 2), or machine epsilon (7) —
//!   unless the last trial point had non-finite residuals: then `NoProgress`.
//! * `Gtol`: the largest cosine between `r` and a column of `J` is at most `gtol` (info 4),
//!   or machine epsilon (8).
//! * `Predicted` (optional, [`LevenbergMarquardt::with_predicted_stop`]; goniofit's fits
//!   use it): the next trial step is the undamped Gauss–Newton step, it predicts a relative
//!   reduction of at most `ftol`, and the last accepted step's reduction matched its
//!   prediction within 25 % — so the evaluation that would confirm `Ftol` is skipped. The
//!   cost is then within about `ftol` (relative) of the converged one.
//! * `MaxEvaluations`, `MaxIterations`, `Timeout`, `Interrupted` (Ctrl-C, SIGTERM, SIGHUP).
//! * After `Ftol`/`Xtol` the solver polishes with a few Gauss–Newton steps (see
//!   [`LevenbergMarquardt::with_polish`]) and then reports the rule that fired.
//!
//! # Departures from MINPACK
//! * The actual reduction is computed as `−Σ(r₁ᵢ−rᵢ)(r₁ᵢ+rᵢ)/‖r‖²` instead of
//!   `1 − (‖r₁‖/‖r‖)²`, which keeps its digits when the two norms agree to many places.
//! * Non-finite trial residuals are a rejected step (MINPACK has no such notion).
//! * Fewer residuals than parameters (`m < n`) are handled by padding with zero rows.
//! * Optional Gauss–Newton polishing after convergence (off by default;
//!   [`LevenbergMarquardt::with_polish`], [`LmConfig::polish`]).
//!   This is what takes the NIST StRD suite from a mean LRE of 9.3 (plain `lmder` rules,
//!   this code with polishing off) to 10.7; see `docs/nist.md`.
//!
//! # Ctrl-C, SIGTERM, time limits
//! [`minimize`] turns the Executor's own handler off (argmin binds it to the first run in the
//! process: later runs could not be interrupted). A [`Stop`] carries the stop request: one
//! process-wide handler, installed on first use, interrupts every live `Stop` on Ctrl-C (or
//! SIGTERM/SIGHUP), and a `Stop` may carry a deadline. The solver checks it before every
//! trial step and after every trial evaluation, and ends with [`Termination::Interrupted`] or
//! [`Termination::Timeout`] at the best point so far, with a full report; an evaluation cut
//! short by the request (the fit layer checks it between blocks of samples) is no step. One
//! `Stop` shared through [`LmConfig::stop`] ends every run of a fit. When no `Stop` is alive
//! the handler exits the process with status 130, as the default handler would. A caller's
//! own flag can be passed in [`LmConfig::interrupt`].
//!
//! Defaults: `ftol = xtol = 1e-10`, `gtol = 1e-12`. MINPACK's driver `lmder1` uses
//! `ftol = xtol = √ε ≈ 1.5e-8`, `gtol = 0`; our defaults are tighter because a fit's standard
//! errors are only as good as its convergence, and LM converges quadratically on
//! small-residual problems so the extra digits cost one or two iterations.
//!
//! # Where the parts are
//! * [`LevenbergMarquardt`] (this file): the solver, its options, and one iteration
//!   (`next_iter`) as a sequence of named stages.
//! * `work.rs`: what the iteration carries; the Jacobian stage (evaluate, factor, scale,
//!   gradient test).
//! * `step.rs`: one trial step: damped step, ratio, trust-region update, convergence tests.
//! * `polish.rs`: Gauss–Newton polishing after convergence.
//! * `qr.rs`: MINPACK `qrfac` and `qrsolv`; `lmpar.rs`: MINPACK `lmpar`; `norm.rs`: `enorm`.
//! * `reduced.rs`: [`Reduced`], a Jacobian reduced block by block of rows to its triangular
//!   factor, which a problem of many residuals supplies
//!   ([`LeastSquaresProblem::reduced_jacobian`]) so that its `m × n` Jacobian is never held:
//!   the pivoted QR of that factor with `Qᵀr` gives the same steps to rounding.
//! * `run.rs`: [`LeastSquaresProblem`], [`LmConfig`], [`LmReport`] and [`minimize`], the
//!   driver through argmin's Executor; `stop.rs`: [`Stop`], the Ctrl-C handler and deadlines;
//!   `progress.rs`: the progress line.
//! * `transform.rs`: [`Transformed`] (log and fixed parameters); `fd.rs`: finite differences.

mod closure;
mod fd;
mod invalid;
mod lmpar;
mod norm;
mod polish;
#[cfg(feature = "progress")]
mod progress;
mod qr;
mod reduced;
mod run;
mod step;
pub mod stop;
mod termination;
#[cfg(test)]
mod test_problems;
#[cfg(test)]
mod tests;
/// The crate by its own name, for the test problems shared with the library's tests.
#[cfg(test)]
extern crate self as goniofit_lm;
mod transform;
mod work;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use argmin::core::{
    Error as ArgminError, IterState, Jacobian, Operator, Problem, Solver, TerminationReason,
    TerminationStatus, KV,
};
use nalgebra::{DMatrix, DVector};

pub use closure::Closure;
pub use fd::finite_difference_jacobian;
pub use invalid::Invalid;
pub use reduced::Reduced;
pub use run::{minimize, ArgminAdapter, LeastSquaresProblem, LmConfig, LmReport, StepResiduals};
pub use stop::Stop;
pub use termination::Termination;
pub use transform::Transformed;

use norm::{all_finite, pad_vec};
use step::Tolerances;
use work::Polish;
use work::Work;

/// The argmin state the solver runs on: parameters `DVector`, gradient slot `Jᵀr`,
/// Jacobian `DMatrix`, no Hessian, no residual slot (residuals live in the solver), `f64` cost.
pub type LmState = IterState<DVector<f64>, DVector<f64>, DMatrix<f64>, (), (), f64>;

const EPSMCH: f64 = f64::EPSILON;
/// Acceptance threshold on the ratio of actual to predicted reduction.
const RHO_ACCEPT: f64 = 1e-4;
const RHO_SHRINK: f64 = 0.25;
const RHO_EXPAND: f64 = 0.75;

/// Moré's scaled trust-region Levenberg–Marquardt (MINPACK `lmder` design) as an argmin
/// [`Solver`] over `DVector<f64>` parameters, `DVector<f64>` residuals and `DMatrix<f64>`
/// Jacobians. See the [module documentation](self) for the algorithm and the state layout.
#[derive(Debug, Clone)]
pub struct LevenbergMarquardt {
    ftol: f64,
    xtol: f64,
    gtol: f64,
    stepbound: f64,
    max_evals: u64,
    interrupt: Option<Arc<AtomicBool>>,
    stop: Option<Stop>,
    polish: bool,
    predicted_stop: bool,
    work: Option<Work>,
    termination: Option<Termination>,
}

impl Default for LevenbergMarquardt {
    fn default() -> Self {
        Self::new()
    }
}

impl LevenbergMarquardt {
    /// Defaults: `ftol = xtol = 1e-10`, `gtol = 1e-12`, step bound factor 100, polishing off,
    /// unlimited evaluations (bound the run with the Executor's `max_iters`, or
    /// [`Self::with_max_evals`]).
    pub fn new() -> Self {
        LevenbergMarquardt {
            ftol: 1e-10,
            xtol: 1e-10,
            gtol: 1e-12,
            stepbound: 100.0,
            max_evals: u64::MAX,
            interrupt: None,
            stop: None,
            polish: false,
            predicted_stop: false,
            work: None,
            termination: None,
        }
    }

    fn check_tol(name: &str, v: f64) -> Result<f64, Invalid> {
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(Invalid::new(
                name,
                format!("{v} is not a valid tolerance; use a finite number ≥ 0, e.g. 1e-10"),
            ))
        }
    }

    /// Relative cost-reduction tolerance (finite, ≥ 0).
    pub fn with_ftol(mut self, v: f64) -> Result<Self, Invalid> {
        self.ftol = Self::check_tol("ftol", v)?;
        Ok(self)
    }

    /// Relative step-size tolerance (finite, ≥ 0).
    pub fn with_xtol(mut self, v: f64) -> Result<Self, Invalid> {
        self.xtol = Self::check_tol("xtol", v)?;
        Ok(self)
    }

    /// Gradient tolerance on the cosine between `r` and the columns of `J` (finite, ≥ 0).
    pub fn with_gtol(mut self, v: f64) -> Result<Self, Invalid> {
        self.gtol = Self::check_tol("gtol", v)?;
        Ok(self)
    }

    /// Initial trust radius factor: `Δ₀ = factor · ‖D x₀‖` (MINPACK `factor`, default 100;
    /// must be finite and > 0).
    pub fn with_stepbound(mut self, v: f64) -> Result<Self, Invalid> {
        if !(v.is_finite() && v > 0.0) {
            return Err(Invalid::new(
                "stepbound",
                format!("{v} must be a finite number > 0, e.g. 100"),
            ));
        }
        self.stepbound = v;
        Ok(self)
    }

    /// Maximum number of residual evaluations (including the one at the start; ≥ 1).
    pub fn with_max_evals(mut self, v: u64) -> Result<Self, Invalid> {
        if v == 0 {
            return Err(Invalid::new(
                "max_evals",
                "0 evaluations cannot start a fit; use at least 1".into(),
            ));
        }
        self.max_evals = v;
        Ok(self)
    }

    /// Stop before evaluating a trial step when it is the undamped Gauss–Newton step, its
    /// predicted relative cost reduction ‖J p‖²/‖r‖² is at most `ftol`, and the last accepted
    /// step's reduction matched its prediction (ratio in [0.75, 1.25], so the linear model
    /// is trustworthy at this scale): `ftol`'s promise — less than `ftol` of relative
    /// reduction left — then already holds, and MINPACK's rule would only confirm it with one
    /// more residual evaluation. Reported as [`Termination::Predicted`]. Default off; ignored
    /// while polishing is on.
    pub fn with_predicted_stop(mut self, on: bool) -> Self {
        self.predicted_stop = on;
        self
    }

    /// Gauss–Newton polishing after convergence (default off). Once a stopping rule on
    /// `ftol` or `xtol` holds, the relative cost reductions still to be had are at the level
    /// of rounding, so the ratio test can no longer tell good steps from bad ones, yet the
    /// Gauss–Newton step from the pivoted QR is still accurate far below that. The solver
    /// then iterates undamped Gauss–Newton steps, which are accepted only while the step's
    /// predicted relative cost reduction is at most `1e-10` and the cost stays within
    /// `max(1e-10, 4·noise)` (relative, `noise` = the largest relative cost change seen on LM
    /// trial steps that predicted less than `1e-12`, capped at `1e-6`) of the cost where
    /// polishing started — so polishing cannot change the cost by more than rounding noise —
    /// and the first step is at most `1e-4‖D x‖`. It stops after 30 steps,
    /// or once 6 iterates in a row fail to produce a smaller step than the best so far, and
    /// returns the iterate with the smallest Gauss–Newton step `‖D p‖` (the linear model's
    /// estimate of the distance to the minimum), reporting the rule that started the phase.
    /// Costs one residual and one Jacobian evaluation per step (typically 5–15 steps) and
    /// buys, on the NIST suite, 1–4 correct digits.
    pub fn with_polish(mut self, on: bool) -> Self {
        self.polish = on;
        self
    }

    /// A flag the caller can set (from any thread) to stop the run after the current step;
    /// the run then ends with [`Termination::Interrupted`].
    pub fn with_interrupt(mut self, flag: Arc<AtomicBool>) -> Self {
        self.interrupt = Some(flag);
        self
    }

    /// The stopping rule that ended the run, if the solver itself stopped it (argmin's
    /// `MaxItersReached`, `Timeout` and `Interrupt` are recorded in the state instead).
    pub fn termination(&self) -> Option<Termination> {
        self.termination
    }

    /// Residual evaluations so far.
    pub fn evaluations(&self) -> u64 {
        self.work.as_ref().map_or(0, |w| w.nfev)
    }

    /// Jacobian evaluations so far.
    pub fn jacobian_evaluations(&self) -> u64 {
        self.work.as_ref().map_or(0, |w| w.njev)
    }

    /// The current point and its (unpadded) residuals.
    pub fn current(&self) -> Option<(&DVector<f64>, DVector<f64>)> {
        self.work
            .as_ref()
            .map(|w| (&w.x, w.r.rows(0, w.m).into_owned()))
    }

    /// The Jacobian at the current point (unpadded), if it has been evaluated there and
    /// kept (a large one is not: ask the problem), moved out of the solver (no copy of an
    /// `m × n` matrix at the end of a big fit); the solver then needs a new Jacobian before
    /// its next step. For a problem that supplied a reduced Jacobian there, its matrix `A`
    /// ([`Reduced`]).
    pub fn take_jacobian(&mut self) -> Option<DMatrix<f64>> {
        let w = self.work.as_mut().filter(|w| !w.need_jac)?;
        if let Some(a) = w.reduced.take() {
            w.need_jac = true;
            return Some(a);
        }
        if w.jac.nrows() == 0 {
            return None;
        }
        w.need_jac = true;
        let jac = std::mem::replace(&mut w.jac, DMatrix::zeros(0, 0));
        Some(if jac.nrows() == w.m {
            jac
        } else {
            jac.rows(0, w.m).into_owned()
        })
    }

    /// Stop the run (after the current step) when `stop` is requested: a signal, its flag, or
    /// its deadline; the run then ends with [`Termination::Interrupted`] or
    /// [`Termination::Timeout`]. Without one, the solver makes its own at `init` (signals
    /// from then on, and the flag of [`Self::with_interrupt`]).
    pub fn with_stop(mut self, stop: Stop) -> Self {
        self.stop = Some(stop);
        self
    }
}

impl<O> Solver<O, LmState> for LevenbergMarquardt
where
    O: Operator<Param = DVector<f64>, Output = DVector<f64>>
        + Jacobian<Param = DVector<f64>, Jacobian = DMatrix<f64>>
        + StepResiduals,
{
    fn name(&self) -> &str {
        "Levenberg-Marquardt (More trust region)"
    }

    fn init(
        &mut self,
        problem: &mut Problem<O>,
        state: LmState,
    ) -> Result<(LmState, Option<KV>), ArgminError> {
        let mut state = state;
        let x = state
            .take_param()
            .ok_or_else(|| argmin::core::ArgminError::NotInitialized {
                text: "LevenbergMarquardt needs an initial parameter vector".to_string(),
            })?;
        if self.stop.is_none() {
            self.stop = Some(Stop::new(None, None));
        }
        self.termination = None;
        let n = x.len();
        let r = problem.apply(&x)?;
        let m = r.len();
        let r = pad_vec(r, m.max(n));
        let work = Work::start(m, x.clone(), r);
        if !all_finite(&work.r) || !all_finite(&x) {
            self.termination = Some(Termination::NonFiniteStart);
        } else if n == 0 || work.fnorm == 0.0 {
            self.termination = Some(Termination::Gtol);
        }
        if self.max_evals <= 1 && self.termination.is_none() {
            self.termination = Some(Termination::MaxEvaluations);
        }
        let cost = work.cost();
        let cost = if cost.is_nan() { f64::INFINITY } else { cost };
        self.work = Some(work);
        Ok((state.param(x).cost(cost), None))
    }

    /// One argmin iteration = one trial step: the Jacobian stage when the last step was
    /// accepted, then either a polishing step or an LM trial step with its tests.
    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        state: LmState,
    ) -> Result<(LmState, Option<KV>), ArgminError> {
        let (stepbound, gtol) = (self.stepbound, self.gtol);
        let predicted_stop = self.predicted_stop && !self.polish;
        let tol = Tolerances {
            ftol: self.ftol,
            xtol: self.xtol,
            max_evals: self.max_evals,
        };
        let Some(w) = self.work.as_mut() else {
            return Err(argmin::core::ArgminError::NotInitialized {
                text: "LevenbergMarquardt::next_iter before init".to_string(),
            }
            .into());
        };
        let mut state = state;
        if w.need_jac {
            let stop;
            (state, stop) = w.refresh_jacobian(problem, state, stepbound, gtol)?;
            if stop.is_some() {
                self.termination = stop;
                return Ok((state, None));
            }
        }
        if let Some(pol) = w.polish.take() {
            let (kv, done) = w.polish_step(problem, pol, tol.max_evals)?;
            if done.is_some() {
                self.termination = done;
            }
            return Ok((state.param(w.x.clone()).cost(w.cost()), Some(kv)));
        }
        let trial = w.propose();
        if predicted_stop && w.predicts_convergence(&trial, tol.ftol) {
            self.termination = Some(Termination::Predicted);
            return Ok((state.param(w.x.clone()).cost(w.cost()), None));
        }
        let outcome = w.evaluate(problem, trial)?;
        // A stop request wins over the tests: a trial evaluation it cut short is no step.
        let stop = stop_reason(self.interrupt.as_deref(), self.stop.as_ref());
        if stop.is_some() {
            self.termination = stop;
        } else {
            match w.convergence(&outcome, tol) {
                Some(t)
                    if self.polish && t.converged() && w.nfev < tol.max_evals && w.fnorm > 0.0 =>
                {
                    // Converged: polish from the current point (its Jacobian is needed first).
                    w.polish = Some(Polish::start(t, w.fnorm));
                }
                Some(t) => self.termination = Some(t),
                None => {}
            }
        }
        let kv = argmin::kv!(
            "delta" => w.delta;
            "lambda" => w.par;
            "ratio" => outcome.ratio;
            "accepted" => outcome.accepted;
            "evals" => w.nfev;
        );
        Ok((state.param(w.x.clone()).cost(w.cost()), Some(kv)))
    }

    fn terminate(&mut self, _state: &LmState) -> TerminationStatus {
        if self.termination.is_none() {
            self.termination = stop_reason(self.interrupt.as_deref(), self.stop.as_ref());
        }
        match self.termination {
            None => TerminationStatus::NotTerminated,
            Some(Termination::Interrupted) => {
                TerminationStatus::Terminated(TerminationReason::Interrupt)
            }
            Some(Termination::Timeout) => TerminationStatus::Terminated(TerminationReason::Timeout),
            Some(t) if t.converged() => {
                TerminationStatus::Terminated(TerminationReason::SolverConverged)
            }
            Some(t) => TerminationStatus::Terminated(TerminationReason::SolverExit(
                t.describe().to_string(),
            )),
        }
    }
}

/// Why a run must stop now, if it must: the caller's flag, or the stop request.
fn stop_reason(flag: Option<&AtomicBool>, stop: Option<&Stop>) -> Option<Termination> {
    if flag.is_some_and(|f| f.load(Ordering::SeqCst)) {
        return Some(Termination::Interrupted);
    }
    stop.and_then(Stop::requested)
}
