//! Statistics of a finished least-squares fit, from the Jacobian at the optimum.
//!
//! The Jacobian's columns are first brought to unit norm, `Ĵ = J D⁻¹` with `D = diag(‖J₍ⱼ₎‖)`
//! (a zero column stays zero), so that what is called determined does not depend on the
//! units of the data or of the parameters: `L → c·L` or a parameter in other units rescales
//! columns of `J` and leaves `Ĵ` unchanged. With `Ĵ = U Σ Vᵀ` (thin SVD, padded with zero
//! rows when `n < p`):
//! * residual variance `s² = 2·cost / (n − p) = Σ r̃ᵢ² / (n − p)` (NaN when `n ≤ p`);
//! * covariance `C = s² (JᵀJ)⁺ = s² D⁻¹ V Σ⁺² Vᵀ D⁻¹`, where singular values
//!   `σₖ ≤ rel_threshold · σ₁` are treated as zero (pseudo-inverse) — `JᵀJ` is never formed;
//!   with every `σₖ` kept this is exactly `s² (JᵀJ)⁻¹`;
//! * standard errors `√Cⱼⱼ`, correlations `Cᵢⱼ / (sᵢ sⱼ)` (NaN where a standard error is 0);
//! * condition number `σ₁ / σₚ` of `Ĵ` (∞ when `σₚ = 0`): at most √p from the best one any
//!   column scaling reaches (van der Sluis);
//! * the undetermined directions: `D⁻¹ v` for the right singular vectors `v` of the dropped
//!   singular values (normalised), i.e. parameter combinations the data do not determine.

use nalgebra::{DMatrix, DVector};

/// Covariance and identifiability from the Jacobian at the optimum.
#[derive(Debug, Clone)]
pub(crate) struct Uncertainty {
    /// `s²(JᵀJ)⁺`, `s² = 2·cost/(n−p)`.
    pub covariance: DMatrix<f64>,
    /// Standard errors √Cⱼⱼ of the free variables (the solver's x, length `p`).
    pub stderr: DVector<f64>,
    /// Correlations Cᵢⱼ/(sᵢsⱼ) (`p × p`; NaN where a standard error is 0).
    pub correlation: DMatrix<f64>,
    /// Singular values of `Ĵ` (`J` with unit-norm columns), descending (length `p`).
    pub singular_values: DVector<f64>,
    /// `σ_max / σ_min` of `Ĵ` (∞ when singular).
    pub condition: f64,
    /// Right singular vectors (unit, length `p`) of directions the data do not determine.
    pub undetermined: Vec<DVector<f64>>,
    /// Number of singular values above `rel_threshold · σ_max`.
    pub rank: usize,
    /// `s²`, the residual variance estimate.
    pub residual_variance: f64,
}

/// Covariance and identifiability of a fit: `jacobian` of the weighted residuals at the
/// optimum (`n × p`), `cost = ½ Σ r̃ᵢ²` there, `n` observations; singular values at or below
/// `rel_threshold · σ_max` count as zero (e.g. `1e-10`; a negative or NaN threshold is
/// treated as 0, i.e. only exact zeros are dropped).
pub(crate) fn uncertainty(
    jacobian: &DMatrix<f64>,
    cost: f64,
    n: usize,
    rel_threshold: f64,
) -> Uncertainty {
    let p = jacobian.ncols();
    let rel = if rel_threshold >= 0.0 {
        rel_threshold
    } else {
        0.0
    };
    let s2 = if n > p {
        2.0 * cost / (n - p) as f64
    } else {
        f64::NAN
    };
    if p == 0 {
        return Uncertainty::filled(0, 0.0, 1.0, s2);
    }
    if !jacobian.iter().all(|v| v.is_finite()) {
        return Uncertainty::filled(p, f64::NAN, f64::NAN, s2);
    }
    let (j, norms) = if jacobian.len() > REDUCE_ABOVE {
        reduced_unit_columns(jacobian)
    } else {
        let mut j = jacobian.clone();
        if j.nrows() < p {
            j = j.resize_vertically(p, 0.0);
        }
        let norms = unit_columns(&mut j);
        (j, norms)
    };
    let svd = j.svd(false, true);
    let v_t = svd.v_t.expect("SVD computed with V");
    let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
    order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
    let sv = DVector::from_iterator(p, order.iter().map(|&k| svd.singular_values[k]));
    let (smax, smin) = (sv[0], sv[p - 1]);
    let cut = rel * smax;
    let mut cov = DMatrix::zeros(p, p);
    let mut undetermined = Vec::new();
    let mut rank = 0;
    for &k in &order {
        let s = svd.singular_values[k];
        let v = v_t.row(k).transpose();
        if s > cut && s > 0.0 {
            rank += 1;
            cov += (&v * v.transpose()) * (s2 / (s * s));
        } else {
            undetermined.push(unscaled_direction(v, &norms));
        }
    }
    let cov = DMatrix::from_fn(p, p, |a, b| cov[(a, b)] / (norms[a] * norms[b]));
    let stderr = DVector::from_iterator(p, (0..p).map(|i| cov[(i, i)].max(0.0).sqrt()));
    Uncertainty {
        correlation: correlation(&cov, &stderr),
        covariance: cov,
        stderr,
        singular_values: sv,
        condition: if smin > 0.0 {
            smax / smin
        } else {
            f64::INFINITY
        },
        undetermined,
        rank,
        residual_variance: s2,
    }
}

