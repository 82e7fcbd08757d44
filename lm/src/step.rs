//! One LM trial step (MINPACK `lmder`'s inner loop): the damped step from `lmpar`, its
//! evaluation, the ratio of actual to predicted reduction, the trust-region update, the
//! acceptance, and the convergence tests.

use argmin::core::{Error as ArgminError, Operator, Problem};
use nalgebra::DVector;

use super::lmpar::lmpar;
use super::norm::{all_finite, enorm, pad_vec};
use super::qr::jp_norm;
use super::run::StepResiduals;
use super::work::Work;
use super::{Termination, EPSMCH, RHO_ACCEPT, RHO_EXPAND, RHO_SHRINK};

/// A proposed step from the current point.
pub(super) struct Trial {
    step: DVector<f64>,
    /// `‖D p‖`.
    pnorm: f64,
    /// `‖J p‖ / ‖r‖`: the square root of the linear model's relative reduction.
    jp_rel: f64,
}

/// What evaluating a trial step found.
pub(super) struct Outcome {
    /// Actual relative reduction `1 − (‖r₁‖/‖r‖)²` (−1 for a large increase).
    pub(super) actred: f64,
    /// Predicted relative reduction of the damped linear model.
    pub(super) prered: f64,
    /// `actred / prered` (0 when nothing was predicted).
    pub(super) ratio: f64,
    /// `‖r₁‖` at the trial point (∞ for non-finite residuals).
    pub(super) fnorm1: f64,
    pub(super) accepted: bool,
}

/// The tolerances the convergence tests use.
#[derive(Debug, Clone, Copy)]
pub(super) struct Tolerances {
    pub(super) ftol: f64,
    pub(super) xtol: f64,
    pub(super) max_evals: u64,
}

impl Work {
    /// The LM step for the current trust radius (`lmpar`, which also updates `λ`).
    pub(super) fn propose(&mut self) -> Trial {
        let qr = self.qr.as_mut().expect("QR present after Jacobian");
        let mut step = DVector::zeros(self.x.len());
        lmpar(qr, &self.diag, self.delta, &mut self.par, &mut step);
        let step = -step;
        let pnorm = enorm(self.diag.component_mul(&step).as_slice());
        let jp_rel = jp_norm(qr, &step) / self.fnorm;
        Trial {
            step,
            pnorm,
            jp_rel,
        }
    }

    /// Whether `trial` lets the run stop as [`Termination::Predicted`]: it is the undamped
    /// Gauss–Newton step, predicts a relative reduction of at most `ftol`, and the last
    /// accepted step's reduction matched its prediction within 25 %.
    pub(super) fn predicts_convergence(&self, trial: &Trial, ftol: f64) -> bool {
        !self.first
            && self.par == 0.0
            && (self.last_ratio - 1.0).abs() <= 0.25
            && trial.jp_rel * trial.jp_rel <= ftol
    }

    /// Evaluate the trial point, update the trust region and accept the step when the ratio
    /// of actual to predicted reduction is at least `RHO_ACCEPT`.
    pub(super) fn evaluate<O>(
        &mut self,
        problem: &mut Problem<O>,
        trial: Trial,
    ) -> Result<Outcome, ArgminError>
    where
        O: Operator<Param = DVector<f64>, Output = DVector<f64>> + StepResiduals,
    {
        let rows = self.r.len();
        let point = &self.x + &trial.step;
        if self.first {
            self.delta = self.delta.min(trial.pnorm);
        }
        let r1 = problem.apply(&point)?;
        self.nfev += 1;
        let r1 = pad_vec(r1, rows);
        let mut fnorm1 = enorm(r1.as_slice());
        if !all_finite(&r1) || r1.len() != rows {
            fnorm1 = f64::INFINITY;
        }
        let actred = self.actual_reduction(&r1, fnorm1);
        // Predicted reduction from the linear model: ‖J p‖² and the λ‖Dp‖² term.
        let temp1 = trial.jp_rel;
        let temp2 = self.par.sqrt() * trial.pnorm / self.fnorm;
        let prered = temp1 * temp1 + temp2 * temp2 / 0.5;
        let dirder = -(temp1 * temp1 + temp2 * temp2);
        let ratio = if prered != 0.0 { actred / prered } else { 0.0 };
        self.update_trust_region(ratio, actred, dirder, fnorm1, trial.pnorm);
        if prered <= 1e-12 && fnorm1.is_finite() {
            self.cost_noise = self.cost_noise.max(actred.abs());
        }
        let accepted = ratio >= RHO_ACCEPT;
        let spent = if accepted {
            self.first = false;
            self.last_ratio = ratio;
            self.move_to(point, r1, fnorm1)
        } else {
            r1
        };
        recycle(problem, spent)?;
        Ok(Outcome {
            actred,
            prered,
            ratio,
            fnorm1,
            accepted,
        })
    }

