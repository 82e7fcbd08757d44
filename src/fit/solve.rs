//! Solve: one Levenberg–Marquardt run of a problem from a point in parameter space.

use super::lm::{self, LmConfig};
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
    let lm = lm::minimize(problem, x0, config);
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
