//! Unit tests of the solver: stopping rules, robustness, argmin integration.

use super::test_problems::{decay, v};
use super::*;
use approx::assert_relative_eq;
use argmin::core::{Executor, State};
use std::cell::Cell;
use std::sync::atomic::AtomicU64;
use std::time::Duration;

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
            let r = DVector::from_iterator(t.len(), t.iter().map(|&t| x[0].sqrt() * t - 2.0 * t));
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
    let mut solver = res.solver;
    assert_eq!(solver.take_jacobian().unwrap().shape(), (2, 2));
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

/// A problem that supplies its Jacobian reduced in blocks of `block` rows.
struct Blocked<P> {
    inner: P,
    block: usize,
}

impl<P: LeastSquaresProblem> LeastSquaresProblem for Blocked<P> {
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
        self.inner.residuals(x)
    }
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        self.inner.jacobian(x)
    }
    fn reduced_jacobian(&self, x: &DVector<f64>) -> Option<Reduced> {
        let (j, f) = (self.inner.jacobian(x), self.inner.residuals(x));
        let mut red = Reduced::empty(j.ncols());
        for first in (0..j.nrows()).step_by(self.block) {
            let rows = self.block.min(j.nrows() - first);
            let part = j.rows(first, rows).into_owned();
            red.push_rows(part.as_slice(), &f.as_slice()[first..first + rows]);
        }
        Some(red)
    }
}

/// y = a·exp(−b t) + c on `m` samples with deterministic pseudo-noise.
fn decay_offset(m: usize) -> impl LeastSquaresProblem {
    let t: Vec<f64> = (0..m).map(|i| 5.0 * i as f64 / m as f64).collect();
    let noise = |i: usize| 0.01 * ((i * 7919 % 101) as f64 / 50.0 - 1.0);
    let y: Vec<f64> = (0..m)
        .map(|i| 3.0 * (-0.7 * t[i]).exp() + 0.2 + noise(i))
        .collect();
    let t2 = t.clone();
    Closure {
        r: move |x: &DVector<f64>| {
            DVector::from_iterator(m, (0..m).map(|i| x[0] * (-x[1] * t[i]).exp() + x[2] - y[i]))
        },
        j: move |x: &DVector<f64>| {
            DMatrix::from_fn(m, 3, |i, k| {
                let e = (-x[1] * t2[i]).exp();
                [e, -x[0] * t2[i] * e, 1.0][k]
            })
        },
    }
}

#[test]
fn reduced_jacobian_solves_as_the_dense_one() {
    let x0 = v(&[1.0, 0.2, 0.0]);
    let dense = minimize(&decay_offset(5000), x0.clone(), &LmConfig::default());
    let blocked = Blocked {
        inner: decay_offset(5000),
        block: 700,
    };
    let reduced = minimize(&blocked, x0, &LmConfig::default());
    assert!(dense.termination.converged() && reduced.termination.converged());
    assert_eq!(reduced.iterations, dense.iterations);
    assert_relative_eq!(reduced.cost, dense.cost, max_relative = 1e-12);
    for k in 0..3 {
        assert_relative_eq!(reduced.x[k], dense.x[k], max_relative = 1e-10);
    }
    // The report's matrix is the reduced one: 3 × 3 with the dense Jacobian's JᵀJ.
    assert_eq!(reduced.jacobian.shape(), (3, 3));
    let gram = dense.jacobian.tr_mul(&dense.jacobian);
    let diff = (reduced.jacobian.tr_mul(&reduced.jacobian) - &gram).norm();
    assert!(diff <= 1e-10 * gram.norm(), "{diff}");
}

/// A problem that counts its residual evaluations and the vectors handed back to it.
struct Counting<P> {
    inner: P,
    evaluations: Cell<u64>,
    recycled: Cell<u64>,
    rows: usize,
}

impl<P: LeastSquaresProblem> LeastSquaresProblem for Counting<P> {
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
        self.evaluations.set(self.evaluations.get() + 1);
        self.inner.residuals(x)
    }
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        self.inner.jacobian(x)
    }
    fn recycle(&self, spent: DVector<f64>) {
        assert_eq!(
            spent.len(),
            self.rows,
            "a residual vector of the problem's length"
        );
        self.recycled.set(self.recycled.get() + 1);
    }
}

#[test]
fn every_evaluation_after_the_first_hands_one_vector_back() {
    for polish in [false, true] {
        let p = Counting {
            inner: decay(),
            evaluations: Cell::new(0),
            recycled: Cell::new(0),
            rows: decay().residuals(&v(&[1.0, 0.1])).len(),
        };
        let config = LmConfig {
            polish,
            ..cfg(1e-15, 1e-15, 0.0)
        };
        let rep = minimize(&p, v(&[1.0, 0.1]), &config);
        assert!(rep.termination.converged(), "{:?}", rep.termination);
        assert_eq!(p.evaluations.get(), rep.evaluations);
        assert!(rep.evaluations > 3);
        // The solver keeps the current point's residuals (the last one it moved to); each
        // trial's vector, or the one it replaced, comes back.
        assert_eq!(p.recycled.get(), rep.evaluations - 1, "polish {polish}");
    }
}
