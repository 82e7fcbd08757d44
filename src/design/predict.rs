//! The linearised prediction of a design: the Fisher information of a set of samples and
//! the standard errors it implies.
//!
//! The design's variables are x = ln p for the positive parameters (every parameter of the
//! goniofit models) and x = p otherwise, so that a standard error in x is a relative error
//! and the information does not depend on the units of L, σ or T. A sample i contributes
//! the row gᵢ = (∂fᵢ/∂x) / sᵢ, sᵢ the standard deviation of its residual under the noise
//! model ([`NoiseModel`]); the information of a set of samples is F = Σ gᵢ gᵢᵀ, and the
//! linearised covariance of x̂ is its pseudo-inverse F⁺: a direction whose information is
//! (numerically) zero is reported as undetermined, never as a finite error bar.

use crate::error::{Error, Result};
use crate::fit::problem::ResidualKind;
use crate::geometry::Geometry;
use crate::model::Model;
use nalgebra::{DMatrix, DVector};

/// Eigenvalues of the Jacobi-scaled information at or below this fraction of the largest
/// count as zero (the singular-value threshold of the fit's statistics, 1e-6, squared).
pub(crate) const NULL_EIGENVALUE: f64 = 1e-12;

/// The noise of one residual: the fit's residual kind and its standard deviation ε.
///
/// * `Absolute`: y = f + ε z, ε in the unit of L (or of the BRDF);
/// * `Relative`: y = f (1 + ε z), ε a fraction (0.01 = 1 %);
/// * `Log`: ln y = ln f + ε z.
///
/// Relative and log noise carry the same information to first order: ∂r/∂x = ∂ ln f/∂x.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NoiseModel {
    /// The residual kind the noise lives in (absolute, relative or log).
    pub kind: ResidualKind,
    /// The standard deviation ε of one residual: in the unit of L (absolute) or a fraction
    /// (relative, log).
    pub level: f64,
}

impl NoiseModel {
    /// A noise model; the level must be finite and positive.
    pub fn new(kind: ResidualKind, level: f64) -> Result<NoiseModel> {
        if !(level.is_finite() && level > 0.0) {
            return Err(Error::Usage(format!(
                "noise level {level} must be finite and positive"
            )));
        }
        Ok(NoiseModel { kind, level })
    }

    /// The standard deviation of the residual of a sample of model value `f`, in the unit
    /// the residual row is divided by: ε for absolute noise, ε·f for relative and log noise
    /// (None where f is not a positive finite number: such a sample carries no information).
    pub fn sd_of(&self, f: f64) -> Option<f64> {
        match self.kind {
            ResidualKind::Absolute => f.is_finite().then_some(self.level),
            _ => (f.is_finite() && f > 0.0).then_some(self.level * f),
        }
    }
}

/// The information rows of a set of samples: their model values and rows gᵢ.
#[derive(Debug, Clone)]
pub(crate) struct Rows {
    /// The model value of each sample (the measured quantity).
    pub value: Vec<f64>,
    /// n × q: row i is gᵢ in the design's variables (zero for a sample without information).
    pub rows: DMatrix<f64>,
}

/// The rows gᵢ of the samples of `geo` for `model` at `params`: model parameter j feeds the
/// design variable `map[j]` of `q`. `positive[j]` says whether parameter j is taken in log
/// space. A sample whose value or derivatives are not finite gets a zero row.
pub(crate) fn information_rows(
    model: &dyn Model,
    params: &[f64],
    geo: &Geometry,
    noise: NoiseModel,
    map: &[usize],
    q: usize,
) -> Rows {
    let n = geo.len();
    let np = params.len();
    let mut value = vec![0.0; n];
    let mut jac = vec![0.0; n * np];
    if n > 0 {
        model.eval(geo, params, &mut value, Some(&mut jac));
    }
    let specs = model.params();
    let mut rows = DMatrix::zeros(n, q);
    for i in 0..n {
        let Some(sd) = noise.sd_of(value[i]) else {
            continue;
        };
        let row: Vec<f64> = (0..np)
            .map(|j| {
                let dx = if specs[j].positive { params[j] } else { 1.0 };
                jac[j * n + i] * dx / sd
            })
            .collect();
        if row.iter().all(|v| v.is_finite()) {
            for (j, v) in row.into_iter().enumerate() {
                rows[(i, map[j])] += v;
            }
        }
    }
    Rows { value, rows }
}

/// F = Σ gᵢ gᵢᵀ of the given rows (q × q).
pub(crate) fn information(rows: &DMatrix<f64>) -> DMatrix<f64> {
    rows.transpose() * rows
}

