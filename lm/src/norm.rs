//! Norms and small vector helpers shared by the solver's parts.

use nalgebra::{DMatrix, DVector};

/// Length from which [`dot`] sums in four lanes.
const LANE_SUM_MIN: usize = 1024;

/// Euclidean norm without destructive overflow or underflow (MINPACK `enorm` in spirit):
/// the plain sum of squares when that is safely in range, a scaled sum otherwise.
pub(super) fn enorm(v: &[f64]) -> f64 {
    const SMALL: f64 = 1e-150;
    const LARGE: f64 = 1e150;
    let s = dot(v, v);
    if s.is_finite() && s > SMALL * SMALL && s < LARGE * LARGE {
        return s.sqrt();
    }
    let amax = v.iter().fold(0.0f64, |a, &x| a.max(x.abs()));
    if amax == 0.0 || !amax.is_finite() {
        return if s.is_nan() { f64::NAN } else { amax };
    }
    let s: f64 = v.iter().map(|&x| (x / amax) * (x / amax)).sum();
    amax * s.sqrt()
}

/// Σ aᵢbᵢ over the common length. Long vectors (≥ [`LANE_SUM_MIN`]) are summed in four
/// interleaved partial sums (independent chains, so a 10k-row column is not bound by the
/// latency of one addition per element); shorter ones in order, as MINPACK does.
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    if a.len().min(b.len()) < LANE_SUM_MIN {
        return a.iter().zip(b).map(|(x, y)| x * y).sum();
    }
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// `v` padded with zeros to at least `rows` entries (for `m < n` problems).
pub(super) fn pad_vec(v: DVector<f64>, rows: usize) -> DVector<f64> {
    if v.len() >= rows {
        v
    } else {
        v.resize_vertically(rows, 0.0)
    }
}

/// `a` padded with zero rows to at least `rows` rows (for `m < n` problems).
pub(super) fn pad_mat(a: DMatrix<f64>, rows: usize) -> DMatrix<f64> {
    if a.nrows() >= rows {
        a
    } else {
        a.resize_vertically(rows, 0.0)
    }
}

/// Whether every entry is finite.
pub(super) fn all_finite(v: &DVector<f64>) -> bool {
    v.iter().all(|x| x.is_finite())
}
