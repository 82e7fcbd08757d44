//! Solve: one Levenberg–Marquardt run of a problem from a point in parameter space.

use nalgebra::{DMatrix, DVector};

use super::lm::{self, LeastSquaresProblem, LmConfig, Stop};
use super::problem::FitProblem;

/// An LM run in parameter space.
pub(super) struct Run {
    pub lm: lm::LmReport,
    /// The solver's final point in parameter space (layout order).
    pub values: Vec<f64>,
}

/// Minimise `problem` from `p0` (parameter space, layout order): the solver works in the
/// transformed space x of the layout, and the result is mapped back.
pub(super) fn run_lm(problem: &FitProblem, p0: &[f64], config: &LmConfig) -> Run {
    let x0 = problem.layout.to_x(p0);
    let lm = match &config.stop {
        Some(stop) => lm::minimize(&Stoppable::new(problem, stop), x0, config),
        None => lm::minimize(problem, x0, config),
    };
    let values = problem.layout.from_x(&lm.x);
    Run { lm, values }
}

impl Run {
    /// Add an earlier run's iteration, evaluation and time counts to this one (the report of
    /// a refit counts the whole fit's work).
    pub fn add_counts(&mut self, earlier: &lm::LmReport) {
        self.lm.iterations += earlier.iterations;
        self.lm.evaluations += earlier.evaluations;
        self.lm.jacobian_evaluations += earlier.jacobian_evaluations;
        self.lm.seconds += earlier.seconds;
    }
}

/// A fit problem whose trial evaluations end within one block of samples once `stop` is
/// requested. The first evaluation (the solver's start) is never cut, so every run has a
/// finite point to report.
struct Stoppable<'p, 'm> {
    problem: &'p FitProblem<'m>,
    stop: &'p Stop,
    started: std::sync::atomic::AtomicBool,
}

impl<'p, 'm> Stoppable<'p, 'm> {
    fn new(problem: &'p FitProblem<'m>, stop: &'p Stop) -> Self {
        Stoppable {
            problem,
            stop,
            started: std::sync::atomic::AtomicBool::new(false),
        }
    }
}

impl LeastSquaresProblem for Stoppable<'_, '_> {
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
        let first = !self
            .started
            .swap(true, std::sync::atomic::Ordering::Relaxed);
        let stop = (!first).then_some(self.stop);
        self.problem.residuals_until(x, stop)
    }

    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        self.problem.jacobian(x)
    }

    fn step_residuals(&self, x: &DVector<f64>) -> Option<DVector<f64>> {
        self.problem.step_residuals(x)
    }
}
