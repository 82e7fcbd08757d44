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
//! # Ctrl-C
//! [`minimize`] turns the Executor's own handler off (argmin binds it to the first run in the
//! process: later runs could not be interrupted) and installs one process-wide handler on
//! first use: while a fit runs, Ctrl-C (or SIGTERM/SIGHUP) ends every running fit with
//! [`Termination::Interrupted`] after its current step, with a full report; when no fit is
//! running it exits the process with status 130, as the default handler would. A caller's own
//! flag can be passed in [`LmConfig::interrupt`].
//!
//! Defaults: `ftol = xtol = 1e-10`, `gtol = 1e-12`. MINPACK's driver `lmder1` uses
//! `ftol = xtol = √ε ≈ 1.5e-8`, `gtol = 0`; our defaults are tighter because a fit's standard
//! errors are only as good as its convergence, and LM converges quadratically on
//! small-residual problems so the extra digits cost one or two iterations.

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Once};
use std::time::{Duration, Instant};

use argmin::core::observers::{Observe, ObserverMode};
use argmin::core::{
    Error as ArgminError, Executor, IterState, Jacobian, Operator, Problem, Solver, State,
    TerminationReason, TerminationStatus, KV,
};
use nalgebra::{DMatrix, DVector};

use crate::Error;

/// The argmin state the solver runs on: parameters `DVector`, gradient slot `Jᵀr`,
/// Jacobian `DMatrix`, no Hessian, no residual slot (residuals live in the solver), `f64` cost.
pub type LmState = IterState<DVector<f64>, DVector<f64>, DMatrix<f64>, (), (), f64>;

const EPSMCH: f64 = f64::EPSILON;
/// Acceptance threshold on the ratio of actual to predicted reduction.
const RHO_ACCEPT: f64 = 1e-4;
const RHO_SHRINK: f64 = 0.25;
const RHO_EXPAND: f64 = 0.75;

/// Which stopping rule ended a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Termination {
    /// Relative reduction of the cost (actual and predicted) at most `ftol`, or at machine
    /// precision.
    Ftol,
    /// Relative size of the trust region at most `xtol`, or at machine precision.
    Xtol,
    /// Both `Ftol` and `Xtol` hold.
    FtolXtol,
    /// The Gauss–Newton step from the current point predicts a relative cost reduction of
    /// at most `ftol`, and the linear model predicted the last step well (see
    /// [`LevenbergMarquardt::with_predicted_stop`]).
    Predicted,
    /// Residual orthogonal to the columns of the Jacobian to within `gtol` (includes a zero
    /// residual or a zero gradient).
    Gtol,
    /// The iteration budget ran out.
    MaxIterations,
    /// The residual evaluation budget ran out.
    MaxEvaluations,
    /// The wall-clock budget ran out.
    Timeout,
    /// Ctrl-C (SIGINT), SIGTERM or SIGHUP, or the caller's interrupt flag.
    Interrupted,
    /// The residuals at the starting point are not all finite.
    NonFiniteStart,
    /// The Jacobian at an accepted point is not all finite (or not `m × n`); the run stops
    /// there.
    NonFiniteJacobian,
    /// The trust region collapsed without any other criterion holding (e.g. every trial
    /// point has non-finite residuals).
    NoProgress,
}

impl Termination {
    /// Whether the run ended at a (local) minimum according to the tolerances.
    pub fn converged(self) -> bool {
        matches!(
            self,
            Termination::Ftol
                | Termination::Xtol
                | Termination::FtolXtol
                | Termination::Gtol
                | Termination::Predicted
        )
    }

    /// One line for a human.
    pub fn describe(self) -> &'static str {
        match self {
            Termination::Ftol => "converged: relative reduction of the cost below ftol",
            Termination::Xtol => "converged: relative step size below xtol",
            Termination::FtolXtol => {
                "converged: relative cost reduction below ftol and step size below xtol"
            }
            Termination::Gtol => "converged: gradient (residual-column cosine) below gtol",
            Termination::Predicted => {
                "converged: the Gauss–Newton step predicts a relative cost reduction below ftol"
            }
            Termination::MaxIterations => "stopped: maximum number of iterations reached",
            Termination::MaxEvaluations => "stopped: maximum number of evaluations reached",
            Termination::Timeout => "stopped: time limit reached",
            Termination::Interrupted => "stopped: interrupted",
            Termination::NonFiniteStart => "failed: residuals at the starting point are not finite",
            Termination::NonFiniteJacobian => "stopped: Jacobian is not finite",
            Termination::NoProgress => {
                "stopped: no further progress possible (trust region collapsed)"
            }
        }
    }
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.describe())
    }
}

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
    interrupt_generation: u64,
    polish: bool,
    predicted_stop: bool,
    work: Option<Work>,
    termination: Option<Termination>,
}

/// Everything the iteration carries between trial steps.
#[derive(Debug, Clone)]
struct Work {
    /// Number of residuals as supplied (before padding to `max(m, n)` rows).
    m: usize,
    x: DVector<f64>,
    /// Residuals at `x`, padded with zeros to `max(m, n)`.
    r: DVector<f64>,
    fnorm: f64,
    /// Jacobian at `x` (padded), valid when `!need_jac`.
    jac: DMatrix<f64>,
    qr: Option<QrState>,
    diag: DVector<f64>,
    delta: f64,
    par: f64,
    xnorm: f64,
    need_jac: bool,
    /// Set once the LM iteration has converged: the Gauss–Newton polishing phase.
    polish: Option<Polish>,
    /// Largest |actual relative reduction| seen on trial steps whose predicted reduction was
    /// below `1e-12`: an estimate of the rounding noise in the relative cost.
    cost_noise: f64,
    /// No step accepted yet (MINPACK's `iter == 1`).
    first: bool,
    /// Ratio of actual to predicted reduction of the last accepted step.
    last_ratio: f64,
    nfev: u64,
    njev: u64,
}

/// State of the Gauss–Newton polishing phase (see [`LevenbergMarquardt::with_polish`]).
#[derive(Debug, Clone)]
struct Polish {
    /// The convergence test that started it; reported as the run's termination.
    reason: Termination,
    /// Accepted polishing steps.
    steps: u32,
    /// `‖r‖` when polishing started.
    fnorm0: f64,
    /// The iterate with the smallest Gauss–Newton step so far.
    best: Option<PolishPoint>,
    /// Iterates since `best` last improved.
    stale: u32,
}

#[derive(Debug, Clone)]
struct PolishPoint {
    x: DVector<f64>,
    r: DVector<f64>,
    fnorm: f64,
    pnorm: f64,
}

/// Most Gauss–Newton polishing steps after convergence.
const MAX_POLISH_STEPS: u32 = 30;
/// Polishing stops after this many iterates without a smaller Gauss–Newton step. Gauss–Newton
/// converges only linearly on large-residual problems (rates of 0.6–0.7 on NIST ENSO, MGH09,
/// Thurber), and not monotonically in `‖D p‖`, so a single non-contracting step is no proof
/// of the noise floor.
const POLISH_PATIENCE: u32 = 6;
/// Polishing only takes steps that predict, and cause, a relative cost change of at most this.
const POLISH_TOL: f64 = 1e-10;
/// Cap on the cost slack granted to polishing for observed rounding noise (relative).
const POLISH_MAX_NOISE: f64 = 1e-6;
/// Largest first polishing step, relative to `‖D x‖`.
const POLISH_MAX_REL_STEP: f64 = 1e-4;

