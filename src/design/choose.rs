//! Choosing the next samples: greedy, then Fedorov exchange, on the information of the
//! samples already measured.
//!
//! The objective is the target's linearised variance cᵀM⁻¹c (c-optimal design) or −ln det M
//! (D-optimal: every parameter at once), with M the information of the measured and the
//! chosen samples plus a weak prior ([`PRIOR_SD`] in every design variable), so that a
//! design whose samples leave a direction undetermined still has a finite objective to
//! improve. Adding a sample of row g changes the objective by a rank-one update:
//! cᵀ(M + ggᵀ)⁻¹c = cᵀM⁻¹c − (cᵀM⁻¹g)²/(1 + gᵀM⁻¹g) and
//! ln det(M + ggᵀ) = ln det M + ln(1 + gᵀM⁻¹g).

use nalgebra::{DMatrix, DVector};

/// Prior standard deviation of every design variable (ln p for the positive parameters):
/// a factor e¹⁰ either way, far looser than anything a design reports as determined, so it
/// only matters where the data has no information at all.
pub(crate) const PRIOR_SD: f64 = 10.0;

/// Most passes of the exchange over the chosen samples.
const EXCHANGE_PASSES: usize = 4;

/// What a design minimises.
#[derive(Debug, Clone)]
pub(crate) enum Criterion {
    /// The variance of cᵀx (c-optimal).
    Variance(DVector<f64>),
    /// −ln det of the information (D-optimal).
    LogDet,
}

impl Criterion {
    /// How much adding a sample of row `g` lowers the objective, given M⁻¹ (≥ 0).
    fn gain(&self, minv: &DMatrix<f64>, g: &DVector<f64>) -> f64 {
        let h = minv * g;
        let denom = 1.0 + g.dot(&h);
        let v = match self {
            Criterion::Variance(c) => c.dot(&h).powi(2) / denom,
            Criterion::LogDet => denom.ln(),
        };
        if v.is_finite() {
            v
        } else {
            0.0
        }
    }

    /// The objective at information `m` (None when `m` is not positive definite).
    pub(crate) fn objective(&self, m: &DMatrix<f64>) -> Option<f64> {
        let chol = m.clone().cholesky()?;
        Some(match self {
            Criterion::Variance(c) => c.dot(&chol.solve(c)),
            Criterion::LogDet => -2.0 * chol.l().diagonal().iter().map(|d| d.ln()).sum::<f64>(),
        })
    }
}

/// `base` plus the prior information I/[`PRIOR_SD`]².
pub(crate) fn with_prior(base: &DMatrix<f64>) -> DMatrix<f64> {
    base + DMatrix::identity(base.nrows(), base.ncols()) / (PRIOR_SD * PRIOR_SD)
}

fn inverse(m: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    m.clone().cholesky().map(|c| c.inverse())
}

fn row(cand: &DMatrix<f64>, i: usize) -> DVector<f64> {
    cand.row(i).transpose()
}

/// The best candidate (most gain) among the allowed ones not in `taken`, with its gain.
fn best(
    crit: &Criterion,
    minv: &DMatrix<f64>,
    cand: &DMatrix<f64>,
    allowed: &[bool],
    taken: &[bool],
) -> Option<(usize, f64)> {
    (0..cand.nrows())
        .filter(|&i| allowed[i] && !taken[i])
        .map(|i| (i, crit.gain(minv, &row(cand, i))))
        .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
}

/// Choose up to `n` distinct candidates (rows of `cand`, K × q; only those `allowed`)
/// that minimise `crit` on top of the information `base` (q × q, the samples already
/// measured): greedily, one sample at a time, then by exchange (a chosen sample is
/// replaced by a better one while that lowers the objective, at most a few passes).
/// Returns the chosen candidates' indices in the order chosen; fewer than `n` when fewer
/// are allowed, none when the information is not finite.
pub(crate) fn choose(
    base: &DMatrix<f64>,
    cand: &DMatrix<f64>,
    n: usize,
    crit: &Criterion,
    allowed: &[bool],
) -> Vec<usize> {
    let mut m = with_prior(base);
    let mut taken = vec![false; cand.nrows()];
    let mut chosen = Vec::new();
    for _ in 0..n {
        let Some(minv) = inverse(&m) else {
            return Vec::new();
        };
        let Some((i, _)) = best(crit, &minv, cand, allowed, &taken) else {
            break;
        };
        let g = row(cand, i);
        m += &g * g.transpose();
        taken[i] = true;
        chosen.push(i);
    }
    exchange(&mut m, cand, crit, allowed, &mut taken, &mut chosen);
    chosen
}

