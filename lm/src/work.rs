//! What the iteration carries between trial steps, and the Jacobian stage of an iteration
//! (evaluate `J`, factor it, update the scaling, test the gradient).

use argmin::core::{Error as ArgminError, Jacobian, Problem};
use nalgebra::{DMatrix, DVector};

use super::norm::{all_finite, enorm, pad_mat, pad_vec};
use super::qr::{qrfac, QrState};
use super::reduced::Reduced;
use super::run::StepResiduals;
use super::{LmState, Termination, EPSMCH};

/// Jacobians of at most this many entries (1M: 8 MB) stay in the work after they are
/// factored; larger ones are factored in their own storage and dropped.
const KEEP_JACOBIAN_MAX: usize = 1 << 20;

/// The pivoted QR of the Jacobian, its column norms and the gradient.
type Factored = (QrState, DVector<f64>, DVector<f64>);

/// Everything the iteration carries between trial steps.
#[derive(Debug, Clone)]
pub(super) struct Work {
    /// Number of residuals as supplied (before padding to `max(m, n)` rows).
    pub(super) m: usize,
    pub(super) x: DVector<f64>,
    /// Residuals at `x`, padded with zeros to `max(m, n)`.
    pub(super) r: DVector<f64>,
    pub(super) fnorm: f64,
    /// Jacobian at `x` (padded), valid when `!need_jac` and it is small enough to keep
    /// ([`KEEP_JACOBIAN_MAX`]; empty otherwise). The gradient `Jᵀr` (`Jᵀf̃` with step
    /// residuals) goes into the argmin state.
    pub(super) jac: DMatrix<f64>,
    /// Step residuals at `x` (padded) when the problem supplies them (a robust loss; see
    /// [`super::LeastSquaresProblem::step_residuals`]), valid when `!need_jac`.
    pub(super) step_r: Option<DVector<f64>>,
    /// The reduced Jacobian's `A` at `x` ([`Reduced`]) when the problem supplied one,
    /// valid when `!need_jac` (then `jac` is empty).
    pub(super) reduced: Option<DMatrix<f64>>,
    pub(super) qr: Option<QrState>,
    pub(super) diag: DVector<f64>,
    pub(super) delta: f64,
    pub(super) par: f64,
    pub(super) xnorm: f64,
    pub(super) need_jac: bool,
    /// Set once the LM iteration has converged: the Gauss–Newton polishing phase.
    pub(super) polish: Option<Polish>,
    /// Largest |actual relative reduction| seen on trial steps whose predicted reduction was
    /// below `1e-12`: an estimate of the rounding noise in the relative cost.
    pub(super) cost_noise: f64,
    /// No step accepted yet (MINPACK's `iter == 1`).
    pub(super) first: bool,
    /// Ratio of actual to predicted reduction of the last accepted step.
    pub(super) last_ratio: f64,
    pub(super) nfev: u64,
    pub(super) njev: u64,
}

impl Work {
    /// The state at the start: `x` with its residuals `r` (padded to `max(m, n)` rows), one
    /// evaluation spent, the Jacobian still to be evaluated.
    pub(super) fn start(m: usize, x: DVector<f64>, r: DVector<f64>) -> Work {
        let n = x.len();
        Work {
            m,
            fnorm: enorm(r.as_slice()),
            x,
            r,
            // Evaluated before its first use (`need_jac`).
            jac: DMatrix::zeros(0, 0),
            step_r: None,
            reduced: None,
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
        }
    }

    /// `½‖r‖²` at the current point.
    pub(super) fn cost(&self) -> f64 {
        0.5 * self.fnorm * self.fnorm
    }

    /// Recompute `‖D x‖` after `x` or `D` changed.
    pub(super) fn update_xnorm(&mut self) {
        self.xnorm = enorm(self.diag.component_mul(&self.x).as_slice());
    }

