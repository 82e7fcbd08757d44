//! A least-squares problem given by two closures.

use super::LeastSquaresProblem;
use nalgebra::{DMatrix, DVector};

/// A problem from closures: `r` gives the weighted residuals at x, `j` their Jacobian
/// (one row per residual, one column per parameter).
pub struct Closure<R, J> {
    /// The residuals r̃(x).
    pub r: R,
    /// The Jacobian ∂r̃/∂x.
    pub j: J,
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
