//! The pivoted QR factorisation of the Jacobian and the regularised least-squares solve
//! (MINPACK `qrfac` and `qrsolv`).

use nalgebra::{DMatrix, DVector};

use super::norm::{dot, enorm};
use super::EPSMCH;

/// The pivoted QR of the Jacobian at the current point, and what `lmpar` needs.
#[derive(Debug, Clone)]
pub(super) struct QrState {
    /// `n × n`: `R` in the upper triangle; the strict lower triangle is workspace for `qrsolv`.
    pub(super) r: DMatrix<f64>,
    /// Column `j` of `R` is column `ipvt[j]` of `J`.
    pub(super) ipvt: Vec<usize>,
    /// First `n` components of `Qᵀ r`.
    pub(super) qtf: DVector<f64>,
}

/// ‖J p‖ for a step p, from the pivoted QR of J (‖Q R Pᵀ p‖ = ‖R Pᵀ p‖).
pub(super) fn jp_norm(qr: &QrState, step: &DVector<f64>) -> f64 {
    let n = step.len();
    let mut jp = DVector::zeros(n);
    for j in 0..n {
        let t = step[qr.ipvt[j]];
        for i in 0..=j {
            jp[i] += qr.r[(i, j)] * t;
        }
    }
    enorm(jp.as_slice())
}

/// Householder QR with column pivoting (MINPACK `qrfac` with `pivot = true`) of `a`
/// (`m × n`, `m ≥ n`), factored in its own storage (the caller passes a copy if it needs
/// `a` again). Returns `R` (`n × n`, upper), the pivots, the column norms of `a`, and `Qᵀ f`
/// (first `n` components). The norms of the remaining partial columns that drive the
/// pivoting are down-dated as in MINPACK and recomputed whenever the down-dating has lost
/// more than half the digits.
pub(super) fn qrfac(mut a: DMatrix<f64>, f: &DVector<f64>) -> (QrState, DVector<f64>) {
    let (m, n) = a.shape();
    // Column-major: column k is cols[k*m .. (k+1)*m].
    let cols: &mut [f64] = a.as_mut_slice();
    let mut qtf: Vec<f64> = f.as_slice().to_vec();
    let acnorm = DVector::from_iterator(n, (0..n).map(|j| enorm(&cols[j * m..(j + 1) * m])));
    let mut rdiag: Vec<f64> = acnorm.iter().copied().collect();
    let mut wa = rdiag.clone();
    let mut ipvt: Vec<usize> = (0..n).collect();
    for j in 0..n.min(m) {
        // Pivot: the remaining column of largest partial norm goes to position j.
        let mut kmax = j;
        for k in j..n {
            if rdiag[k] > rdiag[kmax] {
                kmax = k;
            }
        }
        if kmax != j {
            for i in 0..m {
                cols.swap(j * m + i, kmax * m + i);
            }
            rdiag[kmax] = rdiag[j];
            wa[kmax] = wa[j];
            ipvt.swap(j, kmax);
        }
        let (head, tail) = cols.split_at_mut((j + 1) * m);
        let cj = &mut head[j * m + j..(j + 1) * m];
        let ajnorm = reflector(cj);
        if ajnorm != 0.0 {
            // Apply the reflector to the remaining columns and to f.
            for k in j + 1..n {
                let ck = &mut tail[(k - j - 1) * m + j..(k - j) * m];
                reflect(cj, ck);
                if rdiag[k] != 0.0 {
                    let t = ck[0] / rdiag[k];
                    rdiag[k] *= (1.0 - t * t).max(0.0).sqrt();
                    if 0.05 * (rdiag[k] / wa[k]).powi(2) <= EPSMCH {
                        rdiag[k] = enorm(&ck[1..]);
                        wa[k] = rdiag[k];
                    }
                }
            }
            reflect(cj, &mut qtf[j..m]);
        }
        rdiag[j] = -ajnorm;
    }
    let mut r = DMatrix::zeros(n, n);
    for j in 0..n {
        for i in 0..j {
            r[(i, j)] = cols[j * m + i];
        }
        r[(j, j)] = rdiag[j];
    }
    let qtf = DVector::from_column_slice(&qtf[..n]);
    (QrState { r, ipvt, qtf }, acnorm)
}