/// The pivoted QR of the Jacobian at the current point, and what `lmpar` needs.
#[derive(Debug, Clone)]
struct QrState {
    /// `n × n`: `R` in the upper triangle; the strict lower triangle is workspace for `qrsolv`.
    r: DMatrix<f64>,
    /// Column `j` of `R` is column `ipvt[j]` of `J`.
    ipvt: Vec<usize>,
    /// First `n` components of `Qᵀ r`.
    qtf: DVector<f64>,
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
            interrupt_generation: 0,
            polish: false,
            predicted_stop: false,
            work: None,
            termination: None,
        }
    }

    fn check_tol(name: &str, v: f64) -> Result<f64, Error> {
        if v.is_finite() && v >= 0.0 {
            Ok(v)
        } else {
            Err(Error::Param {
                name: name.to_string(),
                message: format!(
                    "{v} is not a valid tolerance; use a finite number ≥ 0, e.g. 1e-10"
                ),
            })
        }
    }

    /// Relative cost-reduction tolerance (finite, ≥ 0).
    pub fn with_ftol(mut self, v: f64) -> Result<Self, Error> {
        self.ftol = Self::check_tol("ftol", v)?;
        Ok(self)
    }

    /// Relative step-size tolerance (finite, ≥ 0).
    pub fn with_xtol(mut self, v: f64) -> Result<Self, Error> {
        self.xtol = Self::check_tol("xtol", v)?;
        Ok(self)
    }

    /// Gradient tolerance on the cosine between `r` and the columns of `J` (finite, ≥ 0).
    pub fn with_gtol(mut self, v: f64) -> Result<Self, Error> {
        self.gtol = Self::check_tol("gtol", v)?;
        Ok(self)
    }

    /// Initial trust radius factor: `Δ₀ = factor · ‖D x₀‖` (MINPACK `factor`, default 100;
    /// must be finite and > 0).
    pub fn with_stepbound(mut self, v: f64) -> Result<Self, Error> {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::Param {
                name: "stepbound".into(),
                message: format!("{v} must be a finite number > 0, e.g. 100"),
            });
        }
        self.stepbound = v;
        Ok(self)
    }

    /// Maximum number of residual evaluations (including the one at the start; ≥ 1).
    pub fn with_max_evals(mut self, v: u64) -> Result<Self, Error> {
        if v == 0 {
            return Err(Error::Param {
                name: "max_evals".into(),
                message: "0 evaluations cannot start a fit; use at least 1".into(),
            });
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

    /// The Jacobian at the current point, if it has been evaluated there.
    pub fn current_jacobian(&self) -> Option<DMatrix<f64>> {
        self.work
            .as_ref()
            .filter(|w| !w.need_jac)
            .map(|w| w.jac.rows(0, w.m).into_owned())
    }

    fn interrupted(&self) -> bool {
        self.interrupt
            .as_ref()
            .is_some_and(|f| f.load(Ordering::SeqCst))
            || INTERRUPTS.load(Ordering::SeqCst) != self.interrupt_generation
    }
}

/// Length from which [`dot`] sums in four lanes.
const LANE_SUM_MIN: usize = 1024;

/// Euclidean norm without destructive overflow or underflow (MINPACK `enorm` in spirit):
/// the plain sum of squares when that is safely in range, a scaled sum otherwise.
fn enorm(v: &[f64]) -> f64 {
    const SMALL: f64 = 1e-150;
    const LARGE: f64 = 1e150;
    let s = dot(v, v);
    if s.is_finite() && s > SMALL * SMALL && s < LARGE * LARGE {
        return s.sqrt();
    }
    let amax = v.iter().fold(0.0f64, |a, &x| a.max(x.abs()));
    if amax == 0.0 || !amax.is_finite() {
        return if s.is_nan() { f64::NAN } else { amax };
    }
    let s: f64 = v.iter().map(|&x| (x / amax) * (x / amax)).sum();
    amax * s.sqrt()
}

/// Σ aᵢbᵢ over the common length. Long vectors (≥ [`LANE_SUM_MIN`]) are summed in four
/// interleaved partial sums (independent chains, so a 10k-row column is not bound by the
/// latency of one addition per element); shorter ones in order, as MINPACK does.
fn dot(a: &[f64], b: &[f64]) -> f64 {
    if a.len().min(b.len()) < LANE_SUM_MIN {
        return a.iter().zip(b).map(|(x, y)| x * y).sum();
    }
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// ‖J p‖ for a step p, from the pivoted QR of J (‖Q R Pᵀ p‖ = ‖R Pᵀ p‖).
fn jp_norm(qr: &QrState, step: &DVector<f64>) -> f64 {
    let n = step.len();
    let mut jp = DVector::zeros(n);
    for j in 0..n {
        let t = step[qr.ipvt[j]];
        for i in 0..=j {
            jp[i] += qr.r[(i, j)] * t;
        }
    }
    enorm(jp.as_slice())
}

fn pad_vec(v: DVector<f64>, rows: usize) -> DVector<f64> {
    if v.len() >= rows {
        v
    } else {
        v.resize_vertically(rows, 0.0)
    }
}

fn pad_mat(a: DMatrix<f64>, rows: usize) -> DMatrix<f64> {
    if a.nrows() >= rows {
        a
    } else {
        a.resize_vertically(rows, 0.0)
    }
}

/// Householder QR with column pivoting (MINPACK `qrfac` with `pivot = true`), applied to a
/// copy of `a` (`m × n`, `m ≥ n`). Returns `R` (`n × n`, upper), the pivots, the column norms
/// of `a`, and `Qᵀ f` (first `n` components). The norms of the remaining partial columns
/// that drive the pivoting are down-dated as in MINPACK and recomputed whenever the
/// down-dating has lost more than half the digits.
fn qrfac(a: &DMatrix<f64>, f: &DVector<f64>) -> (QrState, DVector<f64>) {
    let (m, n) = a.shape();
    // Column-major working copy: column k is cols[k*m .. (k+1)*m].
    let mut cols: Vec<f64> = a.as_slice().to_vec();
    let mut qtf: Vec<f64> = f.as_slice().to_vec();
    let acnorm = DVector::from_iterator(n, (0..n).map(|j| enorm(&cols[j * m..(j + 1) * m])));
    let mut rdiag: Vec<f64> = acnorm.iter().copied().collect();
    let mut wa = rdiag.clone();
    let mut ipvt: Vec<usize> = (0..n).collect();
    for j in 0..n.min(m) {
        // Pivot: the remaining column of largest partial norm goes to position j.
        let mut kmax = j;
        for k in j..n {
            if rdiag[k] > rdiag[kmax] {
                kmax = k;
            }
        }
        if kmax != j {
            for i in 0..m {
                cols.swap(j * m + i, kmax * m + i);
            }
            rdiag[kmax] = rdiag[j];
            wa[kmax] = wa[j];
            ipvt.swap(j, kmax);
        }
        let (head, tail) = cols.split_at_mut((j + 1) * m);
        let cj = &mut head[j * m + j..(j + 1) * m];
        let mut ajnorm = enorm(&*cj);
        if ajnorm != 0.0 {
            if cj[0] < 0.0 {
                ajnorm = -ajnorm;
            }
            for v in cj.iter_mut() {
                *v /= ajnorm;
            }
            cj[0] += 1.0;
            let ajj = cj[0];
            // Apply the reflector to the remaining columns and to f.
            for k in j + 1..n {
                let ck = &mut tail[(k - j - 1) * m + j..(k - j) * m];
                let sum = dot(cj, ck);
                let t = sum / ajj;
                for (c, &a) in ck.iter_mut().zip(cj.iter()) {
                    *c -= t * a;
                }
                if rdiag[k] != 0.0 {
                    let t = ck[0] / rdiag[k];
                    rdiag[k] *= (1.0 - t * t).max(0.0).sqrt();
                    if 0.05 * (rdiag[k] / wa[k]).powi(2) <= EPSMCH {
                        rdiag[k] = enorm(&ck[1..]);
                        wa[k] = rdiag[k];
                    }
                }
            }
            let fj = &mut qtf[j..m];
            let sum = dot(cj, fj);
            let t = sum / ajj;
            for (v, &a) in fj.iter_mut().zip(cj.iter()) {
                *v -= t * a;
            }
        }
        rdiag[j] = -ajnorm;
    }
    let mut r = DMatrix::zeros(n, n);
    for j in 0..n {
        for i in 0..j {
            r[(i, j)] = cols[j * m + i];
        }
        r[(j, j)] = rdiag[j];
    }
    let qtf = DVector::from_column_slice(&qtf[..n]);
    (QrState { r, ipvt, qtf }, acnorm)
}

/// MINPACK `qrsolv`: given the pivoted QR `J P = Q R` and a diagonal `d`, solve
/// `min ‖[J; D] x − [b; 0]‖` where `qtb = (Qᵀ b)[..n]`. On return the strict lower triangle of
/// `r` holds the strict upper triangle of `S` (transposed), with `Pᵀ(JᵀJ + DD)P = SᵀS`, and
/// `sdiag` the diagonal of `S`. The upper triangle of `r` is unchanged.
fn qrsolv(
    r: &mut DMatrix<f64>,
    ipvt: &[usize],
    d: &DVector<f64>,
    qtb: &DVector<f64>,
    x: &mut DVector<f64>,
    sdiag: &mut DVector<f64>,
) {
    let n = r.ncols();
    let mut wa = qtb.clone();
    for j in 0..n {
        for i in j..n {
            r[(i, j)] = r[(j, i)];
        }
        x[j] = r[(j, j)];
    }
    for j in 0..n {
        let l = ipvt[j];
        if d[l] != 0.0 {
            for k in j..n {
                sdiag[k] = 0.0;
            }
            sdiag[j] = d[l];
            let mut qtbpj = 0.0;
            for k in j..n {
                if sdiag[k] == 0.0 {
                    continue;
                }
                let (sin, cos) = if r[(k, k)].abs() < sdiag[k].abs() {
                    let cotan = r[(k, k)] / sdiag[k];
                    let sin = 0.5 / (0.25 + 0.25 * cotan * cotan).sqrt();
                    (sin, sin * cotan)
                } else {
                    let tan = sdiag[k] / r[(k, k)];
                    let cos = 0.5 / (0.25 + 0.25 * tan * tan).sqrt();
                    (cos * tan, cos)
                };
                r[(k, k)] = cos * r[(k, k)] + sin * sdiag[k];
                let temp = cos * wa[k] + sin * qtbpj;
                qtbpj = -sin * wa[k] + cos * qtbpj;
                wa[k] = temp;
                for i in k + 1..n {
                    let temp = cos * r[(i, k)] + sin * sdiag[i];
                    sdiag[i] = -sin * r[(i, k)] + cos * sdiag[i];
                    r[(i, k)] = temp;
                }
            }
        }
        sdiag[j] = r[(j, j)];
        r[(j, j)] = x[j];
    }
    // Solve S z = wa; a singular S gives the least-squares solution with trailing zeros.
    let mut nsing = n;
    for j in 0..n {
        if sdiag[j] == 0.0 && nsing == n {
            nsing = j;
        }
        if nsing < n {
            wa[j] = 0.0;
        }
    }
    for j in (0..nsing).rev() {
        let mut sum = 0.0;
        for i in j + 1..nsing {
            sum += r[(i, j)] * wa[i];
        }
        wa[j] = (wa[j] - sum) / sdiag[j];
    }
    for j in 0..n {
        x[ipvt[j]] = wa[j];
    }
}

/// MINPACK `lmpar`: find `λ ≥ 0` and the step `x` (the negative of the LM step) with
/// `(JᵀJ + λDD) x = Jᵀ f`, such that either `λ = 0` and `‖D x‖ ≤ 1.1 Δ`, or
/// `|‖D x‖ − Δ| ≤ 0.1 Δ`. `par` is the initial estimate on entry and the result on exit.
fn lmpar(qr: &mut QrState, diag: &DVector<f64>, delta: f64, par: &mut f64, x: &mut DVector<f64>) {
    let n = qr.r.ncols();
    let dwarf = f64::MIN_POSITIVE;
    let r = &mut qr.r;
    let ipvt = &qr.ipvt;
    let qtb = &qr.qtf;
    let mut sdiag = DVector::zeros(n);

    // Gauss–Newton direction (minimum-length on the non-singular part if R is singular).
    let mut wa1 = qtb.clone();
    let mut nsing = n;
    for j in 0..n {
        if r[(j, j)] == 0.0 && nsing == n {
            nsing = j;
        }
        if nsing < n {
            wa1[j] = 0.0;
        }
    }
    for j in (0..nsing).rev() {
        wa1[j] /= r[(j, j)];
        let t = wa1[j];
        for i in 0..j {
            wa1[i] -= r[(i, j)] * t;
        }
    }
    for j in 0..n {
        x[ipvt[j]] = wa1[j];
    }

    let mut wa2 = diag.component_mul(x);
    let mut dxnorm = enorm(wa2.as_slice());
    let mut fp = dxnorm - delta;
    if fp <= 0.1 * delta {
        *par = 0.0;
        return;
    }

    // Lower bound parl (only when R is non-singular: then the Newton step is defined).
    let mut parl = 0.0;
    if nsing >= n {
        for j in 0..n {
            let l = ipvt[j];
            wa1[j] = diag[l] * (wa2[l] / dxnorm);
        }
        for j in 0..n {
            let mut sum = 0.0;
            for i in 0..j {
                sum += r[(i, j)] * wa1[i];
            }
            wa1[j] = (wa1[j] - sum) / r[(j, j)];
        }
        let t = enorm(wa1.as_slice());
        parl = ((fp / delta) / t) / t;
        if !parl.is_finite() {
            parl = 0.0;
        }
    }

    // Upper bound paru.
    for j in 0..n {
        let mut sum = 0.0;
        for i in 0..=j {
            sum += r[(i, j)] * qtb[i];
        }
        wa1[j] = sum / diag[ipvt[j]];
    }
    let gnorm = enorm(wa1.as_slice());
    let mut paru = gnorm / delta;
    if paru == 0.0 {
        paru = dwarf / delta.min(0.1);
    }

    *par = par.max(parl).min(paru);
    if *par == 0.0 {
        *par = gnorm / dxnorm;
    }

    let mut iter = 0;
    loop {
        iter += 1;
        if *par == 0.0 {
            *par = dwarf.max(0.001 * paru);
        }
        let s = par.sqrt();
        let d = diag * s;
        qrsolv(r, ipvt, &d, qtb, x, &mut sdiag);
        wa2 = diag.component_mul(x);
        dxnorm = enorm(wa2.as_slice());
        let temp = fp;
        fp = dxnorm - delta;
        if fp.abs() <= 0.1 * delta || (parl == 0.0 && fp <= temp && temp < 0.0) || iter == 10 {
            break;
        }
        // Newton correction.
        for j in 0..n {
            let l = ipvt[j];
            wa1[j] = diag[l] * (wa2[l] / dxnorm);
        }
        for j in 0..n {
            wa1[j] /= sdiag[j];
            let t = wa1[j];
            for i in j + 1..n {
                wa1[i] -= r[(i, j)] * t;
            }
        }
        let t = enorm(wa1.as_slice());
        let parc = ((fp / delta) / t) / t;
        if fp > 0.0 {
            parl = parl.max(*par);
        }
        if fp < 0.0 {
            paru = paru.min(*par);
        }
        *par = parl.max(*par + parc);
        if !par.is_finite() {
            *par = paru;
        }
    }
}

fn all_finite(v: &DVector<f64>) -> bool {
    v.iter().all(|x| x.is_finite())
}

impl<O> Solver<O, LmState> for LevenbergMarquardt
where
    O: Operator<Param = DVector<f64>, Output = DVector<f64>>
        + Jacobian<Param = DVector<f64>, Jacobian = DMatrix<f64>>,
{
    fn name(&self) -> &str {
        "Levenberg-Marquardt (More trust region)"
    }

    fn init(
        &mut self,
        problem: &mut Problem<O>,
        mut state: LmState,
    ) -> Result<(LmState, Option<KV>), ArgminError> {
        let x = state
            .take_param()
            .ok_or_else(|| argmin::core::ArgminError::NotInitialized {
                text: "LevenbergMarquardt needs an initial parameter vector".to_string(),
            })?;
        self.interrupt_generation = INTERRUPTS.load(Ordering::SeqCst);
        self.termination = None;
        let n = x.len();
        let r = problem.apply(&x)?;
        let m = r.len();
        let rows = m.max(n);
        let r = pad_vec(r, rows);
        let fnorm = enorm(r.as_slice());
        let cost = 0.5 * fnorm * fnorm;
        if !all_finite(&r) || !all_finite(&x) {
            self.termination = Some(Termination::NonFiniteStart);
        } else if n == 0 || fnorm == 0.0 {
            self.termination = Some(Termination::Gtol);
        }
        if self.max_evals <= 1 && self.termination.is_none() {
            self.termination = Some(Termination::MaxEvaluations);
        }
        self.work = Some(Work {
            m,
            x: x.clone(),
            r,
            fnorm,
            jac: DMatrix::zeros(rows, n),
            qr: None,
            diag: DVector::from_element(n, 1.0),
            delta: 0.0,
            par: 0.0,
            xnorm: 0.0,
            need_jac: true,
            polish: None,
            cost_noise: 0.0,
            first: true,
            last_ratio: 0.0,
            nfev: 1,
            njev: 0,
        });
        let cost = if cost.is_nan() { f64::INFINITY } else { cost };
        Ok((state.param(x).cost(cost), None))
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<O>,
        mut state: LmState,
    ) -> Result<(LmState, Option<KV>), ArgminError> {
        let (ftol, xtol, gtol, stepbound, max_evals) = (
            self.ftol,
            self.xtol,
            self.gtol,
            self.stepbound,
            self.max_evals,
        );
        let Some(w) = self.work.as_mut() else {
            return Err(argmin::core::ArgminError::NotInitialized {
                text: "LevenbergMarquardt::next_iter before init".to_string(),
            }
            .into());
        };
        let n = w.x.len();
        let rows = w.r.len();

        if w.need_jac {
            let jac = problem.jacobian(&w.x)?;
            w.njev += 1;
            if jac.shape() != (w.m, n) || jac.iter().any(|v| !v.is_finite()) {
                self.termination = Some(Termination::NonFiniteJacobian);
                return Ok((state, None));
            }
            w.jac = pad_mat(jac, rows);
            let (qr, acnorm) = qrfac(&w.jac, &w.r);
            if w.first {
                for j in 0..n {
                    w.diag[j] = if acnorm[j] == 0.0 { 1.0 } else { acnorm[j] };
                }
                w.xnorm = enorm(w.diag.component_mul(&w.x).as_slice());
                w.delta = stepbound * w.xnorm;
                if w.delta == 0.0 {
                    w.delta = stepbound;
                }
            }
            // Scaled gradient norm: the largest cosine between r and a column of J.
            let mut gnorm: f64 = 0.0;
            if w.fnorm != 0.0 {
                for j in 0..n {
                    let l = qr.ipvt[j];
                    if acnorm[l] != 0.0 {
                        let mut sum = 0.0;
                        for i in 0..=j {
                            sum += qr.r[(i, j)] * (qr.qtf[i] / w.fnorm);
                        }
                        gnorm = gnorm.max((sum / acnorm[l]).abs());
                    }
                }
            }
            for j in 0..n {
                w.diag[j] = w.diag[j].max(acnorm[j]);
            }
            w.qr = Some(qr);
            w.need_jac = false;
            let grad = w.jac.tr_mul(&w.r);
            // The state's Jacobian: the previous one's storage is reused (a fresh matrix of
            // this size is fresh memory from the system on every iteration).
            let mut state_jac = state
                .take_jacobian()
                .filter(|j| j.shape() == (w.m, n))
                .unwrap_or_else(|| DMatrix::zeros(w.m, n));
            state_jac.copy_from(&w.jac.rows(0, w.m));
            state = state.gradient(grad).jacobian(state_jac);
            // (While polishing, the polishing rules decide; they also end at a zero step.)
            if w.polish.is_none() && (gnorm <= gtol || gnorm <= EPSMCH) {
                self.termination = Some(Termination::Gtol);
                return Ok((state, None));
            }
        }

        if let Some(mut pol) = w.polish.take() {
            // Gauss–Newton polishing step (λ = 0, minimum-length on a singular R).
            let qr = w.qr.as_mut().expect("QR present after Jacobian");
            let mut step = DVector::zeros(n);
            let mut par = 0.0;
            lmpar(qr, &w.diag, f64::INFINITY, &mut par, &mut step);
            let step = -step;
            let pnorm = enorm(w.diag.component_mul(&step).as_slice());
            // Predicted relative reduction of the undamped step, ‖J p‖²/‖r‖².
            let prered = (jp_norm(qr, &step) / w.fnorm).powi(2);
            // The iterate with the smallest Gauss–Newton step is the one closest to
            // stationarity as far as the (noise-free) linear model can tell.
            if pol.best.as_ref().is_none_or(|b| pnorm < b.pnorm) {
                pol.best = Some(PolishPoint {
                    x: w.x.clone(),
                    r: w.r.clone(),
                    fnorm: w.fnorm,
                    pnorm,
                });
                pol.stale = 0;
            } else {
                pol.stale += 1;
            }
            let mut finish = pol.stale >= POLISH_PATIENCE
                || pol.steps >= MAX_POLISH_STEPS
                || pnorm <= EPSMCH * w.xnorm
                || w.fnorm == 0.0
                || w.nfev >= max_evals
                || prered > POLISH_TOL
                || (pol.steps == 0 && pnorm > POLISH_MAX_REL_STEP * w.xnorm);
            let mut accepted = false;
            if !finish {
                let trial = &w.x + &step;
                let r1 = pad_vec(problem.apply(&trial)?, rows);
                w.nfev += 1;
                let fnorm1 = if all_finite(&r1) && r1.len() == rows {
                    enorm(r1.as_slice())
                } else {
                    f64::INFINITY
                };
                let slack = POLISH_TOL.max((4.0 * w.cost_noise).min(POLISH_MAX_NOISE));
                if fnorm1 * fnorm1 <= pol.fnorm0 * pol.fnorm0 * (1.0 + slack) {
                    w.x = trial;
                    w.r = r1;
                    w.fnorm = fnorm1;
                    w.xnorm = enorm(w.diag.component_mul(&w.x).as_slice());
                    w.need_jac = true;
                    pol.steps += 1;
                    accepted = true;
                } else {
                    finish = true;
                }
            }
            if finish {
                // End at the best iterate (re-evaluating its Jacobian if it is not the
                // current point).
                if let Some(b) = pol.best.take() {
                    if b.x != w.x {
                        w.x = b.x;
                        w.r = b.r;
                        w.fnorm = b.fnorm;
                        w.xnorm = enorm(w.diag.component_mul(&w.x).as_slice());
                        w.need_jac = true;
                    }
                }
                self.termination = Some(pol.reason);
            }
            let kv = argmin::kv!(
                "delta" => w.delta;
                "lambda" => 0.0;
                "polish" => pol.steps;
                "accepted" => accepted;
                "evals" => w.nfev;
            );
            w.polish = Some(pol);
            let cost = 0.5 * w.fnorm * w.fnorm;
            return Ok((state.param(w.x.clone()).cost(cost), Some(kv)));
        }

        // One trial step.
        let qr = w.qr.as_mut().expect("QR present after Jacobian");
        let mut step = DVector::zeros(n);
        lmpar(qr, &w.diag, w.delta, &mut w.par, &mut step);
        let step = -step;
        let trial = &w.x + &step;
        let pnorm = enorm(w.diag.component_mul(&step).as_slice());
        // Predicted reduction from the linear model: ‖J p‖² and the λ‖Dp‖² term.
        let temp1 = jp_norm(qr, &step) / w.fnorm;
        if self.predicted_stop
            && !self.polish
            && !w.first
            && w.par == 0.0
            && (w.last_ratio - 1.0).abs() <= 0.25
            && temp1 * temp1 <= ftol
        {
            self.termination = Some(Termination::Predicted);
            let cost = 0.5 * w.fnorm * w.fnorm;
            return Ok((state.param(w.x.clone()).cost(cost), None));
        }
        if w.first {
            w.delta = w.delta.min(pnorm);
        }
        let r1 = problem.apply(&trial)?;
        w.nfev += 1;
        let r1 = pad_vec(r1, rows);
        let mut fnorm1 = enorm(r1.as_slice());
        if !all_finite(&r1) || r1.len() != rows {
            fnorm1 = f64::INFINITY;
        }
        // Actual relative reduction 1 − (‖r₁‖/‖r‖)², computed as −Σ(r₁−r)(r₁+r)/‖r‖² to avoid
        // the cancellation of two nearly equal squared norms near convergence.
        let actred = if 0.1 * fnorm1 < w.fnorm {
            let inv = 1.0 / w.fnorm;
            let s: f64 = r1
                .iter()
                .zip(w.r.iter())
                .map(|(&a, &b)| ((a - b) * inv) * ((a + b) * inv))
                .sum();
            -s
        } else {
            -1.0
        };
        let temp2 = w.par.sqrt() * pnorm / w.fnorm;
        let prered = temp1 * temp1 + temp2 * temp2 / 0.5;
        let dirder = -(temp1 * temp1 + temp2 * temp2);
        let ratio = if prered != 0.0 { actred / prered } else { 0.0 };

        if ratio <= RHO_SHRINK {
            let mut temp = if actred >= 0.0 {
                0.5
            } else {
                0.5 * dirder / (dirder + 0.5 * actred)
            };
            if 0.1 * fnorm1 >= w.fnorm || temp.is_nan() || temp < 0.1 {
                temp = 0.1;
            }
            w.delta = temp * w.delta.min(pnorm / 0.1);
            w.par /= temp;
        } else if w.par == 0.0 || ratio >= RHO_EXPAND {
            w.delta = pnorm / 0.5;
            w.par *= 0.5;
        }

        if prered <= 1e-12 && fnorm1.is_finite() {
            w.cost_noise = w.cost_noise.max(actred.abs());
        }
        let accepted = ratio >= RHO_ACCEPT;
        if accepted {
            w.x = trial;
            w.r = r1;
            w.fnorm = fnorm1;
            w.xnorm = enorm(w.diag.component_mul(&w.x).as_slice());
            w.need_jac = true;
            w.first = false;
            w.last_ratio = ratio;
        }

        // Convergence tests (MINPACK order).
        let f_ok = actred.abs() <= ftol && prered <= ftol && 0.5 * ratio <= 1.0;
        let x_ok = w.delta <= xtol * w.xnorm;
        let term = if f_ok && x_ok {
            Some(Termination::FtolXtol)
        } else if f_ok {
            Some(Termination::Ftol)
        } else if x_ok {
            Some(Termination::Xtol)
        } else if w.nfev >= max_evals {
            Some(Termination::MaxEvaluations)
        } else if actred.abs() <= EPSMCH && prered <= EPSMCH && 0.5 * ratio <= 1.0 {
            Some(Termination::Ftol)
        } else if w.delta <= EPSMCH * w.xnorm {
            Some(Termination::Xtol)
        } else if w.delta.is_nan() || w.delta <= f64::MIN_POSITIVE {
            Some(Termination::NoProgress)
        } else {
            None
        };
        // A trust region that collapsed onto non-finite trial points is not convergence.
        let term = match term {
            Some(Termination::Xtol) if fnorm1.is_infinite() => Some(Termination::NoProgress),
            t => t,
        };
        match term {
            Some(t) if self.polish && t.converged() && w.nfev < max_evals && w.fnorm > 0.0 => {
                // Converged: polish from the current point (its Jacobian is needed first).
                w.polish = Some(Polish {
                    reason: t,
                    steps: 0,
                    fnorm0: w.fnorm,
                    best: None,
                    stale: 0,
                });
            }
            Some(t) => self.termination = Some(t),
            None => {}
        }

        let kv = argmin::kv!(
            "delta" => w.delta;
            "lambda" => w.par;
            "ratio" => ratio;
            "accepted" => accepted;
            "evals" => w.nfev;
        );
        let cost = 0.5 * w.fnorm * w.fnorm;
        Ok((state.param(w.x.clone()).cost(cost), Some(kv)))
    }

    fn terminate(&mut self, _state: &LmState) -> TerminationStatus {
        if self.termination.is_none() && self.interrupted() {
            self.termination = Some(Termination::Interrupted);
        }
        match self.termination {
            None => TerminationStatus::NotTerminated,
            Some(Termination::Interrupted) => {
                TerminationStatus::Terminated(TerminationReason::Interrupt)
            }
            Some(t) if t.converged() => {
                TerminationStatus::Terminated(TerminationReason::SolverConverged)
            }
            Some(t) => TerminationStatus::Terminated(TerminationReason::SolverExit(
                t.describe().to_string(),
            )),
        }
    }
}

// ---------------------------------------------------------------------------------------
// Ctrl-C: one process-wide handler, installed on first use.
//
// argmin's Executor installs its own handler bound to the flag of the *first* run in the
// process (later runs cannot be interrupted, and Ctrl-C is swallowed between runs). Instead
// `minimize` turns the Executor's handler off and installs one that bumps a global
// generation counter while a fit is running (every running solver sees the change) and,
// when no fit is running, exits the process with status 130 as an unhandled SIGINT would.

static INTERRUPTS: AtomicU64 = AtomicU64::new(0);
static ACTIVE_RUNS: AtomicUsize = AtomicUsize::new(0);
static HANDLER: Once = Once::new();

fn install_interrupt_handler() {
    HANDLER.call_once(|| {
        // If another handler is already installed (e.g. by a direct argmin Executor run),
        // Ctrl-C keeps working through that one; nothing else to do.
        let _ = ctrlc::set_handler(|| {
            if ACTIVE_RUNS.load(Ordering::SeqCst) == 0 {
                std::process::exit(130);
            }
            INTERRUPTS.fetch_add(1, Ordering::SeqCst);
        });
    });
}

struct ActiveRun;
impl ActiveRun {
    fn start() -> Self {
        ACTIVE_RUNS.fetch_add(1, Ordering::SeqCst);
        ActiveRun
    }
}
impl Drop for ActiveRun {
    fn drop(&mut self) {
        ACTIVE_RUNS.fetch_sub(1, Ordering::SeqCst);
    }
}

// ---------------------------------------------------------------------------------------
// The fit layer's view of a problem, and the driver.

/// A least-squares problem in the form the fit layer supplies. Residuals are already
/// weighted (`r̃ᵢ = √wᵢ rᵢ`), so `cost = ½ Σ r̃ᵢ²`.
pub trait LeastSquaresProblem {
    /// Weighted residuals at `x`. May contain NaN or ±∞ (e.g. outside the model's domain):
    /// such a trial point is rejected and the trust region shrinks.
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64>;
    /// Jacobian `∂r̃ᵢ/∂xⱼ` (`m × n`), analytic; see [`finite_difference_jacobian`] otherwise.
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64>;
}

impl<P: LeastSquaresProblem + ?Sized> LeastSquaresProblem for &P {
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
        (**self).residuals(x)
    }
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        (**self).jacobian(x)
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
    /// Wall-clock limit. Default none.
    pub timeout: Option<Duration>,
    /// Show a progress line on the terminal (stderr, via indicatif). Default false.
    pub progress: bool,
    /// Stop when this flag becomes true (in addition to Ctrl-C). Default none.
    pub interrupt: Option<Arc<AtomicBool>>,
    /// Install goniofit's process-wide Ctrl-C/SIGTERM/SIGHUP handler (see "Ctrl-C" in the
    /// module docs). Default true. False for a host that owns its signals, such as the
    /// Python interpreter: its own handler stays in place and the host sets `interrupt`.
    pub install_signal_handler: bool,
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
            install_signal_handler: true,
            polish: false,
            predicted_stop: false,
        }
    }
}