    /// Move to an accepted point with residuals `r` (norm `fnorm`); its Jacobian is due.
    /// Returns the residuals of the point left.
    pub(super) fn move_to(&mut self, x: DVector<f64>, r: DVector<f64>, fnorm: f64) -> DVector<f64> {
        self.x = x;
        let left = std::mem::replace(&mut self.r, r);
        self.fnorm = fnorm;
        self.update_xnorm();
        self.need_jac = true;
        left
    }

    /// Evaluate and factor the Jacobian at the current point, update the scaling `D` (and on
    /// the first call the trust radius `Δ₀ = stepbound·‖D x₀‖`), and put `Jᵀr` and `J` into
    /// the argmin state. Returns the state and a termination when `J` (or the step
    /// residuals) is not finite (or not `m × n`), or when the gradient test (`gtol`, or
    /// machine epsilon) holds outside polishing. With step residuals `f̃` (a robust loss),
    /// `J` is factored with `f̃` in place of `r`, and `Jᵀf̃` is the gradient.
    pub(super) fn refresh_jacobian<O>(
        &mut self,
        problem: &mut Problem<O>,
        state: LmState,
        stepbound: f64,
        gtol: f64,
    ) -> Result<(LmState, Option<Termination>), ArgminError>
    where
        O: Jacobian<Param = DVector<f64>, Jacobian = DMatrix<f64>> + StepResiduals,
    {
        let reduced = problem.problem("reduced_jacobian", |o| Ok(o.reduced_jacobian(&self.x)))?;
        let factored = match reduced {
            Some(red) => self.factor_reduced(red),
            None => self.factor_jacobian(problem)?,
        };
        let Some((qr, acnorm, grad)) = factored else {
            return Ok((state, Some(Termination::NonFiniteJacobian)));
        };
        if self.first {
            self.initial_scaling(&acnorm, stepbound);
        }
        let rs_norm = match &self.step_r {
            Some(f) => enorm(f.as_slice()),
            None => self.fnorm,
        };
        let gnorm = scaled_gradient_norm(&qr, &acnorm, rs_norm);
        for j in 0..self.x.len() {
            self.diag[j] = self.diag[j].max(acnorm[j]);
        }
        self.qr = Some(qr);
        self.need_jac = false;
        let state = state.gradient(grad);
        // (While polishing, the polishing rules decide; they also end at a zero step.)
        if self.polish.is_none() && (gnorm <= gtol || gnorm <= EPSMCH) {
            return Ok((state, Some(Termination::Gtol)));
        }
        Ok((state, None))
    }

    /// Evaluate the Jacobian (and the step residuals, when the problem has them) at the
    /// current point and factor it: the pivoted QR, the column norms of `J` and the
    /// gradient `Jᵀr` (`Jᵀf̃`); None when `J` or the step residuals are not finite or not
    /// `m × n`.
    fn factor_jacobian<O>(
        &mut self,
        problem: &mut Problem<O>,
    ) -> Result<Option<Factored>, ArgminError>
    where
        O: Jacobian<Param = DVector<f64>, Jacobian = DMatrix<f64>> + StepResiduals,
    {
        let n = self.x.len();
        let jac = problem.jacobian(&self.x)?;
        self.njev += 1;
        if jac.shape() != (self.m, n) || jac.iter().any(|v| !v.is_finite()) {
            return Ok(None);
        }
        let step_r = problem.problem("step_residuals_count", |o| Ok(o.step_residuals(&self.x)))?;
        if step_r
            .as_ref()
            .is_some_and(|f| f.len() != self.m || !all_finite(f))
        {
            return Ok(None);
        }
        self.step_r = step_r.map(|f| pad_vec(f, self.r.len()));
        self.reduced = None;
        let jac = pad_mat(jac, self.r.len());
        let rs = self.step_r.as_ref().unwrap_or(&self.r);
        let grad = jac.tr_mul(rs);
        // The step needs only the factors. A small J is kept for the caller at the end; a
        // large one is factored in place (one m × n matrix less for the whole run) and
        // asked for again at the end (see [`super::LevenbergMarquardt::take_jacobian`]).
        let (qr, acnorm) = if jac.len() <= KEEP_JACOBIAN_MAX {
            self.jac = jac;
            qrfac(self.jac.clone(), rs)
        } else {
            self.jac = DMatrix::zeros(0, 0);
            qrfac(jac, rs)
        };
        Ok(Some((qr, acnorm, grad)))
    }

