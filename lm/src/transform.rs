//! Positivity and fixed parameters: the problem the solver sees over the free parameters.

use nalgebra::{DMatrix, DVector};

use super::{Invalid, LeastSquaresProblem};

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
    pub fn new(inner: P, log_mask: Vec<bool>, fixed: Vec<Option<f64>>) -> Result<Self, Invalid> {
        if log_mask.len() != fixed.len() {
            return Err(Invalid::new(
                "fixed",
                format!(
                    "{} entries but log_mask has {}; give one per parameter",
                    fixed.len(),
                    log_mask.len()
                ),
            ));
        }
        for (j, f) in fixed.iter().enumerate() {
            if let Some(v) = f {
                if !v.is_finite() || (log_mask[j] && *v <= 0.0) {
                    return Err(Invalid::new(
                        format!("#{j}"),
                        format!(
                            "fixed value {v} is not allowed (must be finite{})",
                            if log_mask[j] { " and > 0" } else { "" }
                        ),
                    ));
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
    pub fn to_free(&self, x: &DVector<f64>) -> Result<DVector<f64>, Invalid> {
        if x.len() != self.n_full() {
            return Err(Invalid::new(
                "x",
                format!("expected {} parameters, got {}", self.n_full(), x.len()),
            ));
        }
        let mut z = DVector::zeros(self.free.len());
        for (k, &j) in self.free.iter().enumerate() {
            z[k] = if self.log_mask[j] {
                if x[j].is_nan() || x[j] <= 0.0 {
                    return Err(Invalid::new(
                        format!("#{j}"),
                        format!("{} must be > 0 (it is fitted on a log scale)", x[j]),
                    ));
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

    fn step_residuals(&self, z: &DVector<f64>) -> Option<DVector<f64>> {
        self.inner.step_residuals(&self.to_full(z))
    }
}