/// The result of a run: never an error for non-convergence.
#[derive(Debug, Clone)]
pub struct LmReport {
    /// Final (best) parameters.
    pub x: DVector<f64>,
    /// Weighted residuals at `x`.
    pub residuals: DVector<f64>,
    /// Jacobian at `x` (evaluated once more at the end if the last step was accepted).
    pub jacobian: DMatrix<f64>,
    /// `½ ‖residuals‖²`.
    pub cost: f64,
    pub termination: Termination,
    /// argmin iterations = trial steps.
    pub iterations: u64,
    /// Residual evaluations (including the start).
    pub evaluations: u64,
    pub jacobian_evaluations: u64,
    pub seconds: f64,
}

/// Terminal progress line as an argmin observer.
struct ProgressObserver {
    bar: indicatif::ProgressBar,
}

impl ProgressObserver {
    fn new() -> Self {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.set_style(
            indicatif::ProgressStyle::with_template("{spinner} LM {elapsed} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
        );
        ProgressObserver { bar }
    }
}

impl Observe<LmState> for ProgressObserver {
    fn observe_iter(&mut self, state: &LmState, kv: &KV) -> Result<(), ArgminError> {
        let get = |k: &str| kv.get(k).and_then(|v| v.get_float()).unwrap_or(f64::NAN);
        self.bar.set_message(format!(
            "iter {:>5}  cost {:.9e}  Δ {:.3e}  λ {:.3e}",
            state.get_iter(),
            state.get_best_cost(),
            get("delta"),
            get("lambda"),
        ));
        self.bar.tick();
        Ok(())
    }