    /// Factor a reduced Jacobian `[A; b]` ([`Reduced`]) as [`Self::factor_jacobian`] factors
    /// `J` and `r`: the pivoted QR of `A` (padded with zero rows to `n`) with `b` is that of
    /// `J` with `r`, and `A`'s column norms are `J`'s. `A` is kept for the report. None when
    /// it is not finite or not `k × n` with `b` of length `k`.
    fn factor_reduced(&mut self, red: Reduced) -> Option<Factored> {
        let n = self.x.len();
        self.njev += 1;
        let k = red.a.nrows();
        let finite = red.a.iter().chain(red.b.iter()).all(|v| v.is_finite());
        if red.a.ncols() != n || red.b.len() != k || !finite {
            return None;
        }
        self.step_r = None;
        self.jac = DMatrix::zeros(0, 0);
        let grad = red.gradient();
        let rows = k.max(n);
        let Reduced { a, b } = red;
        let (qr, acnorm) = qrfac(
            a.clone().resize_vertically(rows, 0.0),
            &b.resize_vertically(rows, 0.0),
        );
        self.reduced = Some(a);
        Some((qr, acnorm, grad))
    }

    /// MINPACK `mode = 1`: `D` from the column norms of the first Jacobian (1 for a zero
    /// column), and the initial trust radius.
    fn initial_scaling(&mut self, acnorm: &DVector<f64>, stepbound: f64) {
        for j in 0..self.x.len() {
            self.diag[j] = if acnorm[j] == 0.0 { 1.0 } else { acnorm[j] };
        }
        self.update_xnorm();
        self.delta = stepbound * self.xnorm;
        if self.delta == 0.0 {
            self.delta = stepbound;
        }
    }
}

/// The largest cosine between `r` and a column of `J` (MINPACK's `gnorm`), from the pivoted
/// QR; 0 for a zero residual.
fn scaled_gradient_norm(qr: &QrState, acnorm: &DVector<f64>, fnorm: f64) -> f64 {
    let mut gnorm: f64 = 0.0;
    if fnorm != 0.0 {
        for j in 0..acnorm.len() {
            let l = qr.ipvt[j];
            if acnorm[l] != 0.0 {
                let mut sum = 0.0;
                for i in 0..=j {
                    sum += qr.r[(i, j)] * (qr.qtf[i] / fnorm);
                }
                gnorm = gnorm.max((sum / acnorm[l]).abs());
            }
        }
    }
    gnorm
}

/// State of the Gauss–Newton polishing phase (its steps are in `polish.rs`).
#[derive(Debug, Clone)]
pub(super) struct Polish {
    /// The convergence test that started it; reported as the run's termination.
    pub(super) reason: Termination,
    /// Accepted polishing steps.
    pub(super) steps: u32,
    /// `‖r‖` when polishing started.
    pub(super) fnorm0: f64,
    /// The iterate with the smallest Gauss–Newton step so far.
    pub(super) best: Option<PolishPoint>,
    /// Iterates since `best` last improved.
    pub(super) stale: u32,
}

#[derive(Debug, Clone)]
pub(super) struct PolishPoint {
    pub(super) x: DVector<f64>,
    pub(super) r: DVector<f64>,
    pub(super) fnorm: f64,
    pub(super) pnorm: f64,
}

impl Polish {
    /// Polishing that starts at a point with residual norm `fnorm0`, after `reason` held.
    pub(super) fn start(reason: Termination, fnorm0: f64) -> Polish {
        Polish {
            reason,
            steps: 0,
            fnorm0,
            best: None,
            stale: 0,
        }
    }
}