/// Fedorov exchange: for each chosen sample, remove it and add back the best candidate
/// (itself or another) when another lowers the objective by more than rounding.
fn exchange(
    m: &mut DMatrix<f64>,
    cand: &DMatrix<f64>,
    crit: &Criterion,
    allowed: &[bool],
    taken: &mut [bool],
    chosen: &mut [usize],
) {
    for _ in 0..EXCHANGE_PASSES {
        let mut swapped = false;
        for slot in chosen.iter_mut() {
            let out = *slot;
            let g_out = row(cand, out);
            let without = &*m - &g_out * g_out.transpose();
            let Some(minv) = inverse(&without) else {
                return;
            };
            let keep = crit.gain(&minv, &g_out);
            let Some((j, gain)) = best(crit, &minv, cand, allowed, taken) else {
                continue;
            };
            if gain > keep * (1.0 + 1e-9) + 1e-300 {
                let g_in = row(cand, j);
                *m = without + &g_in * g_in.transpose();
                taken[out] = false;
                taken[j] = true;
                *slot = j;
                swapped = true;
            }
        }
        if !swapped {
            break;
        }
    }
}

/// What each candidate alone would add to the information `base`: the fraction by which
/// it lowers the target's variance (c-optimal), or the gain in ln det (D-optimal). Used to
/// colour the candidates in the design's picture.
pub(crate) fn single_gains(base: &DMatrix<f64>, cand: &DMatrix<f64>, crit: &Criterion) -> Vec<f64> {
    let m = with_prior(base);
    let (Some(minv), Some(obj)) = (inverse(&m), crit.objective(&m)) else {
        return vec![0.0; cand.nrows()];
    };
    (0..cand.nrows())
        .map(|i| {
            let gain = crit.gain(&minv, &row(cand, i));
            match crit {
                Criterion::Variance(_) if obj > 0.0 => gain / obj,
                _ => gain,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn greedy_takes_the_samples_that_see_the_target() {
        // Candidates: three see x0 strongly, one weakly, two see only x1.
        let cand = DMatrix::from_row_slice(
            6,
            2,
            &[0.1, 0.0, 0.0, 5.0, 3.0, 0.0, 0.0, 4.0, 2.0, 0.0, 1.0, 0.0],
        );
        let base = DMatrix::zeros(2, 2);
        let c = Criterion::Variance(DVector::from_vec(vec![1.0, 0.0]));
        let allowed = vec![true; 6];
        let mut got = choose(&base, &cand, 3, &c, &allowed);
        got.sort();
        assert_eq!(got, vec![2, 4, 5]);
        // D-optimal needs both variables: the strongest of each kind first.
        let got = choose(&base, &cand, 2, &Criterion::LogDet, &allowed);
        let mut got = got.clone();
        got.sort();
        assert_eq!(got, vec![1, 2]);
        // A forbidden candidate is never chosen.
        let mut allowed = allowed;
        allowed[2] = false;
        assert!(!choose(&base, &cand, 3, &c, &allowed).contains(&2));
    }

    #[test]
    fn variance_gain_is_the_rank_one_update() {
        let m = DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.5, 1.0]);
        let g = DVector::from_vec(vec![0.3, 1.2]);
        let c = Criterion::Variance(DVector::from_vec(vec![1.0, -1.0]));
        let before = c.objective(&m).unwrap();
        let after = c.objective(&(&m + &g * g.transpose())).unwrap();
        let gain = c.gain(&m.clone().try_inverse().unwrap(), &g);
        assert!((before - after - gain).abs() < 1e-12);
        let d = Criterion::LogDet;
        let dd = d.objective(&m).unwrap() - d.objective(&(&m + &g * g.transpose())).unwrap();
        assert!((dd - d.gain(&m.try_inverse().unwrap(), &g)).abs() < 1e-12);
    }
}