impl Uncertainty {
    /// The uncertainty of `p` parameters with every matrix and vector entry `value`, no
    /// undetermined direction and rank 0 (no parameters, or a Jacobian that is not finite).
    fn filled(p: usize, value: f64, condition: f64, s2: f64) -> Self {
        let m = DMatrix::from_element(p, p, value);
        Uncertainty {
            covariance: m.clone(),
            stderr: DVector::from_element(p, value),
            correlation: m,
            singular_values: DVector::from_element(p, value),
            condition,
            undetermined: Vec::new(),
            rank: 0,
            residual_variance: s2,
        }
    }
}

/// The Euclidean norm of each column of `j`, 1 for a zero or non-finite one.
fn column_norms(j: &DMatrix<f64>) -> Vec<f64> {
    (0..j.ncols())
        .map(|k| {
            let d = j.column(k).norm();
            if d > 0.0 && d.is_finite() {
                d
            } else {
                1.0
            }
        })
        .collect()
}

/// Scale the columns of `j` to unit norm in place and return their norms (a zero or
/// non-finite column keeps its entries and a factor 1).
fn unit_columns(j: &mut DMatrix<f64>) -> Vec<f64> {
    let norms = column_norms(j);
    for (k, d) in norms.iter().enumerate() {
        j.column_mut(k).unscale_mut(*d);
    }
    norms
}

/// Jacobians of more entries than this (1M: 8 MB) are reduced to the `p × p` triangular
/// factor of their unit-column form before the SVD ([`reduced_unit_columns`]): no copy of
/// a big fit's `n × p` matrix. Smaller ones are copied and decomposed as they are.
const REDUCE_ABOVE: usize = 1 << 20;

/// Rows of the unit-column Jacobian stacked under the running factor per QR step.
const REDUCE_BLOCK: usize = 4096;

/// The column norms of `j` (as [`unit_columns`] takes them) and the `p × p` upper
/// triangular `R` of `Ĵ = Q R` for the unit-column `Ĵ`, accumulated block by block of rows
/// (the QR of `[R; next rows of Ĵ]` each time), so at most [`REDUCE_BLOCK`] rows are
/// copied at once. `R` has the singular values and right singular vectors of `Ĵ` (to
/// rounding: both are backward stable). `j` must have at least `p` rows.
fn reduced_unit_columns(j: &DMatrix<f64>) -> (DMatrix<f64>, Vec<f64>) {
    let (n, p) = j.shape();
    let norms = column_norms(j);
    let mut r = DMatrix::<f64>::zeros(0, p);
    let mut first = 0;
    while first < n {
        let rows = REDUCE_BLOCK.min(n - first);
        let top = r.nrows();
        let stacked = DMatrix::from_fn(top + rows, p, |i, k| {
            if i < top {
                r[(i, k)]
            } else {
                j[(first + i - top, k)] / norms[k]
            }
        });
        r = stacked.qr().r();
        first += rows;
    }
    (r, norms)
}