    /// Actual relative reduction 1 − (‖r₁‖/‖r‖)², computed as −Σ(r₁−r)(r₁+r)/‖r‖² to avoid
    /// the cancellation of two nearly equal squared norms near convergence; −1 when
    /// `‖r₁‖ ≥ 10‖r‖` (as MINPACK).
    fn actual_reduction(&self, r1: &DVector<f64>, fnorm1: f64) -> f64 {
        if 0.1 * fnorm1 < self.fnorm {
            let inv = 1.0 / self.fnorm;
            let s: f64 = r1
                .iter()
                .zip(self.r.iter())
                .map(|(&a, &b)| ((a - b) * inv) * ((a + b) * inv))
                .sum();
            -s
        } else {
            -1.0
        }
    }

    /// MINPACK's trust-region update: shrink `Δ` by a factor in `[0.1, 0.5]` (quadratic
    /// interpolation) for a poor ratio, set `Δ = 2‖D p‖` for a good one or a Gauss–Newton
    /// step, and move `λ` the other way.
    fn update_trust_region(
        &mut self,
        ratio: f64,
        actred: f64,
        dirder: f64,
        fnorm1: f64,
        pnorm: f64,
    ) {
        if ratio <= RHO_SHRINK {
            let mut temp = if actred >= 0.0 {
                0.5
            } else {
                0.5 * dirder / (dirder + 0.5 * actred)
            };
            if 0.1 * fnorm1 >= self.fnorm || temp.is_nan() || temp < 0.1 {
                temp = 0.1;
            }
            self.delta = temp * self.delta.min(pnorm / 0.1);
            self.par /= temp;
        } else if self.par == 0.0 || ratio >= RHO_EXPAND {
            self.delta = pnorm / 0.5;
            self.par *= 0.5;
        }
    }

    /// MINPACK's convergence tests, in MINPACK's order, after a trial step.
    pub(super) fn convergence(&self, o: &Outcome, tol: Tolerances) -> Option<Termination> {
        let f_ok = o.actred.abs() <= tol.ftol && o.prered <= tol.ftol && 0.5 * o.ratio <= 1.0;
        let x_ok = self.delta <= tol.xtol * self.xnorm;
        let term = if f_ok && x_ok {
            Some(Termination::FtolXtol)
        } else if f_ok {
            Some(Termination::Ftol)
        } else if x_ok {
            Some(Termination::Xtol)
        } else if self.nfev >= tol.max_evals {
            Some(Termination::MaxEvaluations)
        } else if o.actred.abs() <= EPSMCH && o.prered <= EPSMCH && 0.5 * o.ratio <= 1.0 {
            Some(Termination::Ftol)
        } else if self.delta <= EPSMCH * self.xnorm {
            Some(Termination::Xtol)
        } else if self.delta.is_nan() || self.delta <= f64::MIN_POSITIVE {
            Some(Termination::NoProgress)
        } else {
            None
        };
        // A trust region that collapsed onto non-finite trial points is not convergence.
        match term {
            Some(Termination::Xtol) if o.fnorm1.is_infinite() => Some(Termination::NoProgress),
            t => t,
        }
    }
}

/// Hand residuals the iteration is done with back to the problem
/// ([`super::LeastSquaresProblem::recycle`]).
pub(super) fn recycle<O: StepResiduals>(
    problem: &mut Problem<O>,
    spent: DVector<f64>,
) -> Result<(), ArgminError> {
    problem.problem("recycle", |o| {
        o.recycle(spent);
        Ok(())
    })
}
