//! Small least-squares problems the solver's tests and the fit layer's covariance tests
//! share (the latter include this file by path).

use goniofit_lm::{Closure, LeastSquaresProblem};
use nalgebra::{DMatrix, DVector};

/// A column vector of `xs`.
pub(crate) fn v(xs: &[f64]) -> DVector<f64> {
    DVector::from_column_slice(xs)
}

/// The decay problem's data: t = 0, 0.25, …, 4.75 and y = 3 e^(−0.7 t) + a deterministic
/// ±0.02 pattern.
pub(crate) fn decay_data() -> (Vec<f64>, Vec<f64>) {
    let t: Vec<f64> = (0..20).map(|i| i as f64 * 0.25).collect();
    let y = t
        .iter()
        .enumerate()
        .map(|(i, &t)| 3.0 * (-0.7 * t).exp() + 0.01 * ((i * 7 % 5) as f64 - 2.0))
        .collect();
    (t, y)
}

/// y = a·exp(−b t) + deterministic pseudo-noise: a non-zero-residual problem.
pub(crate) fn decay() -> impl LeastSquaresProblem {
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
