//! A Jacobian reduced to `n` rows as it is evaluated: for a problem of many residuals the
//! solver needs only the triangular factor of `J` and the first `n` components of `Qᵀ f`,
//! which row blocks of `J` and `f` update one after the other, so the `m × n` Jacobian is
//! never held.

use nalgebra::{DMatrix, DVector};

use super::qr::{reflect, reflector};

/// A matrix `A` (`k × n`; `k ≤ n` when built by [`Reduced::push_rows`]) and a vector `b`
/// (length `k`) standing for an `m × n` Jacobian `J` and residuals `f`: `J = Q₁ A` and
/// `b = Q₁ᵀ f` for some `m × k` matrix `Q₁` with orthonormal columns whose range holds
/// the columns of `J`. Then `AᵀA = JᵀJ`, `Aᵀb = Jᵀf`, and the least-squares problems
/// `min ‖J p + f‖` and `min ‖A p + b‖` have the same solutions. Built block by block of
/// rows with Householder reflections (the blocked QR is backward stable: `A` is the
/// triangular factor of `J` to a few ulps of `‖J‖` per column).
#[derive(Debug, Clone, PartialEq)]
pub struct Reduced {
    /// `A`: upper trapezoidal after [`Reduced::push_rows`].
    pub a: DMatrix<f64>,
    /// `b = Q₁ᵀ f`.
    pub b: DVector<f64>,
}

impl Reduced {
    /// No rows yet, `n` columns.
    pub fn empty(n: usize) -> Reduced {
        Reduced {
            a: DMatrix::zeros(0, n),
            b: DVector::zeros(0),
        }
    }

    /// Number of columns `n`.
    pub fn ncols(&self) -> usize {
        self.a.ncols()
    }

    /// Add `rows` rows of the Jacobian (`block`, column-major `rows × n`) with their
    /// residuals `f` (length `rows`): `A` and `b` become the triangular factor and the
    /// transformed residuals of `[A; block]` and `[b; f]`.
    pub fn push_rows(&mut self, block: &[f64], f: &[f64]) {
        let n = self.ncols();
        let rows = f.len();
        assert_eq!(
            block.len(),
            rows * n,
            "block of {rows} rows and {n} columns"
        );
        let top = self.a.nrows();
        let m = top + rows;
        // The stacked [A; block] and [b; f], column-major.
        let mut s = vec![0.0; m * n];
        for k in 0..n {
            for i in 0..top {
                s[k * m + i] = self.a[(i, k)];
            }
            s[k * m + top..(k + 1) * m].copy_from_slice(&block[k * rows..(k + 1) * rows]);
        }
        let mut t: Vec<f64> = self.b.iter().chain(f).copied().collect();
        householder(&mut s, &mut t, m, n);
        let k = m.min(n);
        self.a = DMatrix::from_fn(k, n, |i, j| if i <= j { s[j * m + i] } else { 0.0 });
        self.b = DVector::from_column_slice(&t[..k]);
    }

    /// Add another reduction's rows (`other` stands for rows below this one's).
    pub fn push(&mut self, other: &Reduced) {
        self.push_rows(other.a.as_slice(), other.b.as_slice());
    }

    /// `Jᵀ f = Aᵀ b`.
    pub fn gradient(&self) -> DVector<f64> {
        self.a.tr_mul(&self.b)
    }
}