/// A null direction `v` of the unit-column Jacobian taken back to the parameters,
/// `D⁻¹ v` normalised (`v` itself when that has no finite length).
fn unscaled_direction(v: DVector<f64>, norms: &[f64]) -> DVector<f64> {
    let x = DVector::from_iterator(v.len(), v.iter().zip(norms).map(|(a, d)| a / d));
    let len = x.norm();
    if len > 0.0 && len.is_finite() {
        x / len
    } else {
        v
    }
}

/// Correlations `Cᵢⱼ / (sᵢ sⱼ)` of covariance `cov` with standard errors `stderr` (NaN
/// where a standard error is 0).
pub(crate) fn correlation(cov: &DMatrix<f64>, stderr: &DVector<f64>) -> DMatrix<f64> {
    DMatrix::from_fn(cov.nrows(), cov.ncols(), |a, b| {
        let d = stderr[a] * stderr[b];
        if d > 0.0 {
            cov[(a, b)] / d
        } else {
            f64::NAN
        }
    })
}

/// The solver's small test problems (goniofit-lm's tests use them too).
#[cfg(test)]
#[path = "../../../lm/src/test_problems.rs"]
mod test_problems;

#[cfg(test)]
mod tests {
    use super::test_problems::{decay, decay_data, v};
    use super::*;
    use approx::assert_relative_eq;
    use goniofit_lm::{
        finite_difference_jacobian, minimize, Closure, LeastSquaresProblem, LmConfig, Transformed,
    };
    use nalgebra::{DMatrix, DVector};

    /// Straight line y = a + b t: the textbook closed forms for the covariance,
    /// Var(b) = s²/Sₜₜ, Var(a) = s²(1/n + t̄²/Sₜₜ), Cov(a, b) = −s² t̄/Sₜₜ.
    #[test]
    fn covariance_matches_closed_form_linear_regression() {
        let t = [0.5, 1.0, 2.0, 3.5, 4.0, 6.0, 7.5];
        let y = [1.1, 1.9, 3.2, 5.1, 5.8, 8.9, 11.2];
        let n = t.len();
        let tbar = t.iter().sum::<f64>() / n as f64;
        let ybar = y.iter().sum::<f64>() / n as f64;
        let stt: f64 = t.iter().map(|&t| (t - tbar).powi(2)).sum();
        let sty: f64 = t
            .iter()
            .zip(&y)
            .map(|(&t, &y)| (t - tbar) * (y - ybar))
            .sum();
        let b = sty / stt;
        let a = ybar - b * tbar;
        let rss: f64 = t
            .iter()
            .zip(&y)
            .map(|(&t, &y)| (y - a - b * t).powi(2))
            .sum();
        let s2 = rss / (n - 2) as f64;

        let jac = DMatrix::from_fn(n, 2, |i, j| if j == 0 { 1.0 } else { t[i] });
        let u = uncertainty(&jac, 0.5 * rss, n, 1e-12);
        assert_relative_eq!(u.residual_variance, s2, max_relative = 1e-14);
        assert_relative_eq!(u.covariance[(1, 1)], s2 / stt, max_relative = 1e-12);
        assert_relative_eq!(
            u.covariance[(0, 0)],
            s2 * (1.0 / n as f64 + tbar * tbar / stt),
            max_relative = 1e-12
        );
        assert_relative_eq!(u.covariance[(0, 1)], -s2 * tbar / stt, max_relative = 1e-12);
        assert_relative_eq!(
            u.covariance[(1, 0)],
            u.covariance[(0, 1)],
            max_relative = 1e-12
        );
        assert_relative_eq!(u.stderr[1], (s2 / stt).sqrt(), max_relative = 1e-12);
        let rho = -tbar / (tbar * tbar + stt / n as f64).sqrt();
        assert_relative_eq!(u.correlation[(0, 1)], rho, max_relative = 1e-12);
        assert_relative_eq!(u.correlation[(0, 0)], 1.0, max_relative = 1e-12);
        assert_eq!(u.rank, 2);
        assert!(u.undetermined.is_empty());
        assert!(u.singular_values[0] >= u.singular_values[1]);
        assert_relative_eq!(
            u.condition,
            u.singular_values[0] / u.singular_values[1],
            max_relative = 1e-14
        );
    }