/// Turn column `v` (its part from the diagonal down) into the Householder vector that
/// maps it to (−α, 0, …) and return α = ±‖v‖ (the sign of v₀); 0 leaves `v` unchanged.
/// The vector is scaled so that its first entry is 1 + |v₀|/‖v‖ (MINPACK's qrfac).
pub(super) fn reflector(v: &mut [f64]) -> f64 {
    let mut norm = enorm(v);
    if norm == 0.0 {
        return 0.0;
    }
    if v[0] < 0.0 {
        norm = -norm;
    }
    for x in v.iter_mut() {
        *x /= norm;
    }
    v[0] += 1.0;
    norm
}

/// Apply the reflection of Householder vector `v` ([`reflector`]) to `c`.
pub(super) fn reflect(v: &[f64], c: &mut [f64]) {
    let t = dot(v, c) / v[0];
    for (x, &a) in c.iter_mut().zip(v.iter()) {
        *x -= t * a;
    }
}

/// MINPACK `qrsolv`: given the pivoted QR `J P = Q R` and a diagonal `d`, solve
/// `min ‖[J; D] x − [b; 0]‖` where `qtb = (Qᵀ b)[..n]`. On return the strict lower triangle of
/// `r` holds the strict upper triangle of `S` (transposed), with `Pᵀ(JᵀJ + DD)P = SᵀS`, and
/// `sdiag` the diagonal of `S`. The upper triangle of `r` is unchanged.
pub(super) fn qrsolv(
    r: &mut DMatrix<f64>,
    ipvt: &[usize],
    d: &DVector<f64>,
    qtb: &DVector<f64>,
    x: &mut DVector<f64>,
    sdiag: &mut DVector<f64>,
) {
    let n = r.ncols();
    let mut wa = qtb.clone();
    for j in 0..n {
        for i in j..n {
            r[(i, j)] = r[(j, i)];
        }
        x[j] = r[(j, j)];
    }
    for j in 0..n {
        let l = ipvt[j];
        if d[l] != 0.0 {
            for k in j..n {
                sdiag[k] = 0.0;
            }
            sdiag[j] = d[l];
            let mut qtbpj = 0.0;
            for k in j..n {
                if sdiag[k] == 0.0 {
                    continue;
                }
                let (sin, cos) = if r[(k, k)].abs() < sdiag[k].abs() {
                    let cotan = r[(k, k)] / sdiag[k];
                    let sin = 0.5 / (0.25 + 0.25 * cotan * cotan).sqrt();
                    (sin, sin * cotan)
                } else {
                    let tan = sdiag[k] / r[(k, k)];
                    let cos = 0.5 / (0.25 + 0.25 * tan * tan).sqrt();
                    (cos * tan, cos)
                };
                r[(k, k)] = cos * r[(k, k)] + sin * sdiag[k];
                let temp = cos * wa[k] + sin * qtbpj;
                qtbpj = -sin * wa[k] + cos * qtbpj;
                wa[k] = temp;
                for i in k + 1..n {
                    let temp = cos * r[(i, k)] + sin * sdiag[i];
                    sdiag[i] = -sin * r[(i, k)] + cos * sdiag[i];
                    r[(i, k)] = temp;
                }
            }
        }
        sdiag[j] = r[(j, j)];
        r[(j, j)] = x[j];
    }
    // Solve S z = wa; a singular S gives the least-squares solution with trailing zeros.
    let mut nsing = n;
    for j in 0..n {
        if sdiag[j] == 0.0 && nsing == n {
            nsing = j;
        }
        if nsing < n {
            wa[j] = 0.0;
        }
    }
    for j in (0..nsing).rev() {
        let mut sum = 0.0;
        for i in j + 1..nsing {
            sum += r[(i, j)] * wa[i];
        }
        wa[j] = (wa[j] - sum) / sdiag[j];
    }
    for j in 0..n {
        x[ipvt[j]] = wa[j];
    }
}
