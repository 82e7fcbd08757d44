//! Gauss–Newton polishing after convergence (see
//! [`super::LevenbergMarquardt::with_polish`]).

use argmin::core::{Error as ArgminError, Operator, Problem, KV};
use nalgebra::DVector;

use super::lmpar::lmpar;
use super::norm::{all_finite, enorm, pad_vec};
use super::qr::jp_norm;
use super::run::StepResiduals;
use super::step::recycle;
use super::work::{Polish, PolishPoint, Work};
use super::{Termination, EPSMCH};

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

impl Work {
    /// One polishing iteration: the undamped Gauss–Newton step from the current point
    /// (minimum-length on a singular `R`), taken when it is small and keeps the cost within
    /// rounding noise of where polishing started. Returns the argmin key-values and, when
    /// polishing ends, the termination to report (the run then stands at the iterate with
    /// the smallest Gauss–Newton step).
    pub(super) fn polish_step<O>(
        &mut self,
        problem: &mut Problem<O>,
        mut pol: Polish,
        max_evals: u64,
    ) -> Result<(KV, Option<Termination>), ArgminError>
    where
        O: Operator<Param = DVector<f64>, Output = DVector<f64>> + StepResiduals,
    {
        let (step, pnorm, prered) = self.gauss_newton_probe();
        self.record_polish_point(&mut pol, pnorm);
        let mut finish = pol.stale >= POLISH_PATIENCE
            || pol.steps >= MAX_POLISH_STEPS
            || pnorm <= EPSMCH * self.xnorm
            || self.fnorm == 0.0
            || self.nfev >= max_evals
            || prered > POLISH_TOL
            || (pol.steps == 0 && pnorm > POLISH_MAX_REL_STEP * self.xnorm);
        let mut accepted = false;
        if !finish {
            accepted = self.try_polish_step(problem, &pol, step)?;
            if accepted {
                pol.steps += 1;
            } else {
                finish = true;
            }
        }
        let mut termination = None;
        if finish {
            self.end_at_best(&mut pol);
            termination = Some(pol.reason);
        }
        let kv = argmin::kv!(
            "delta" => self.delta;
            "lambda" => 0.0;
            "polish" => pol.steps;
            "accepted" => accepted;
            "evals" => self.nfev;
        );
        self.polish = Some(pol);
        Ok((kv, termination))
    }

    /// The Gauss–Newton step `p` (λ = 0), `‖D p‖`, and its predicted relative reduction
    /// `‖J p‖²/‖r‖²`.
    fn gauss_newton_probe(&mut self) -> (DVector<f64>, f64, f64) {
        let qr = self.qr.as_mut().expect("QR present after Jacobian");
        let mut step = DVector::zeros(self.x.len());
        let mut par = 0.0;
        lmpar(qr, &self.diag, f64::INFINITY, &mut par, &mut step);
        let step = -step;
        let pnorm = enorm(self.diag.component_mul(&step).as_slice());
        let prered = (jp_norm(qr, &step) / self.fnorm).powi(2);
        (step, pnorm, prered)
    }

    /// Keep the current point as the best when its Gauss–Newton step is the smallest yet:
    /// it is then the one closest to stationarity as far as the (noise-free) linear model
    /// can tell.
    fn record_polish_point(&self, pol: &mut Polish, pnorm: f64) {
        if pol.best.as_ref().is_none_or(|b| pnorm < b.pnorm) {
            pol.best = Some(PolishPoint {
                x: self.x.clone(),
                r: self.r.clone(),
                fnorm: self.fnorm,
                pnorm,
            });
            pol.stale = 0;
        } else {
            pol.stale += 1;
        }
    }

    /// Evaluate `x + step` and move there when the cost stays within the polishing slack of
    /// the cost where polishing started. Returns whether the step was taken.
    fn try_polish_step<O>(
        &mut self,
        problem: &mut Problem<O>,
        pol: &Polish,
        step: DVector<f64>,
    ) -> Result<bool, ArgminError>
    where
        O: Operator<Param = DVector<f64>, Output = DVector<f64>> + StepResiduals,
    {
        let rows = self.r.len();
        let trial = &self.x + &step;
        let r1 = pad_vec(problem.apply(&trial)?, rows);
        self.nfev += 1;
        let fnorm1 = if all_finite(&r1) && r1.len() == rows {
            enorm(r1.as_slice())
        } else {
            f64::INFINITY
        };
        let slack = POLISH_TOL.max((4.0 * self.cost_noise).min(POLISH_MAX_NOISE));
        let taken = fnorm1 * fnorm1 <= pol.fnorm0 * pol.fnorm0 * (1.0 + slack);
        let spent = if taken {
            self.move_to(trial, r1, fnorm1)
        } else {
            r1
        };
        recycle(problem, spent)?;
        Ok(taken)
    }

    /// End at the best iterate (its Jacobian is re-evaluated if it is not the current point).
    fn end_at_best(&mut self, pol: &mut Polish) {
        if let Some(b) = pol.best.take() {
            if b.x != self.x {
                self.move_to(b.x, b.r, b.fnorm);
            }
        }
    }
}