    #[test]
    fn singular_jacobian_uses_the_pseudo_inverse() {
        // Columns 0 and 2 identical: the direction (1, 0, −1)/√2 is undetermined.
        let jac = DMatrix::from_fn(6, 3, |i, j| match j {
            0 | 2 => 1.0,
            _ => i as f64,
        });
        let u = uncertainty(&jac, 1.5, 6, 1e-12);
        assert_eq!(u.rank, 2);
        assert_eq!(u.undetermined.len(), 1);
        let d = &u.undetermined[0];
        assert_relative_eq!(d[1], 0.0, epsilon = 1e-12);
        assert_relative_eq!(d[0], -d[2], epsilon = 1e-12);
        assert!(u.condition > 1e12);
        assert!(u.stderr.iter().all(|s| s.is_finite()));
        // The pseudo-inverse gives zero variance along the undetermined direction.
        let var_d = (d.transpose() * &u.covariance * d)[(0, 0)];
        assert!(var_d.abs() < 1e-12);
    }

    #[test]
    fn rank_and_errors_do_not_depend_on_column_units() {
        // A well-posed 3-parameter Jacobian, then the same with one column in units 1e10
        // smaller (e.g. a scale when L is given ×1e10) and one 1e-8: the rank, the
        // condition and the standard errors in each column's own unit are unchanged.
        let jac = DMatrix::from_fn(20, 3, |i, j| {
            let t = i as f64 / 19.0;
            [1.0, t, (3.0 * t).sin()][j]
        });
        let c = [1.0, 1e10, 1e-8];
        let scaled = DMatrix::from_fn(20, 3, |i, j| jac[(i, j)] * c[j]);
        let a = uncertainty(&jac, 0.7, 20, 1e-9);
        let b = uncertainty(&scaled, 0.7, 20, 1e-9);
        assert_eq!((a.rank, b.rank), (3, 3));
        assert!(b.undetermined.is_empty());
        assert_relative_eq!(a.condition, b.condition, max_relative = 1e-10);
        for (k, ck) in c.iter().enumerate() {
            assert_relative_eq!(a.stderr[k], b.stderr[k] * ck, max_relative = 1e-10);
        }
        // Unscaled, the 1e-9 cut would have dropped the 1e-8 column.
        let raw = nalgebra::linalg::SVD::new(scaled.clone(), false, false).singular_values;
        assert!(raw.min() < 1e-9 * raw.max());
    }

    #[test]
    fn too_few_observations_give_nan_variance() {
        let jac = DMatrix::from_row_slice(1, 2, &[1.0, 2.0]);
        let u = uncertainty(&jac, 0.0, 1, 1e-12);
        assert!(u.residual_variance.is_nan());
        assert_eq!(u.rank, 1);
        assert_eq!(u.undetermined.len(), 1);
        assert_eq!(u.singular_values.len(), 2);
    }