    fn observe_final(&mut self, _state: &LmState) -> Result<(), ArgminError> {
        self.bar.finish_and_clear();
        Ok(())
    }
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
    if config.install_signal_handler {
        install_interrupt_handler();
    }
    let _active = ActiveRun::start();
    let tol = |v: f64| if v.is_finite() && v >= 0.0 { v } else { 0.0 };
    let mut solver = LevenbergMarquardt {
        ftol: tol(config.ftol),
        xtol: tol(config.xtol),
        gtol: tol(config.gtol),
        max_evals: config.max_evals.max(1),
        polish: config.polish,
        predicted_stop: config.predicted_stop,
        ..LevenbergMarquardt::new()
    };
    if let Some(flag) = &config.interrupt {
        solver = solver.with_interrupt(flag.clone());
    }
    let mut exec = Executor::new(ArgminAdapter(problem), solver)
        .configure(|s| s.param(x0.clone()).max_iters(config.max_iters))
        .ctrlc(false);
    if let Some(t) = config.timeout {
        exec = exec.timeout(t);
    }
    if config.progress {
        exec = exec.add_observer(ProgressObserver::new(), ObserverMode::Always);
    }
    let result = exec.run();
    let fallback = |termination| {
        let residuals = problem.residuals(&x0);
        let jacobian = problem.jacobian(&x0);
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
    };
    let Ok(result) = result else {
        // Unreachable with this adapter (it never fails) and the Executor's handler off.
        return fallback(Termination::NoProgress);
    };
    let state = &result.state;
    let solver = &result.solver;
    let termination = solver
        .termination
        .unwrap_or(match state.get_termination_reason() {
            Some(TerminationReason::MaxItersReached) => Termination::MaxIterations,
            Some(TerminationReason::Timeout) => Termination::Timeout,
            Some(TerminationReason::Interrupt) => Termination::Interrupted,
            _ => Termination::NoProgress,
        });
    let Some((x, residuals)) = solver.current() else {
        return fallback(termination);
    };
    let x = x.clone();
    let mut jacobian_evaluations = solver.jacobian_evaluations();
    let jacobian = match solver.current_jacobian() {
        Some(j) => j,
        None => {
            jacobian_evaluations += 1;
            problem.jacobian(&x)
        }
    };
    LmReport {
        cost: 0.5 * enorm(residuals.as_slice()).powi(2),
        x,
        residuals,
        jacobian,
        termination,
        iterations: state.get_iter(),
        evaluations: solver.evaluations(),
        jacobian_evaluations,
        seconds: start.elapsed().as_secs_f64(),
    }
}

/// Finite-difference Jacobian of `f` at `x`, for models without an analytic one.
///
/// * With `r0 = Some(f(x))`: forward differences (`n` evaluations), step
///   `hⱼ = √ε · |xⱼ|` (`√ε` when `xⱼ = 0`), as MINPACK `fdjac2`; error `O(√ε)` relative.
/// * With `r0 = None`: central differences (`2n` evaluations), step `hⱼ = ε^{1/3} · max(|xⱼ|, 1e-8)`
///   … capped below by `ε^{1/3}·1e-8`; error `O(ε^{2/3})` relative.
///
/// In both cases the step is rounded so that `xⱼ + hⱼ` is exactly representable.
pub fn finite_difference_jacobian<F: Fn(&DVector<f64>) -> DVector<f64>>(
    f: F,
    x: &DVector<f64>,
    r0: Option<&DVector<f64>>,
) -> DMatrix<f64> {
    let n = x.len();
    let mut xt = x.clone();
    match r0 {
        Some(r0) => {
            let mut jac = DMatrix::zeros(r0.len(), n);
            for j in 0..n {
                let xj = x[j];
                let mut h = EPSMCH.sqrt() * xj.abs();
                if h == 0.0 {
                    h = EPSMCH.sqrt();
                }
                xt[j] = xj + h;
                let h = xt[j] - xj;
                let r1 = f(&xt);
                xt[j] = xj;
                for i in 0..r0.len().min(r1.len()) {
                    jac[(i, j)] = (r1[i] - r0[i]) / h;
                }
            }
            jac
        }
        None => {
            let mut jac: Option<DMatrix<f64>> = None;
            for j in 0..n {
                let xj = x[j];
                let h = EPSMCH.cbrt() * xj.abs().max(1e-8);
                xt[j] = xj + h;
                let hp = xt[j] - xj;
                let rp = f(&xt);
                xt[j] = xj - h;
                let hm = xj - xt[j];
                let rm = f(&xt);
                xt[j] = xj;
                let jac = jac.get_or_insert_with(|| DMatrix::zeros(rp.len(), n));
                for i in 0..jac.nrows().min(rp.len()).min(rm.len()) {
                    jac[(i, j)] = (rp[i] - rm[i]) / (hp + hm);
                }
            }
            jac.unwrap_or_else(|| DMatrix::zeros(f(x).len(), 0))
        }
    }
}

// ---------------------------------------------------------------------------------------
// Positivity and fixed parameters.

/// A [`LeastSquaresProblem`] over the *free* parameters of an inner problem: parameters with
/// `fixed[j] = Some(v)` are held at `v`; free parameters with `log_mask[j] = true` are
/// optimised as `zⱼ = ln xⱼ` (so `xⱼ = exp zⱼ > 0` always). The Jacobian follows by the chain
/// rule, `∂r/∂zⱼ = xⱼ ∂r/∂xⱼ`. [`Transformed::to_full`] maps a solution back and
/// [`Transformed::covariance_to_full`] maps its covariance by the delta method
/// (`C_x = G C_z Gᵀ`, `G = ∂x/∂z`, zero rows and columns for fixed parameters) — first order,
/// so for log parameters with large relative errors the interval on `ln x` is the better one.
#[derive(Debug, Clone)]
pub struct Transformed<P> {
    inner: P,
    log_mask: Vec<bool>,
    fixed: Vec<Option<f64>>,
    /// Indices (into the full vector) of the free parameters, in order.
    free: Vec<usize>,
}

impl<P> Transformed<P> {
    /// `log_mask` and `fixed` have one entry per parameter of `inner`. Fixed values must be
    /// finite, and positive where `log_mask` is set.
    pub fn new(inner: P, log_mask: Vec<bool>, fixed: Vec<Option<f64>>) -> Result<Self, Error> {
        if log_mask.len() != fixed.len() {
            return Err(Error::Usage(format!(
                "Transformed: log_mask has {} entries but fixed has {}; give one per parameter",
                log_mask.len(),
                fixed.len()
            )));
        }
        for (j, f) in fixed.iter().enumerate() {
            if let Some(v) = f {
                if !v.is_finite() || (log_mask[j] && *v <= 0.0) {
                    return Err(Error::Param {
                        name: format!("#{j}"),
                        message: format!(
                            "fixed value {v} is not allowed (must be finite{})",
                            if log_mask[j] { " and > 0" } else { "" }
                        ),
                    });
                }
            }
        }
        let free = (0..fixed.len()).filter(|&j| fixed[j].is_none()).collect();
        Ok(Transformed {
            inner,
            log_mask,
            fixed,
            free,
        })
    }

