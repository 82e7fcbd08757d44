//! The series on a stride: every h-th term of the sum, times h, where the peak of the terms
//! is wide (`auto`'s evaluation of a rough surface far from the specular direction, where
//! the asymptotic expansion does not apply and the plain sum needs O(√g) terms).
//!
//! Around its peak m* the term t_m = e^{−g} g^m/(m! m) e^{−a/m} is a smooth, log-concave
//! function of m with width W (its log's curvature −φ'' = ψ'(m+1) − 1/m² + 2a/m³ = 1/W²).
//! By Poisson summation, h Σ_j t_{m*+jh} equals Σ_m t_m up to the Fourier transform of the
//! terms at frequency 1/h relative to its value at 0, ≈ 2 e^{−2π² (W/h)²} for a Gaussian
//! peak: with h = ⌊W/1.5⌋ that is 5e-20, below rounding (and the integer sum itself differs
//! from the integral by 2 e^{−2π² W²}). For the derivative sum Σ (m−1−g) t_m the factor
//! (m−1−g) adds ~2π (W/h) W: 7e-17 at W = 150, ~5e-16 at g = 1e6. The terms are not exactly
//! Gaussian (skew of order 1/W), so this is an estimate, not a proof like the plain sum's
//! tail bounds. Measured in 30-digit arithmetic (`tests/ref/kbs_strided.py`, its output
//! `kbs_strided.csv`: 16 random (g, a), g 1e2..3e5, a 0..600 g^1.5): worst 8.4e-20 on ln S
//! and 6.1e-17 on g ∂lnS/∂g (with W/h = 1 instead: 5.8e-9 and 8.2e-7, the law predicted);
//! and the code here against the 60-digit grid and against the plain sum at 3000 random
//! (g, a) (tests below).
//!
//! Each term is computed on its own ([`ln_rel`]: no product of ratios), one `exp` and near
//! the peak no logarithm; the sum stops by the plain sum's tail bounds applied to the strided terms
//! (they fall geometrically beyond the peak, the ratios decreasing by log-concavity, and
//! monotonically below it). At tol 1e-10 a Gaussian peak's terms fall below the bound
//! ~7 W from the peak: ~10 strides each way, ~21 terms at any g, against ~14 W for the
//! plain sum (an estimate from the Gaussian, not counted); used where h ≥ [`STRIDE_MIN`] (W ≥ 18; below, the plain sum is as fast).

use super::terms::{ln_poisson, stirling, LnQ, Sums};

/// Stride over the width: h = ⌊W / WIDTH_PER_STRIDE⌋ (aliasing ≈ 2 e^{−2π²·1.5²} = 5e-20).
const WIDTH_PER_STRIDE: f64 = 1.5;

/// Smallest stride `auto` uses: below it the plain sum is as fast (`cargo bench --bench
/// off_specular`: at g = 200, a = 3.5 g^1.5, h = 8, the stride took 1.37 µs and the plain
/// sum 1.15; at g = 400, h = 12, 1.28 against 1.53; against the plain sum,
/// 7× faster at g = 1e4 and 60× at 7e5).
pub(super) const STRIDE_MIN: f64 = 12.0;

/// The stride for the peak at `m0` (the index of the largest term, ≥ 1) of the sum with
/// exponent `a`, or `None` where it would be below [`STRIDE_MIN`].
#[inline]
pub(super) fn stride(m0: f64, a: f64) -> Option<f64> {
    // 2 (a/m0³), not (2a)/m0³: the same bits, and no ∞/∞ at a near f64::MAX.
    let curvature = 1.0 / (m0 + 0.5) - 1.0 / (m0 * m0) + 2.0 * (a / (m0 * m0 * m0));
    let h = (1.0 / (WIDTH_PER_STRIDE * curvature.sqrt())).floor();
    (h >= STRIDE_MIN).then_some(h)
}

/// Most strided terms [`sum`] adds on either side of the peak (a Gaussian peak needs ~10;
/// the bound keeps the work finite where rounding makes the tail bounds fail).
const STRIDES_MAX: usize = 1000;