    /// Seeded synthetic recovery: y = a·exp(−b t) + N(0, σ²). Over 200 data sets the true
    /// values fall within 1.96 standard errors ~95 % of the time, and the standard errors
    /// match the scatter of the estimates.
    #[test]
    fn synthetic_recovery_is_calibrated() {
        use rand::SeedableRng;
        use rand_distr::{Distribution, Normal};

        struct Decay {
            t: Vec<f64>,
            y: Vec<f64>,
        }
        impl LeastSquaresProblem for Decay {
            fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
                DVector::from_iterator(
                    self.t.len(),
                    self.t
                        .iter()
                        .zip(&self.y)
                        .map(|(&t, &y)| x[0] * (-x[1] * t).exp() - y),
                )
            }
            fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
                DMatrix::from_fn(self.t.len(), 2, |i, j| {
                    let e = (-x[1] * self.t[i]).exp();
                    if j == 0 {
                        e
                    } else {
                        -x[0] * self.t[i] * e
                    }
                })
            }
        }

        let (a, b, sigma) = (2.0, 0.8, 0.05);
        let t: Vec<f64> = (0..40).map(|i| i as f64 * 0.1).collect();
        let noise = Normal::new(0.0, sigma).unwrap();
        let mut rng = rand::rngs::StdRng::seed_from_u64(20261123);
        let trials = 200;
        let (mut covered, mut est_b, mut se_b) = (0, Vec::new(), Vec::new());
        for _ in 0..trials {
            let y = t
                .iter()
                .map(|&t| a * (-b * t).exp() + noise.sample(&mut rng))
                .collect();
            let p = Decay { t: t.clone(), y };
            let rep = minimize(
                &p,
                DVector::from_column_slice(&[1.0, 1.0]),
                &LmConfig::default(),
            );
            assert!(rep.termination.converged(), "{:?}", rep.termination);
            let u = uncertainty(&rep.jacobian, rep.cost, t.len(), 1e-12);
            if (rep.x[0] - a).abs() <= 1.96 * u.stderr[0] {
                covered += 1;
            }
            est_b.push(rep.x[1]);
            se_b.push(u.stderr[1]);
        }
        let coverage = covered as f64 / trials as f64;
        assert!((0.90..=0.99).contains(&coverage), "coverage {coverage}");
        let mean = est_b.iter().sum::<f64>() / trials as f64;
        let sd =
            (est_b.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (trials - 1) as f64).sqrt();
        let se_mean = se_b.iter().sum::<f64>() / trials as f64;
        assert!(
            (sd / se_mean - 1.0).abs() < 0.15,
            "scatter {sd:e} vs stderr {se_mean:e}"
        );
        assert!((mean - b).abs() < 3.0 * sd / (trials as f64).sqrt() + 1e-3);
    }

    #[test]
    fn a_big_jacobian_reduced_to_its_r_factor_gives_the_same_uncertainty() {
        // J repeats a 6 × 3 block k times (3·6k > 2^20 entries: the reduced path), so
        // JᵀJ = k J₀ᵀJ₀: the unit-column singular values are J₀'s, the covariance at the
        // same s² is J₀'s over k.
        let j0 = DMatrix::from_row_slice(
            6,
            3,
            &[
                1.0, 0.5, -2.0, 0.3, 1.2, 0.7, -0.4, 2.0, 1.1, 2.2, -0.1, 0.4, 0.9, 0.8, -1.3,
                -1.5, 0.6, 0.2,
            ],
        );
        let k = 60_000;
        let big = DMatrix::from_fn(6 * k, 3, |i, c| j0[(i % 6, c)]);
        assert!(big.len() > REDUCE_ABOVE);
        let (n, cost) = (6 * k, 0.5 * 6.0 * k as f64);
        let ub = uncertainty(&big, cost, n, 1e-12);
        let s2 = 2.0 * cost / (n - 3) as f64;
        let u0 = uncertainty(&j0, 0.5 * s2 * 3.0, 6, 1e-12);
        for c in 0..3 {
            assert_relative_eq!(
                ub.singular_values[c],
                u0.singular_values[c],
                max_relative = 1e-12
            );
            assert_relative_eq!(
                ub.covariance[(c, c)] * k as f64,
                u0.covariance[(c, c)],
                max_relative = 1e-12
            );
        }
        assert_relative_eq!(ub.condition, u0.condition, max_relative = 1e-12);
        assert_relative_eq!(
            ub.correlation[(0, 2)],
            u0.correlation[(0, 2)],
            max_relative = 1e-11
        );
        assert_eq!(ub.rank, 3);
    }

    #[test]
    fn rank_deficient_jacobian() {
        // r = (a + b)·t − 2t + noise: only a + b is determined.
        let t: Vec<f64> = (1..=5).map(|i| i as f64).collect();
        let noise = [0.01, -0.02, 0.0, 0.015, -0.005];
        let p = Closure {
            r: |x: &DVector<f64>| {
                DVector::from_iterator(
                    5,
                    (0..5).map(|i| (x[0] + x[1]) * t[i] - 2.0 * t[i] + noise[i]),
                )
            },
            j: |_: &DVector<f64>| DMatrix::from_fn(5, 2, |i, _| t[i]),
        };
        let rep = minimize(&p, v(&[5.0, -7.0]), &LmConfig::default());
        assert!(rep.termination.converged(), "{:?}", rep.termination);
        let sum_ls = 2.0 - (0..5).map(|i| noise[i] * t[i]).sum::<f64>() / 55.0;
        assert_relative_eq!(rep.x[0] + rep.x[1], sum_ls, epsilon = 1e-12);
        assert!(rep.x.iter().all(|v| v.is_finite()));
        let u = uncertainty(&rep.jacobian, rep.cost, 5, 1e-10);
        assert_eq!(u.rank, 1);
        assert!(u.condition.is_infinite() || u.condition > 1e14);
        assert_eq!(u.undetermined.len(), 1);
        let d = &u.undetermined[0];
        assert_relative_eq!(d[0].abs(), std::f64::consts::FRAC_1_SQRT_2, epsilon = 1e-12);
        assert_relative_eq!(d[0], -d[1], epsilon = 1e-12);
        // Pseudo-inverse: the determined combination a + b has variance s²/Σt², the
        // undetermined one a − b gets none.
        let s2 = 2.0 * rep.cost / 3.0;
        let var_sum = u.covariance.sum();
        assert_relative_eq!(var_sum, s2 / 55.0, max_relative = 1e-10);
    }

    #[test]
    fn transformed_log_and_fixed_parameters() {
        // Inner parameters (a, b, c) of y = a·exp(−b t) + c, with c fixed at 0 and b on a
        // log scale: the fit must match the direct two-parameter fit.
        let (t, y) = decay_data();
        let inner = Closure {
            r: |x: &DVector<f64>| {
                DVector::from_iterator(
                    t.len(),
                    t.iter()
                        .zip(&y)
                        .map(|(&t, &y)| x[0] * (-x[1] * t).exp() + x[2] - y),
                )
            },
            j: |x: &DVector<f64>| {
                let mut j = DMatrix::zeros(t.len(), 3);
                for (i, &t) in t.iter().enumerate() {
                    let e = (-x[1] * t).exp();
                    j[(i, 0)] = e;
                    j[(i, 1)] = -x[0] * t * e;
                    j[(i, 2)] = 1.0;
                }
                j
            },
        };
        let tr =
            Transformed::new(inner, vec![false, true, false], vec![None, None, Some(0.0)]).unwrap();
        assert_eq!(tr.n_free(), 2);
        assert_eq!(tr.free_indices(), &[0, 1]);
        let z0 = tr.to_free(&v(&[1.0, 0.1, 123.0])).unwrap();
        assert_relative_eq!(z0[1], 0.1f64.ln());
        // Chain rule against finite differences.
        let jz = tr.jacobian(&z0);
        let jn = finite_difference_jacobian(|z| tr.residuals(z), &z0, None);
        assert!((&jz - &jn).amax() < 1e-8 * jz.amax());
        let rep_z = minimize(&tr, z0, &LmConfig::default());
        let rep_x = minimize(&decay(), v(&[1.0, 0.1]), &LmConfig::default());
        let x = tr.to_full(&rep_z.x);
        assert_relative_eq!(x[0], rep_x.x[0], epsilon = 1e-8);
        assert_relative_eq!(x[1], rep_x.x[1], epsilon = 1e-8);
        assert_eq!(x[2], 0.0);
        // Delta method: the covariance of (a, b) equals the direct fit's.
        let uz = uncertainty(&rep_z.jacobian, rep_z.cost, 20, 1e-12);
        let ux = uncertainty(&rep_x.jacobian, rep_x.cost, 20, 1e-12);
        let cx = tr.covariance_to_full(&rep_z.x, &uz.covariance);
        assert_eq!(cx.shape(), (3, 3));
        for i in 0..2 {
            for j in 0..2 {
                assert_relative_eq!(cx[(i, j)], ux.covariance[(i, j)], max_relative = 1e-6);
            }
        }
        assert_eq!(cx[(2, 2)], 0.0);
        assert!(tr.to_free(&v(&[1.0, -0.1, 0.0])).is_err());
        assert!(Transformed::new((), vec![true], vec![Some(-1.0)]).is_err());
        assert!(Transformed::new((), vec![true, false], vec![None]).is_err());
    }
}