    /// The wrapped problem.
    pub fn inner(&self) -> &P {
        &self.inner
    }

    /// Number of parameters of the inner problem.
    pub fn n_full(&self) -> usize {
        self.fixed.len()
    }

    /// Number of free parameters (the dimension the solver sees).
    pub fn n_free(&self) -> usize {
        self.free.len()
    }

    /// Indices of the free parameters in the full vector.
    pub fn free_indices(&self) -> &[usize] {
        &self.free
    }

    /// Free (log-)coordinates of a full parameter vector; fixed entries of `x` are ignored.
    /// Fails when a log parameter is not positive.
    pub fn to_free(&self, x: &DVector<f64>) -> Result<DVector<f64>, Error> {
        if x.len() != self.n_full() {
            return Err(Error::Usage(format!(
                "expected {} parameters, got {}",
                self.n_full(),
                x.len()
            )));
        }
        let mut z = DVector::zeros(self.free.len());
        for (k, &j) in self.free.iter().enumerate() {
            z[k] = if self.log_mask[j] {
                if x[j].is_nan() || x[j] <= 0.0 {
                    return Err(Error::Param {
                        name: format!("#{j}"),
                        message: format!("{} must be > 0 (it is fitted on a log scale)", x[j]),
                    });
                }
                x[j].ln()
            } else {
                x[j]
            };
        }
        Ok(z)
    }