/// ln Q and its derivatives from the terms m0 + j h (j ∈ ℤ, m ≥ 1), stopped where the
/// bounds on the omitted strided terms are below `tol`/10 relative to each sum; `None`
/// when the sum reaches m < 1 before that (the peak is not clear of the sum's start: the
/// caller sums every term), or when a side needs more than [`STRIDES_MAX`] terms.
/// `ln_g` = ln g; `m0` the peak index, `h` from [`stride`].
pub(super) fn sum(g: f64, a: f64, tol: f64, ln_g: f64, m0: f64, h: f64) -> Option<LnQ> {
    let eps = 0.1 * tol.max(1e-17);
    let p0 = ln_poisson(m0, g, ln_g);
    let ln_m0 = m0.ln();
    let ln_m0_g = libm::log1p((m0 - g) / g);
    let rel = |m: f64| ln_rel(g, a, ln_g, m0, p0, ln_m0, ln_m0_g, m).exp();
    let mut s = Sums::at_peak(g, m0);
    // Upward: with q = t_m/t_{m−h} < 1, the later strided terms are ≤ t_m q^k.
    let (mut m, mut prev) = (m0, 1.0f64);
    let mut steps = 0..STRIDES_MAX;
    loop {
        steps.next()?;
        m += h;
        let t = rel(m);
        s.add(m, t, g);
        let q = t / prev;
        if q < 1.0 && s.upper_tail_below(t, q, m, h, g, a, eps) {
            break;
        }
        if t == 0.0 || !t.is_finite() {
            break;
        }
        prev = t;
    }
    // Downward: the terms fall monotonically below the peak; after t_m, the ⌊(m−1)/h⌋
    // strided terms left are each ≤ t_m.
    let mut m = m0;
    let mut steps = 0..STRIDES_MAX;
    loop {
        steps.next()?;
        m -= h;
        if m < 1.0 {
            return None;
        }
        let t = rel(m);
        s.add(m, t, g);
        if s.lower_tail_below(((m - 1.0) / h).floor() * t, m, g, a, eps) {
            break;
        }
    }
    Some(s.ln_q(p0 - ln_m0 - a / m0, h, g, ln_g))
}

/// ln(t_m/t_{m0}) with an absolute error of a few ulps times its size plus ~1e-15 (the
/// peak's terms need it: the derivative sums cancel by ~W). With d = m − m0, x = d/m0,
/// ℓ = ln(1+x) and Stirling's series for ln m! (m, m0 ≥ 30), ln(t_m/t_{m0}) =
/// −d (ln(m0/g) + ℓ) − m0 (ℓ − x) − 1.5 ℓ − Δc + a d/(m m0), Δc the difference of Stirling's
/// corrections; ℓ − x from its series where small (as one difference it would lose d ulps),
/// so that near the peak no logarithm is taken per term. Below m = 30 (far down the peak's
/// tail) from `ln_poisson` directly. `p0` = ln_poisson(m0), `ln_m0` = ln m0,
/// `ln_m0_g` = ln(m0/g).
#[inline]
#[allow(clippy::too_many_arguments)]
fn ln_rel(g: f64, a: f64, ln_g: f64, m0: f64, p0: f64, ln_m0: f64, ln_m0_g: f64, m: f64) -> f64 {
    let d = m - m0;
    if m < 30.0 {
        return ln_poisson(m, g, ln_g) - p0 - (m.ln() - ln_m0) + a * d / (m * m0);
    }
    let x = d / m0;
    let (l, lx) = if x.abs() < 0.5 {
        let lx = log1pmx(x);
        (lx + x, lx)
    } else {
        let l = libm::log1p(x);
        (l, l - x)
    };
    -d * (ln_m0_g + l) - m0 * lx - 1.5 * l - (stirling(m) - stirling(m0)) + a * d / (m * m0)
}

/// ln(1+x) − x for x > −1, with a relative error of a few ulps: for |x| < ½ from
/// u = x/(2+x) (ln(1+x) = 2 atanh u): −2u²/(1−u) + 2(u³/3 + u⁵/5 + …), |u| < ⅓, the series
/// to u^31 (the omitted terms < 1e-17 of the result); else as one difference.
fn log1pmx(x: f64) -> f64 {
    if x.abs() >= 0.5 {
        return libm::log1p(x) - x;
    }
    let u = x / (2.0 + x);
    let u2 = u * u;
    // Σ_{k≥1} u^{2k+1}/(2k+1), Horner in u² from k = 15 down.
    let mut s = 0.0;
    for k in (1..=15).rev() {
        s = s * u2 + 1.0 / (2 * k + 1) as f64;
    }
    -2.0 * u2 / (1.0 - u) + 2.0 * u * u2 * s
}