/// Unpivoted Householder QR of the column-major `m × n` matrix `s` in place (`R` in its
/// upper triangle), with the reflections applied to `t` (`Qᵀ t`).
fn householder(s: &mut [f64], t: &mut [f64], m: usize, n: usize) {
    for j in 0..m.min(n) {
        let (head, tail) = s.split_at_mut((j + 1) * m);
        let v = &mut head[j * m + j..(j + 1) * m];
        let norm = reflector(v);
        if norm == 0.0 {
            continue;
        }
        for k in j + 1..n {
            reflect(v, &mut tail[(k - j - 1) * m + j..(k - j) * m]);
        }
        reflect(v, &mut t[j..m]);
        // The column becomes (−norm, 0, …): only its diagonal is kept.
        v[0] = -norm;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lmpar::lmpar;
    use crate::qr::{qrfac, qrsolv};

    /// Uniform values in [−1, 1) from a fixed seed (a linear congruential generator).
    fn values(seed: u64, len: usize) -> Vec<f64> {
        let mut s = seed;
        (0..len)
            .map(|_| {
                s = s
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (s >> 11) as f64 / (1u64 << 52) as f64 - 1.0
            })
            .collect()
    }

    /// A tall `m × n` matrix with columns of very different scales; with `rank < n` its
    /// last columns are combinations of the first `rank`.
    fn tall(seed: u64, m: usize, n: usize, rank: usize) -> DMatrix<f64> {
        let v = values(seed, m * n);
        let mut j = DMatrix::from_fn(m, n, |i, k| v[k * m + i] * 10f64.powi(k as i32 - 1));
        for k in rank..n {
            let comb = j.column(0) * 0.5 - j.column(rank - 1) * 2.0;
            j.set_column(k, &comb);
        }
        j
    }

    /// `J` and `f` pushed in blocks of `block` rows.
    fn reduce(j: &DMatrix<f64>, f: &DVector<f64>, block: usize) -> Reduced {
        let (m, n) = j.shape();
        let mut red = Reduced::empty(n);
        let mut first = 0;
        while first < m {
            let rows = block.min(m - first);
            let part = j.rows(first, rows).into_owned();
            let mut one = Reduced::empty(n);
            one.push_rows(part.as_slice(), &f.as_slice()[first..first + rows]);
            red.push(&one);
            first += rows;
        }
        red
    }

    /// The LM step (`lmpar`) for trust radius `delta` from the pivoted QR of `a` with `b`,
    /// and the Levenberg parameter found.
    fn step(a: DMatrix<f64>, b: &DVector<f64>, delta: f64) -> (DVector<f64>, f64) {
        let n = a.ncols();
        let (mut qr, acnorm) = qrfac(a, b);
        let diag = acnorm.map(|d| if d == 0.0 { 1.0 } else { d });
        let mut par = 0.0;
        let mut x = DVector::zeros(n);
        lmpar(&mut qr, &diag, delta, &mut par, &mut x);
        (x, par)
    }

    /// The damped step for a given Levenberg parameter `par` > 0 (`qrsolv` with
    /// `D = √par · diag(column norms)`) from the pivoted QR of `a` with `b`.
    fn damped(a: DMatrix<f64>, b: &DVector<f64>, par: f64) -> DVector<f64> {
        let n = a.ncols();
        let (mut qr, acnorm) = qrfac(a, b);
        let d = acnorm.map(|d| par.sqrt() * if d == 0.0 { 1.0 } else { d });
        let (mut x, mut sdiag) = (DVector::zeros(n), DVector::zeros(n));
        qrsolv(&mut qr.r, &qr.ipvt, &d, &qr.qtf, &mut x, &mut sdiag);
        x
    }

    fn assert_close(a: &DVector<f64>, b: &DVector<f64>, tol: f64) {
        let scale = a.norm().max(b.norm());
        assert!((a - b).norm() <= tol * scale, "{a} vs {b}");
    }

    #[test]
    fn reduced_jacobian_has_the_dense_gram_matrix_gradient_and_steps() {
        for (seed, m, n, rank, block) in [
            (1, 5000, 3, 3, 1024),
            (2, 777, 4, 4, 100),
            (3, 3000, 5, 3, 512),
            (4, 9, 3, 3, 2),
            (5, 2000, 3, 2, 333),
        ] {
            let j = tall(seed, m, n, rank);
            let f = DVector::from_vec(values(seed + 100, m));
            let red = reduce(&j, &f, block);
            assert_eq!(red.a.shape(), (n, n));
            let gram = j.tr_mul(&j);
            let diff = (red.a.tr_mul(&red.a) - &gram).norm();
            assert!(
                diff <= 1e-12 * gram.norm(),
                "seed {seed}: Gram off by {diff}"
            );
            assert_close(&red.gradient(), &j.tr_mul(&f), 1e-12);
            // ‖f‖² = ‖b‖² + the part of f outside J's range: never less.
            assert!(red.b.norm() <= f.norm() * (1.0 + 1e-12));
            // The damped steps for a given λ > 0 agree, rank-deficient or not.
            for par in [1e-6, 1e-2, 1.0] {
                let dense = damped(j.clone(), &f, par);
                assert_close(&damped(red.a.clone(), &red.b, par), &dense, 1e-10);
            }
            // On full rank, so do the steps `lmpar` chooses for a short trust radius
            // (λ > 0) and a long one (the Gauss–Newton step), and their λ.
            if rank < n {
                continue;
            }
            for delta in [1e-3, 1e6] {
                let (dense, par_dense) = step(j.clone(), &f, delta);
                let (reduced, par_reduced) = step(red.a.clone(), &red.b, delta);
                assert_close(&reduced, &dense, 1e-10);
                assert!((par_reduced - par_dense).abs() <= 1e-9 * par_dense.abs().max(1e-300));
            }
        }
    }

    #[test]
    fn fewer_rows_than_columns_keep_every_row() {
        let j = tall(7, 2, 3, 3);
        let f = DVector::from_vec(values(8, 2));
        let red = reduce(&j, &f, 1);
        assert_eq!(red.a.shape(), (2, 3));
        let diff = (red.a.tr_mul(&red.a) - j.tr_mul(&j)).norm();
        assert!(diff <= 1e-12 * j.norm().powi(2));
        assert!((red.b.norm() - f.norm()).abs() <= 1e-12 * f.norm());
    }
}