    /// The full parameter vector for free coordinates `z`.
    pub fn to_full(&self, z: &DVector<f64>) -> DVector<f64> {
        let mut x = DVector::zeros(self.n_full());
        for (j, f) in self.fixed.iter().enumerate() {
            if let Some(v) = f {
                x[j] = *v;
            }
        }
        for (k, &j) in self.free.iter().enumerate() {
            x[j] = if self.log_mask[j] { z[k].exp() } else { z[k] };
        }
        x
    }

    /// `G = ∂x/∂z` (`n_full × n_free`).
    pub fn dx_dz(&self, z: &DVector<f64>) -> DMatrix<f64> {
        let mut g = DMatrix::zeros(self.n_full(), self.free.len());
        for (k, &j) in self.free.iter().enumerate() {
            g[(j, k)] = if self.log_mask[j] { z[k].exp() } else { 1.0 };
        }
        g
    }

    /// Delta-method covariance of the full parameters from the covariance of `z`.
    pub fn covariance_to_full(&self, z: &DVector<f64>, cov_z: &DMatrix<f64>) -> DMatrix<f64> {
        let g = self.dx_dz(z);
        &g * cov_z * g.transpose()
    }

    /// Jacobian of the full problem mapped to the free coordinates.
    pub fn jacobian_to_free(&self, z: &DVector<f64>, jac_full: &DMatrix<f64>) -> DMatrix<f64> {
        let mut jz = DMatrix::zeros(jac_full.nrows(), self.free.len());
        for (k, &j) in self.free.iter().enumerate() {
            let s = if self.log_mask[j] { z[k].exp() } else { 1.0 };
            jz.set_column(k, &(jac_full.column(j) * s));
        }
        jz
    }
}

impl<P: LeastSquaresProblem> LeastSquaresProblem for Transformed<P> {
    fn residuals(&self, z: &DVector<f64>) -> DVector<f64> {
        self.inner.residuals(&self.to_full(z))
    }

    fn jacobian(&self, z: &DVector<f64>) -> DMatrix<f64> {
        let jac = self.inner.jacobian(&self.to_full(z));
        self.jacobian_to_free(z, &jac)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;
    use std::cell::Cell;

    /// A problem from closures: residuals and Jacobian.
    struct Closure<R, J> {
        r: R,
        j: J,
    }
    impl<R, J> LeastSquaresProblem for Closure<R, J>
    where
        R: Fn(&DVector<f64>) -> DVector<f64>,
        J: Fn(&DVector<f64>) -> DMatrix<f64>,
    {
        fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
            (self.r)(x)
        }
        fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
            (self.j)(x)
        }
    }

    fn v(xs: &[f64]) -> DVector<f64> {
        DVector::from_column_slice(xs)
    }