#[cfg(test)]
mod tests {
    use super::super::test_data::{mpmath_grid, uniform};
    use super::super::{peak_index, series_from_peak};
    use super::*;
    use crate::model::lanes::Portable;

    /// The strided sum where `auto` would use it: (g, a, its result, the plain sum's).
    fn strided_and_plain(g: f64, a: f64, tol: f64) -> Option<(LnQ, LnQ)> {
        let ln_g = g.ln();
        let m0 = peak_index(g, ln_g, a);
        let h = stride(m0, a)?;
        let q = sum(g, a, tol, ln_g, m0, h)?;
        Some((q, series_from_peak::<Portable<true>>(g, a, 1e-15, ln_g, m0)))
    }

    /// Against the 60-digit mpmath grid (`tests/ref/kbs_reference_q.csv`): every grid point
    /// on the strided path meets the module's accuracy claim at tol 1e-12 (a hundredth of
    /// the fits' default), and the grid has such points at g from 1e2 to 1e6.
    #[test]
    fn strided_sum_matches_mpmath() {
        let tol = 1e-12;
        let mut used = Vec::new();
        for f in mpmath_grid() {
            let (g, a) = (f[0], f[1]);
            let Some((q, _)) = strided_and_plain(g, a, tol) else {
                continue;
            };
            let rel = |x: f64, r: f64| (x - r).abs() / (1.0 + r.abs());
            let round = 64.0 * f64::EPSILON * (1.0 + f[2].abs() + g.sqrt());
            assert!(
                (q.ln_q - f[2]).abs() <= tol + round
                    && rel(g * q.d_g, g * f[3]) <= tol + round
                    && rel(a * q.d_a, a * f[4]) <= tol + round,
                "g={g} a={a}: {q:?} vs {:?}",
                &f[2..5]
            );
            used.push(g);
        }
        let lo = used.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = used.iter().cloned().fold(0.0, f64::max);
        assert!(
            used.len() >= 10 && lo <= 1e3 && hi >= 1e6,
            "{} points, g {lo}..{hi}",
            used.len()
        );
    }

    /// Against the plain sum (every term) at random (g, a) over the strided path's whole
    /// range: g 1e2..1e6, a from 0 to 1e4 g^1.5.
    #[test]
    fn strided_sum_matches_every_term() {
        let mut uniform = uniform(0x9e37_79b9_7f4a_7c15);
        let (tol, mut n) = (1e-12, 0);
        for _ in 0..3000 {
            let g = 10f64.powf(2.0 + 4.0 * uniform());
            let a = if uniform() < 0.1 {
                0.0
            } else {
                g.powf(1.5) * 10f64.powf(-3.0 + 7.0 * uniform())
            };
            let Some((q, p)) = strided_and_plain(g, a, tol) else {
                continue;
            };
            // The module's claim (tol, plus rounding of a few ulps times the condition: √g for
            // the derivatives) for both, against each other.
            let round = 64.0 * f64::EPSILON * g.sqrt();
            let close = |x: f64, y: f64| (x - y).abs() <= 2.0 * tol * (1.0 + y.abs()) + round;
            assert!(
                close(q.ln_q, p.ln_q) && close(g * q.d_g, g * p.d_g) && close(a * q.d_a, a * p.d_a),
                "g={g} a={a}: {q:?} vs {p:?}"
            );
            n += 1;
        }
        assert!(n > 2000, "only {n} samples on the strided path");
    }

    #[test]
    fn log1pmx_is_accurate() {
        // Against the Taylor series x²(−1/2 + x/3 − x²/4 …) summed to convergence at small x,
        // and the plain difference where it loses nothing (|x| ≥ ½).
        for &x in &[1e-8, -1e-8, 1e-3, -1e-3, 0.1, -0.1, 0.3, -0.3, 0.49, -0.49] {
            let (mut term, mut taylor) = (x, 0.0);
            for k in 2..400 {
                term *= -x;
                taylor += term / k as f64;
            }
            let f = log1pmx(x);
            assert!(
                (f - taylor).abs() <= 8.0 * f64::EPSILON * taylor.abs(),
                "x={x}: {f} vs {taylor}"
            );
        }
        assert_eq!(log1pmx(0.7), libm::log1p(0.7) - 0.7);
    }
}
