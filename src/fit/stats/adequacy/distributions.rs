//! Closed-form distributions of the adequacy tests: normal and χ² tails, the sign test's
//! binomial tail, the Wald–Wolfowitz runs count, Spearman's rank correlation and R².
//! Pure functions of numbers: no fit, no geometry.

use rayon::prelude::*;

/// Upper tail of the standard normal, P(Z ≥ z) = erfc(z/√2)/2 (to ~1e-15 relative; libm).
pub(crate) fn normal_sf(z: f64) -> f64 {
    0.5 * libm::erfc(z / std::f64::consts::SQRT_2)
}

/// Upper tail of the χ² distribution with `nu` > 0 degrees of freedom at `x` ≥ 0,
/// P(X ≥ x) = Q(ν/2, x/2), the regularized upper incomplete gamma function, by its power
/// series below a + 1 and Lentz's continued fraction above (Numerical Recipes §6.2;
/// ~1e-14 relative). 1 for x ≤ 0; NaN for ν ≤ 0 or a NaN argument.
pub(crate) fn chi2_sf(x: f64, nu: f64) -> f64 {
    if nu.is_nan() || nu <= 0.0 || x.is_nan() {
        return f64::NAN;
    }
    if x <= 0.0 {
        return 1.0;
    }
    let (a, x) = (0.5 * nu, 0.5 * x);
    let log_prefactor = a * x.ln() - x - libm::lgamma(a);
    if x < a + 1.0 {
        // P(a, x) = e^{−x} x^a / Γ(a) Σ x^k / (a (a+1) ... (a+k)).
        let (mut term, mut sum, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..10_000 {
            ap += 1.0;
            term *= x / ap;
            sum += term;
            if term.abs() < sum.abs() * 1e-16 {
                break;
            }
        }
        (1.0 - sum * log_prefactor.exp()).clamp(0.0, 1.0)
    } else {
        // Q(a, x) = e^{−x} x^a / Γ(a) · 1/(x + 1 − a − 1·(1 − a)/(x + 3 − a − ...)).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let delta = d * c;
            h *= delta;
            if (delta - 1.0).abs() < 1e-16 {
                break;
            }
        }
        (log_prefactor.exp() * h).clamp(0.0, 1.0)
    }
}

/// Two-sided sign test: the probability, for `n` fair coin flips, of a count of heads at
/// least as far from n/2 as `k` (exact binomial sum, min(1, 2·P(X ≥ max(k, n − k)))).
pub(crate) fn sign_test(k: usize, n: usize) -> f64 {
    if n == 0 {
        return 1.0;
    }
    let hi = k.max(n - k);
    let ln_norm = libm::lgamma(n as f64 + 1.0) - n as f64 * std::f64::consts::LN_2;
    let tail: f64 = (hi..=n)
        .map(|j| {
            (ln_norm - libm::lgamma(j as f64 + 1.0) - libm::lgamma((n - j) as f64 + 1.0)).exp()
        })
        .sum();
    (2.0 * tail).min(1.0)
}

/// The Wald–Wolfowitz runs count of sequences of signs, summed over the sequences, with its
/// mean and variance under exchangeable signs given each sequence's counts: for one
/// sequence with n₊ and n₋ signs (n = n₊ + n₋), E R = 1 + 2n₊n₋/n and
/// Var R = 2n₊n₋(2n₊n₋ − n)/(n²(n − 1)).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct Runs {
    /// Observed number of runs (maximal blocks of one sign), summed over the sequences.
    pub runs: usize,
    /// Signs counted (sequences of one sample contribute their one run, and no variance).
    pub signs: usize,
    /// Expected number of runs under independent signs, Σ (1 + 2n₊n₋/n) per sequence.
    pub expected: f64,
    /// Variance of the number of runs under independent signs, summed over the sequences.
    pub variance: f64,
}

impl Runs {
    /// The runs of `sequences` (true: positive).
    pub(crate) fn of<'a>(sequences: impl IntoIterator<Item = &'a [bool]>) -> Runs {
        let mut out = Runs {
            runs: 0,
            signs: 0,
            expected: 0.0,
            variance: 0.0,
        };
        for s in sequences {
            if s.is_empty() {
                continue;
            }
            let n = s.len() as f64;
            let plus = s.iter().filter(|&&b| b).count() as f64;
            let two_pm = 2.0 * plus * (n - plus);
            out.runs += 1 + s.windows(2).filter(|w| w[0] != w[1]).count();
            out.signs += s.len();
            out.expected += 1.0 + two_pm / n;
            if s.len() > 1 {
                out.variance += two_pm * (two_pm - n) / (n * n * (n - 1.0));
            }
        }
        out
    }

    /// (R − E R)/√Var R: negative when the signs cluster (fewer runs than chance); NaN
    /// without variance.
    pub(crate) fn z(&self) -> f64 {
        if self.variance > 0.0 {
            (self.runs as f64 - self.expected) / self.variance.sqrt()
        } else {
            f64::NAN
        }
    }
}