    fn rosen_r(x: &DVector<f64>) -> DVector<f64> {
        v(&[10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]])
    }

    fn rosen_j(x: &DVector<f64>) -> DMatrix<f64> {
        DMatrix::from_row_slice(2, 2, &[-20.0 * x[0], 10.0, -1.0, 0.0])
    }

    /// Rosenbrock as least squares: r = (10(x₂ − x₁²), 1 − x₁), minimum 0 at (1, 1).
    fn rosenbrock() -> impl LeastSquaresProblem {
        Closure {
            r: rosen_r,
            j: rosen_j,
        }
    }

    fn decay_data() -> (Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..20).map(|i| i as f64 * 0.25).collect();
        let y = t
            .iter()
            .enumerate()
            .map(|(i, &t)| 3.0 * (-0.7 * t).exp() + 0.01 * ((i * 7 % 5) as f64 - 2.0))
            .collect();
        (t, y)
    }

    /// y = a·exp(−b t) + deterministic pseudo-noise: a non-zero-residual problem.
    fn decay() -> impl LeastSquaresProblem {
        let (t, y) = decay_data();
        let t2 = t.clone();
        Closure {
            r: move |x: &DVector<f64>| {
                DVector::from_iterator(
                    t.len(),
                    t.iter()
                        .zip(&y)
                        .map(|(&t, &y)| x[0] * (-x[1] * t).exp() - y),
                )
            },
            j: move |x: &DVector<f64>| {
                let mut j = DMatrix::zeros(t2.len(), 2);
                for (i, &t) in t2.iter().enumerate() {
                    let e = (-x[1] * t).exp();
                    j[(i, 0)] = e;
                    j[(i, 1)] = -x[0] * t * e;
                }
                j
            },
        }
    }

    fn cfg(ftol: f64, xtol: f64, gtol: f64) -> LmConfig {
        LmConfig {
            ftol,
            xtol,
            gtol,
            max_iters: 10_000,
            max_evals: 10_000,
            ..LmConfig::default()
        }
    }

    #[test]
    fn solves_rosenbrock_with_default_config() {
        let rep = minimize(&rosenbrock(), v(&[-1.2, 1.0]), &LmConfig::default());
        assert!(rep.termination.converged(), "{:?}", rep.termination);
        assert_relative_eq!(rep.x[0], 1.0, epsilon = 1e-10);
        assert_relative_eq!(rep.x[1], 1.0, epsilon = 1e-10);
        assert!(rep.cost < 1e-20);
        assert_eq!(rep.jacobian.shape(), (2, 2));
        assert!(rep.evaluations >= rep.jacobian_evaluations);
    }

    #[test]
    fn polishing_reaches_the_noise_floor_and_keeps_the_reason() {
        let reference = minimize(
            &decay(),
            v(&[1.0, 0.1]),
            &LmConfig {
                polish: true,
                ..cfg(1e-15, 1e-15, 0.0)
            },
        );
        let plain = minimize(&decay(), v(&[1.0, 0.1]), &cfg(1e-4, 0.0, 0.0));
        let polished = minimize(
            &decay(),
            v(&[1.0, 0.1]),
            &LmConfig {
                polish: true,
                ..cfg(1e-4, 0.0, 0.0)
            },
        );
        assert_eq!(plain.termination, Termination::Ftol);
        assert_eq!(polished.termination, Termination::Ftol);
        let err = |x: &DVector<f64>| ((x - &reference.x).amax()) / reference.x.amax();
        assert!(err(&plain.x) > 1e-9, "{:e}", err(&plain.x));
        assert!(err(&polished.x) < 1e-13, "{:e}", err(&polished.x));
        assert!(polished.evaluations > plain.evaluations);
        // Polishing cannot raise the cost beyond rounding.
        assert!(polished.cost <= plain.cost * (1.0 + 1e-10));
    }

    #[test]
    fn progress_observer_runs() {
        // Not a terminal under `cargo test`: indicatif draws nothing, but the observer path
        // (init, every iteration, final) is exercised.
        let config = LmConfig {
            progress: true,
            ..LmConfig::default()
        };
        let rep = minimize(&rosenbrock(), v(&[-1.2, 1.0]), &config);
        assert!(rep.termination.converged());
    }

    #[test]
    fn terminates_on_ftol() {
        let rep = minimize(&decay(), v(&[1.0, 0.1]), &cfg(1e-8, 0.0, 0.0));
        assert_eq!(rep.termination, Termination::Ftol);
        assert!(rep.cost > 0.0);
        assert_relative_eq!(rep.x[1], 0.7, epsilon = 0.01);
    }

    #[test]
    fn predicted_stop_saves_the_confirming_evaluation() {
        // Same run with MINPACK's rules and with the predicted-reduction stop: the latter
        // ends one or more evaluations earlier, at a point whose cost is within ftol
        // (relative) of the fully converged one.
        let ftol = 1e-10;
        let plain = minimize(&decay(), v(&[1.0, 0.1]), &cfg(ftol, 0.0, 0.0));
        let early = minimize(
            &decay(),
            v(&[1.0, 0.1]),
            &LmConfig {
                predicted_stop: true,
                ..cfg(ftol, 0.0, 0.0)
            },
        );
        assert_eq!(plain.termination, Termination::Ftol);
        assert_eq!(early.termination, Termination::Predicted);
        assert!(early.termination.converged());
        assert!(early.evaluations < plain.evaluations);
        assert!(early.cost >= plain.cost * (1.0 - 1e-15));
        assert!(
            early.cost <= plain.cost * (1.0 + ftol),
            "{} vs {}",
            early.cost,
            plain.cost
        );
        // Ignored while polishing.
        let polished = minimize(
            &decay(),
            v(&[1.0, 0.1]),
            &LmConfig {
                predicted_stop: true,
                polish: true,
                ..cfg(ftol, 0.0, 0.0)
            },
        );
        assert_ne!(polished.termination, Termination::Predicted);
    }

    #[test]
    fn terminates_on_xtol() {
        let rep = minimize(&decay(), v(&[1.0, 0.1]), &cfg(0.0, 1e-3, 0.0));
        assert_eq!(rep.termination, Termination::Xtol);
        assert_relative_eq!(rep.x[1], 0.7, epsilon = 0.01);
    }

    #[test]
    fn terminates_on_ftol_and_xtol() {
        let rep = minimize(&decay(), v(&[1.0, 0.1]), &cfg(1e-3, 1e-3, 0.0));
        assert_eq!(rep.termination, Termination::FtolXtol);
        assert!(rep.termination.converged());
    }

    #[test]
    fn terminates_on_gtol() {
        let rep = minimize(&decay(), v(&[1.0, 0.1]), &cfg(0.0, 0.0, 1e-4));
        assert_eq!(rep.termination, Termination::Gtol);
        // A zero residual at the start is a zero gradient.
        let rep = minimize(&rosenbrock(), v(&[1.0, 1.0]), &LmConfig::default());
        assert_eq!(rep.termination, Termination::Gtol);
        assert_eq!(rep.evaluations, 1);
    }

    #[test]
    fn terminates_on_max_iterations() {
        let config = LmConfig {
            max_iters: 3,
            ..cfg(0.0, 0.0, 0.0)
        };
        let rep = minimize(&rosenbrock(), v(&[-1.2, 1.0]), &config);
        assert_eq!(rep.termination, Termination::MaxIterations);
        assert_eq!(rep.iterations, 3);
        assert!(!rep.termination.converged());
    }

    #[test]
    fn terminates_on_max_evaluations() {
        let config = LmConfig {
            max_evals: 4,
            ..cfg(0.0, 0.0, 0.0)
        };
        let rep = minimize(&rosenbrock(), v(&[-1.2, 1.0]), &config);
        assert_eq!(rep.termination, Termination::MaxEvaluations);
        assert_eq!(rep.evaluations, 4);
    }

    #[test]
    fn terminates_on_timeout() {
        let slow = Closure {
            r: |x: &DVector<f64>| {
                std::thread::sleep(Duration::from_millis(5));
                v(&[10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0], 1.0])
            },
            j: |x: &DVector<f64>| {
                DMatrix::from_row_slice(3, 2, &[-20.0 * x[0], 10.0, -1.0, 0.0, 0.0, 0.0])
            },
        };
        let config = LmConfig {
            timeout: Some(Duration::from_millis(30)),
            ..cfg(0.0, 0.0, 0.0)
        };
        let rep = minimize(&slow, v(&[-1.2, 1.0]), &config);
        assert_eq!(rep.termination, Termination::Timeout);
        assert!(rep.seconds < 5.0);
    }

    #[test]
    fn terminates_on_interrupt_flag() {
        let flag = Arc::new(AtomicBool::new(false));
        let count = AtomicU64::new(0);
        let f2 = flag.clone();
        let p = Closure {
            r: move |x: &DVector<f64>| {
                if count.fetch_add(1, Ordering::SeqCst) == 5 {
                    f2.store(true, Ordering::SeqCst);
                }
                rosen_r(x)
            },
            j: rosen_j,
        };
        let config = LmConfig {
            interrupt: Some(flag),
            ..cfg(0.0, 0.0, 0.0)
        };
        let rep = minimize(&p, v(&[-1.2, 1.0]), &config);
        assert_eq!(rep.termination, Termination::Interrupted);
        assert_eq!(rep.evaluations, 6);
    }

    #[test]
    fn reports_non_finite_start() {
        let p = Closure {
            r: |x: &DVector<f64>| v(&[x[0].sqrt() - 1.0, 0.0]),
            j: |x: &DVector<f64>| DMatrix::from_row_slice(2, 1, &[0.5 / x[0].sqrt(), 0.0]),
        };
        let rep = minimize(&p, v(&[-1.0]), &LmConfig::default());
        assert_eq!(rep.termination, Termination::NonFiniteStart);
        assert_eq!(rep.x[0], -1.0);
        assert!(!rep.termination.converged());
    }

    #[test]
    fn reports_non_finite_jacobian() {
        let p = Closure {
            r: |x: &DVector<f64>| v(&[x[0] - 1.0, 0.0]),
            j: |_: &DVector<f64>| DMatrix::from_row_slice(2, 1, &[f64::NAN, 0.0]),
        };
        let rep = minimize(&p, v(&[3.0]), &LmConfig::default());
        assert_eq!(rep.termination, Termination::NonFiniteJacobian);
    }

    #[test]
    fn reports_no_progress_when_every_trial_is_non_finite() {
        // Finite only at the start: the trust region collapses onto NaN trial points.
        let p = Closure {
            r: |x: &DVector<f64>| {
                if x[0] == 3.0 {
                    v(&[2.0, 1.0])
                } else {
                    v(&[f64::NAN, 1.0])
                }
            },
            j: |_: &DVector<f64>| DMatrix::from_row_slice(2, 1, &[1.0, 0.0]),
        };
        let rep = minimize(&p, v(&[3.0]), &LmConfig::default());
        assert_eq!(rep.termination, Termination::NoProgress);
        assert_eq!(rep.x[0], 3.0);
    }

    #[test]
    fn nan_residuals_reject_the_step_and_the_fit_recovers() {
        // r = √a·t − 2t is NaN for a < 0; from a = 25 the first (Gauss–Newton sized) step,
        // Δa = −2(√a − 2)√a = −75, lands at a < 0.
        let t: Vec<f64> = (1..=10).map(|i| i as f64).collect();
        let nan_seen = Cell::new(false);
        let p = Closure {
            r: |x: &DVector<f64>| {
                let r =
                    DVector::from_iterator(t.len(), t.iter().map(|&t| x[0].sqrt() * t - 2.0 * t));
                if r.iter().any(|v| v.is_nan()) {
                    nan_seen.set(true);
                }
                r
            },
            j: |x: &DVector<f64>| {
                DMatrix::from_iterator(t.len(), 1, t.iter().map(|&t| 0.5 * t / x[0].sqrt()))
            },
        };
        let rep = minimize(&p, v(&[25.0]), &LmConfig::default());
        assert!(rep.termination.converged(), "{:?}", rep.termination);
        assert_relative_eq!(rep.x[0], 4.0, epsilon = 1e-9);
        assert!(nan_seen.get(), "the test should exercise a NaN trial point");
    }

    #[test]
    fn rank_deficient_jacobian() {
        // r = (a + b)·t − 2t + noise: only a + b is determined.
        let t: Vec<f64> = (1..=5).map(|i| i as f64).collect();
        let noise = [0.01, -0.02, 0.0, 0.015, -0.005];
        let p = Closure {
            r: |x: &DVector<f64>| {
                DVector::from_iterator(
                    5,
                    (0..5).map(|i| (x[0] + x[1]) * t[i] - 2.0 * t[i] + noise[i]),
                )
            },
            j: |_: &DVector<f64>| DMatrix::from_fn(5, 2, |i, _| t[i]),
        };
        let rep = minimize(&p, v(&[5.0, -7.0]), &LmConfig::default());
        assert!(rep.termination.converged(), "{:?}", rep.termination);
        let sum_ls = 2.0 - (0..5).map(|i| noise[i] * t[i]).sum::<f64>() / 55.0;
        assert_relative_eq!(rep.x[0] + rep.x[1], sum_ls, epsilon = 1e-12);
        assert!(rep.x.iter().all(|v| v.is_finite()));
        let u = crate::fit::stats::uncertainty(&rep.jacobian, rep.cost, 5, 1e-10);
        assert_eq!(u.rank, 1);
        assert!(u.condition.is_infinite() || u.condition > 1e14);
        assert_eq!(u.undetermined.len(), 1);
        let d = &u.undetermined[0];
        assert_relative_eq!(d[0].abs(), std::f64::consts::FRAC_1_SQRT_2, epsilon = 1e-12);
        assert_relative_eq!(d[0], -d[1], epsilon = 1e-12);
        // Pseudo-inverse: the determined combination a + b has variance s²/Σt², the
        // undetermined one a − b gets none.
        let s2 = 2.0 * rep.cost / 3.0;
        let var_sum = u.covariance.sum();
        assert_relative_eq!(var_sum, s2 / 55.0, max_relative = 1e-10);
    }

    #[test]
    fn fewer_residuals_than_parameters() {
        // One residual, two parameters: padded internally, converges onto the solution set.
        let p = Closure {
            r: |x: &DVector<f64>| v(&[x[0] * x[1] - 6.0]),
            j: |x: &DVector<f64>| DMatrix::from_row_slice(1, 2, &[x[1], x[0]]),
        };
        let rep = minimize(&p, v(&[1.0, 1.0]), &LmConfig::default());
        assert!(rep.termination.converged(), "{:?}", rep.termination);
        assert!(rep.cost < 1e-20);
        assert_eq!(rep.residuals.len(), 1);
        assert_eq!(rep.jacobian.shape(), (1, 2));
    }

    #[test]
    fn runs_as_an_argmin_solver_through_the_executor() {
        let p = rosenbrock();
        let solver = LevenbergMarquardt::new().with_ftol(1e-12).unwrap();
        let res = Executor::new(ArgminAdapter(&p), solver)
            .configure(|s| s.param(v(&[-1.2, 1.0])).max_iters(200))
            .ctrlc(false)
            .run()
            .unwrap();
        let x = res.state.get_best_param().unwrap();
        assert_relative_eq!(x[0], 1.0, epsilon = 1e-10);
        assert!(res.solver.termination().unwrap().converged());
        assert_eq!(
            res.state.get_termination_reason(),
            Some(&TerminationReason::SolverConverged)
        );
        // The gradient slot holds Jᵀr (at the last Jacobian evaluation).
        assert!(res.state.get_gradient().unwrap().norm() < 1e-6);
        assert_eq!(res.state.get_jacobian().unwrap().shape(), (2, 2));
    }

    #[test]
    fn builders_validate() {
        assert!(LevenbergMarquardt::new().with_ftol(-1.0).is_err());
        assert!(LevenbergMarquardt::new().with_xtol(f64::NAN).is_err());
        assert!(LevenbergMarquardt::new().with_gtol(f64::INFINITY).is_err());
        assert!(LevenbergMarquardt::new().with_stepbound(0.0).is_err());
        assert!(LevenbergMarquardt::new().with_max_evals(0).is_err());
        assert!(LevenbergMarquardt::new().with_ftol(0.0).is_ok());
        let e = LevenbergMarquardt::new()
            .with_ftol(-1.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("ftol") && e.contains("-1"), "{e}");
    }

    #[test]
    fn termination_descriptions() {
        use Termination::*;
        for t in [
            Ftol,
            Xtol,
            FtolXtol,
            Gtol,
            Predicted,
            MaxIterations,
            MaxEvaluations,
            Timeout,
            Interrupted,
            NonFiniteStart,
            NonFiniteJacobian,
            NoProgress,
        ] {
            assert!(!t.describe().is_empty());
            assert_eq!(t.converged(), t.describe().starts_with("converged"));
        }
    }

    #[test]
    fn finite_differences_match_analytic() {
        let p = decay();
        let x = v(&[2.0, 0.5]);
        let ja = p.jacobian(&x);
        let r0 = p.residuals(&x);
        let jf = finite_difference_jacobian(|x| p.residuals(x), &x, Some(&r0));
        let jc = finite_difference_jacobian(|x| p.residuals(x), &x, None);
        assert!((&jf - &ja).amax() < 1e-6 * ja.amax());
        assert!((&jc - &ja).amax() < 1e-9 * ja.amax());
    }

    #[test]
    fn transformed_log_and_fixed_parameters() {
        // Inner parameters (a, b, c) of y = a·exp(−b t) + c, with c fixed at 0 and b on a
        // log scale: the fit must match the direct two-parameter fit.
        let (t, y) = decay_data();
        let inner = Closure {
            r: |x: &DVector<f64>| {
                DVector::from_iterator(
                    t.len(),
                    t.iter()
                        .zip(&y)
                        .map(|(&t, &y)| x[0] * (-x[1] * t).exp() + x[2] - y),
                )
            },
            j: |x: &DVector<f64>| {
                let mut j = DMatrix::zeros(t.len(), 3);
                for (i, &t) in t.iter().enumerate() {
                    let e = (-x[1] * t).exp();
                    j[(i, 0)] = e;
                    j[(i, 1)] = -x[0] * t * e;
                    j[(i, 2)] = 1.0;
                }
                j
            },
        };
        let tr =
            Transformed::new(inner, vec![false, true, false], vec![None, None, Some(0.0)]).unwrap();
        assert_eq!(tr.n_free(), 2);
        assert_eq!(tr.free_indices(), &[0, 1]);
        let z0 = tr.to_free(&v(&[1.0, 0.1, 123.0])).unwrap();
        assert_relative_eq!(z0[1], 0.1f64.ln());
        // Chain rule against finite differences.
        let jz = tr.jacobian(&z0);
        let jn = finite_difference_jacobian(|z| tr.residuals(z), &z0, None);
        assert!((&jz - &jn).amax() < 1e-8 * jz.amax());
        let rep_z = minimize(&tr, z0, &LmConfig::default());
        let rep_x = minimize(&decay(), v(&[1.0, 0.1]), &LmConfig::default());
        let x = tr.to_full(&rep_z.x);
        assert_relative_eq!(x[0], rep_x.x[0], epsilon = 1e-8);
        assert_relative_eq!(x[1], rep_x.x[1], epsilon = 1e-8);
        assert_eq!(x[2], 0.0);
        // Delta method: the covariance of (a, b) equals the direct fit's.
        let uz = crate::fit::stats::uncertainty(&rep_z.jacobian, rep_z.cost, 20, 1e-12);
        let ux = crate::fit::stats::uncertainty(&rep_x.jacobian, rep_x.cost, 20, 1e-12);
        let cx = tr.covariance_to_full(&rep_z.x, &uz.covariance);
        assert_eq!(cx.shape(), (3, 3));
        for i in 0..2 {
            for j in 0..2 {
                assert_relative_eq!(cx[(i, j)], ux.covariance[(i, j)], max_relative = 1e-6);
            }
        }
        assert_eq!(cx[(2, 2)], 0.0);
        assert!(tr.to_free(&v(&[1.0, -0.1, 0.0])).is_err());
        assert!(Transformed::new((), vec![true], vec![Some(-1.0)]).is_err());
        assert!(Transformed::new((), vec![true, false], vec![None]).is_err());
    }
}