/// The linearised covariance of the design variables: the pseudo-inverse of the
/// information, and the directions it leaves undetermined.
#[derive(Debug, Clone)]
pub(crate) struct Covariance {
    /// F⁺ (q × q).
    pub cov: DMatrix<f64>,
    /// Unit vectors (in the design variables) of the directions with no information.
    pub null: Vec<DVector<f64>>,
}

/// F⁺ with eigenvalues of the Jacobi-scaled D⁻¹FD⁻¹ (D = √diag F) at or below
/// [`NULL_EIGENVALUE`] × the largest treated as zero; a variable with no information at
/// all is a null direction by itself. Non-finite information gives every direction null.
pub(crate) fn covariance(f: &DMatrix<f64>) -> Covariance {
    let q = f.nrows();
    if !f.iter().all(|v| v.is_finite()) {
        return Covariance {
            cov: DMatrix::zeros(q, q),
            null: (0..q).map(|k| unit(q, k)).collect(),
        };
    }
    let d: Vec<f64> = (0..q)
        .map(|k| {
            let v = f[(k, k)].max(0.0).sqrt();
            if v > 0.0 {
                v
            } else {
                1.0
            }
        })
        .collect();
    let scaled = DMatrix::from_fn(q, q, |a, b| f[(a, b)] / (d[a] * d[b]));
    let eig = nalgebra::SymmetricEigen::new(scaled);
    let largest = eig.eigenvalues.iter().fold(0.0f64, |m, v| m.max(*v));
    let mut cov = DMatrix::zeros(q, q);
    let mut null = Vec::new();
    for k in 0..q {
        let lambda = eig.eigenvalues[k];
        let v = eig.eigenvectors.column(k).into_owned();
        if lambda > NULL_EIGENVALUE * largest && lambda > 0.0 {
            cov += &v * v.transpose() / lambda;
        } else {
            let back = DVector::from_iterator(q, v.iter().zip(&d).map(|(a, s)| a / s));
            let len = back.norm();
            null.push(if len > 0.0 { back / len } else { v });
        }
    }
    let cov = DMatrix::from_fn(q, q, |a, b| cov[(a, b)] / (d[a] * d[b]));
    Covariance { cov, null }
}

fn unit(q: usize, k: usize) -> DVector<f64> {
    let mut v = DVector::zeros(q);
    v[k] = 1.0;
    v
}

impl Covariance {
    /// The standard error of cᵀx, or None when c has a component along an undetermined
    /// direction (more than 1e-6 of its length) or the variance is not finite.
    pub(crate) fn se(&self, c: &DVector<f64>) -> Option<f64> {
        let len = c.norm();
        if self.null.iter().any(|v| v.dot(c).abs() > 1e-6 * len) {
            return None;
        }
        let var = (c.transpose() * &self.cov * c)[(0, 0)];
        (var.is_finite() && var >= 0.0).then(|| var.sqrt())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn covariance_of_a_diagonal_information_is_its_inverse() {
        let f = DMatrix::from_diagonal(&DVector::from_vec(vec![4.0, 100.0]));
        let c = covariance(&f);
        assert!(c.null.is_empty());
        assert!((c.se(&unit(2, 0)).unwrap() - 0.5).abs() < 1e-12);
        assert!((c.se(&unit(2, 1)).unwrap() - 0.1).abs() < 1e-12);
    }

    #[test]
    fn a_ridge_leaves_only_the_determined_combination() {
        // Rows that see only x0 − x1: the difference is determined, each alone is not.
        let rows = DMatrix::from_row_slice(3, 2, &[1.0, -1.0, 2.0, -2.0, -1.0, 1.0]);
        let c = covariance(&information(&rows));
        assert_eq!(c.null.len(), 1);
        assert_eq!(c.se(&unit(2, 0)), None);
        let diff = DVector::from_vec(vec![1.0, -1.0]);
        // F = 6 d dᵀ with d = (1, −1): var(dᵀx) = (dᵀd)² / (6 (dᵀd)²) = 1/6.
        assert!((c.se(&diff).unwrap() - (1.0f64 / 6.0).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn relative_noise_needs_a_positive_value() {
        let n = NoiseModel::new(ResidualKind::Relative, 0.01).unwrap();
        assert_eq!(n.sd_of(2.0), Some(0.02));
        assert_eq!(n.sd_of(0.0), None);
        assert!(NoiseModel::new(ResidualKind::Log, f64::NAN).is_err());
    }
}