/// A sample's index as the tests hold it, in four bytes: a fit's samples number far fewer
/// than 2³² (that many would need hundreds of GB); an index beyond is held as `u32::MAX`.
pub(crate) fn index_u32(i: usize) -> u32 {
    u32::try_from(i).unwrap_or(u32::MAX)
}

/// Ranks 1..n of `v` (ties get their mean rank).
fn ranks(v: &[f64]) -> Vec<f64> {
    let at = |k: u32| v[k as usize];
    let mut sorted: Vec<u32> = (0..v.len()).map(index_u32).collect();
    sorted.par_sort_unstable_by(|&a, &b| at(a).total_cmp(&at(b)));
    let mut r = vec![0.0; v.len()];
    let mut i = 0;
    while i < sorted.len() {
        let mut j = i;
        while j + 1 < sorted.len() && at(sorted[j + 1]) == at(sorted[i]) {
            j += 1;
        }
        let mean = 0.5 * (i + j) as f64 + 1.0;
        for &k in &sorted[i..=j] {
            r[k as usize] = mean;
        }
        i = j + 1;
    }
    r
}

/// Spearman's rank correlation of `x` and `y` (equal lengths): Pearson's correlation of
/// their ranks (ties at mean ranks). Under independence √(n − 1)·ρ is asymptotically
/// N(0, 1). NaN for fewer than two pairs or a constant variable.
pub(crate) fn spearman(x: &[f64], y: &[f64]) -> f64 {
    let (rx, ry) = rayon::join(|| ranks(x), || ranks(y));
    pearson(&rx, &ry)
}

/// Pearson's correlation (NaN for fewer than two pairs or a constant variable).
fn pearson(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    if x.len() < 2 {
        return f64::NAN;
    }
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (a, b) in x.iter().zip(y) {
        sxy += (a - mx) * (b - my);
        sxx += (a - mx) * (a - mx);
        syy += (b - my) * (b - my);
    }
    if sxx > 0.0 && syy > 0.0 {
        sxy / (sxx * syy).sqrt()
    } else {
        f64::NAN
    }
}

/// Least-squares slope of `y` on `x` (NaN for fewer than two points or constant `x`).
pub(crate) fn slope(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len() as f64;
    if x.len() < 2 {
        return f64::NAN;
    }
    let (mx, my) = (x.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    if sxx > 0.0 {
        sxy / sxx
    } else {
        f64::NAN
    }
}

/// Weighted R² = 1 − Σ wᵢ(fᵢ − tᵢ)² / Σ wᵢ(tᵢ − t̄)² of `n` values `f(i)` against data
/// `t(i)` in one space (t̄ the weighted mean; `sqrt_w` gives √wᵢ); NaN when the data has no
/// spread.
pub(crate) fn r_squared(
    n: usize,
    t: impl Fn(usize) -> f64,
    f: impl Fn(usize) -> f64,
    sqrt_w: impl Fn(usize) -> f64,
) -> f64 {
    let wsum: f64 = (0..n).map(|i| sqrt_w(i).powi(2)).sum();
    let tbar = (0..n).map(|i| t(i) * sqrt_w(i).powi(2)).sum::<f64>() / wsum;
    let ss_tot: f64 = (0..n).map(|i| (sqrt_w(i) * (t(i) - tbar)).powi(2)).sum();
    let ss_res: f64 = (0..n).map(|i| (sqrt_w(i) * (f(i) - t(i))).powi(2)).sum();
    if ss_tot > 0.0 {
        1.0 - ss_res / ss_tot
    } else {
        f64::NAN
    }
}

#[cfg(test)]
mod unit {
    use super::*;

    #[test]
    fn normal_tail_matches_known_quantiles() {
        assert!((normal_sf(0.0) - 0.5).abs() < 1e-15);
        assert!((normal_sf(1.959_963_984_540_054) - 0.025).abs() < 1e-12);
        assert!((normal_sf(-3.090_232_306_167_813_5) - 0.999).abs() < 1e-12);
    }

    #[test]
    fn chi2_tail_matches_the_closed_forms_of_one_and_two_degrees_of_freedom() {
        // ν = 2: Q = e^{−x/2}; ν = 1: Q = erfc(√(x/2)); both sides of the series switch.
        for x in [0.01f64, 0.5, 1.9, 3.0, 10.0, 80.0, 700.0] {
            let two = chi2_sf(x, 2.0);
            assert!(
                ((two - (-0.5 * x).exp()) / two).abs() < 1e-12,
                "ν=2, x={x}: {two}"
            );
            let one = chi2_sf(x, 1.0);
            let want = libm::erfc((0.5 * x).sqrt());
            assert!(
                ((one - want) / want).abs() < 1e-10,
                "ν=1, x={x}: {one} vs {want}"
            );
        }
        // ν = 4: Q = e^{−x/2}(1 + x/2).
        for x in [0.3f64, 4.0, 40.0] {
            let want = (-0.5 * x).exp() * (1.0 + 0.5 * x);
            assert!(((chi2_sf(x, 4.0) - want) / want).abs() < 1e-12);
        }
        assert_eq!(chi2_sf(0.0, 5.0), 1.0);
        assert!(chi2_sf(1.0, 0.0).is_nan());
    }

    #[test]
    fn sign_test_is_the_exact_binomial_tail() {
        // 10 of 10 heads: 2/1024; 8 of 10: 2·(45+10+1)/1024; 5 of 10: 1.
        assert!((sign_test(10, 10) - 2.0 / 1024.0).abs() < 1e-15);
        assert!((sign_test(0, 10) - 2.0 / 1024.0).abs() < 1e-15);
        assert!((sign_test(8, 10) - 112.0 / 1024.0).abs() < 1e-14);
        assert_eq!(sign_test(5, 10), 1.0);
        assert_eq!(sign_test(0, 0), 1.0);
    }

    /// Every arrangement of `plus` positive and `minus` negative signs (each equally likely
    /// under exchangeability).
    fn arrangements(plus: usize, minus: usize) -> Vec<Vec<bool>> {
        let n = plus + minus;
        (0u32..1 << n)
            .filter(|m| m.count_ones() as usize == plus)
            .map(|m| (0..n).map(|i| m >> i & 1 == 1).collect())
            .collect()
    }

    #[test]
    fn runs_mean_and_variance_match_the_enumerated_distribution() {
        for (plus, minus) in [(3, 2), (4, 4), (1, 6), (5, 3)] {
            let all = arrangements(plus, minus);
            let counts: Vec<f64> = all
                .iter()
                .map(|s| Runs::of([s.as_slice()]).runs as f64)
                .collect();
            let m = counts.len() as f64;
            let mean = counts.iter().sum::<f64>() / m;
            let var = counts.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / m;
            let r = Runs::of([all[0].as_slice()]);
            assert!((r.expected - mean).abs() < 1e-12, "{plus}/{minus}: mean");
            assert!((r.variance - var).abs() < 1e-12, "{plus}/{minus}: variance");
        }
        // Two sequences add: + + − − (2 runs) and + − (2 runs).
        let r = Runs::of([[true, true, false, false].as_slice(), &[true, false]]);
        assert_eq!((r.runs, r.signs), (4, 6));
        assert!((r.expected - (3.0 + 2.0)).abs() < 1e-12);
    }

    #[test]
    fn spearman_of_monotone_and_reversed_data_is_plus_and_minus_one() {
        let x = [1.0, 2.0, 3.0, 4.0, 5.0];
        let y = [1.0, 4.0, 9.0, 16.0, 25.0];
        assert!((spearman(&x, &y) - 1.0).abs() < 1e-15);
        let rev: Vec<f64> = y.iter().rev().copied().collect();
        assert!((spearman(&x, &rev) + 1.0).abs() < 1e-15);
        // 1 − 6Σd²/(n(n²−1)) without ties: ranks of y = 2,1,4,3,5 → Σd² = 4, ρ = 0.8.
        assert!((spearman(&x, &[2.0, 1.0, 4.0, 3.0, 5.0]) - 0.8).abs() < 1e-14);
        assert!(spearman(&x, &[1.0; 5]).is_nan());
    }

    #[test]
    fn r_squared_of_known_data() {
        // ss_res = 0.01 + 0.01 + 0.04 + 0.04 = 0.1, ss_tot = 5: R² = 0.98.
        let t = [1.0, 2.0, 3.0, 4.0];
        let f = [1.1, 1.9, 3.2, 3.8];
        assert!((r_squared(4, |i| t[i], |i| f[i], |_| 1.0) - 0.98).abs() < 1e-14);
        // The mean itself: R² = 0; constant data: NaN.
        assert!(r_squared(4, |i| t[i], |_| 2.5, |_| 1.0).abs() < 1e-15);
        assert!(r_squared(3, |_| 1.0, |_| 1.0, |_| 1.0).is_nan());
        assert!((slope(&[0.0, 1.0, 2.0], &[1.0, 3.0, 5.0]) - 2.0).abs() < 1e-15);
    }
}
