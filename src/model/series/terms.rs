//! The pieces every evaluation of the KBS sum shares: its result type, the Poisson
//! weight and the term ratio in stable form, and a vectorisable `exp` (see the parent
//! module's doc for how they are used and their accuracy).

use super::super::lanes::F64x4;
use super::super::Mode;

/// ln Q(g, a) and its partial derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LnQ {
    /// ln Q, Q = e^{−g} S(g, a) / g.
    pub ln_q: f64,
    /// ∂ ln Q / ∂g.
    pub d_g: f64,
    /// ∂ ln Q / ∂a.
    pub d_a: f64,
    /// How it was evaluated.
    pub mode: Mode,
}

/// ½ ln 2π.
const HALF_LN_2PI: f64 = 0.918_938_533_204_672_8;

/// ln(e^{−g} g^m / m!) for integer m ≥ 1, without the cancellation between −g, m ln g and
/// ln m! (each ~ g) that would cost ~g ulps of ln Q when g is large.
pub(super) fn ln_poisson(m: f64, g: f64, ln_g: f64) -> f64 {
    if m < 30.0 {
        return m * ln_g - g - libm::lgamma(m + 1.0);
    }
    // ln m! = (m+½) ln m − m + ½ ln 2π + 1/(12m) − 1/(360m³) + 1/(1260m⁵) − 1/(1680m⁷),
    // error < 1/(1188 m⁹) < 1e-16 for m ≥ 30. Then with δ = (g − m)/m:
    // m ln g − g − (m ln m − m) = m (ln(1+δ) − δ).
    let delta = (g - m) / m;
    let ln_m = m.ln();
    let main = if delta.abs() < 0.5 {
        m * (libm::log1p(delta) - delta)
    } else {
        m * (ln_g - ln_m) + (m - g)
    };
    main - 0.5 * ln_m - HALF_LN_2PI - stirling(m)
}

/// Stirling's correction ln m! − ((m+½) ln m − m + ½ ln 2π) = 1/(12m) − 1/(360m³) +
/// 1/(1260m⁵) − 1/(1680m⁷), error < 1/(1188 m⁹) < 1e-16 for m ≥ 30.
#[inline(always)]
pub(super) fn stirling(m: f64) -> f64 {
    let r = 1.0 / m;
    let r2 = r * r;
    r * (1.0 / 12.0 - r2 * (1.0 / 360.0 - r2 * (1.0 / 1260.0 - r2 / 1680.0)))
}

/// The sums of a summation outward from the peak term t0 = t_{m0}, relative to it:
/// s0 = Σ t/t0, s_c = Σ (m−1−g) t/t0 (centred so that g ∂lnQ/∂g = s_c/s0 has no
/// cancellation at large g), s_inv = Σ (t/m)/t0; and the tests of the tail bounds the plain
/// and the strided sums stop by (each omitted part below `eps` of its sum).
pub(super) struct Sums {
    pub(super) s0: f64,
    pub(super) s_c: f64,
    pub(super) s_inv: f64,
}

impl Sums {
    /// The peak term alone.
    #[inline(always)]
    pub(super) fn at_peak(g: f64, m0: f64) -> Self {
        Sums {
            s0: 1.0,
            s_c: m0 - 1.0 - g,
            s_inv: 1.0 / m0,
        }
    }

    /// Add the term at m (`t` = t_m/t0).
    #[inline(always)]
    pub(super) fn add(&mut self, m: f64, t: f64, g: f64) {
        self.s0 += t;
        self.s_c += (m - 1.0 - g) * t;
        self.s_inv += t / m;
    }

    /// Upward, after adding the term at m (`rel` = t_m/t0), the terms m + step, m + 2 step,
    /// … each at most `r` < 1 times the one before: Σ t ≤ rel r/(1−r), Σ |j−1−g| t ≤
    /// rel [(m+g) r/(1−r) + step r/(1−r)²], Σ t/j ≤ that first bound/(m + step). Whether all
    /// three are below `eps` of their sums.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn upper_tail_below(
        &self,
        rel: f64,
        r: f64,
        m: f64,
        step: f64,
        g: f64,
        a: f64,
        eps: f64,
    ) -> bool {
        let q = r / (1.0 - r);
        let tail = rel * q;
        let tail_c = rel * ((m + g) * q + step * q / (1.0 - r));
        tail <= eps * self.s0
            && tail_c <= eps * (self.s0 + self.s_c.abs())
            && a * tail / (m + step) <= eps * (self.s0 + a * self.s_inv)
    }

    /// Downward, with at most `left` in all the terms below m together (each term ≤ t1 and
    /// fewer than m of them: left = count × t1 bounds Σ t, (m+g) left bounds Σ |j−1−g| t,
    /// and left bounds Σ t/j as j ≥ 1): whether all three are below `eps` of their sums.
    #[inline(always)]
    pub(super) fn lower_tail_below(&self, left: f64, m: f64, g: f64, a: f64, eps: f64) -> bool {
        left <= eps * self.s0
            && left * (m + g) <= eps * (self.s0 + self.s_c.abs())
            && a * left <= eps * (self.s0 + a * self.s_inv)
    }

    /// ln Q and its derivatives from the sums of terms taken `step` apart (1: every term),
    /// `ln_t0` = ln(e^{−g} t_{m0}).
    #[inline(always)]
    pub(super) fn ln_q(&self, ln_t0: f64, step: f64, g: f64, ln_g: f64) -> LnQ {
        LnQ {
            ln_q: ln_t0 + (step * self.s0).ln() - ln_g,
            d_g: self.s_c / (g * self.s0),
            d_a: -self.s_inv / self.s0,
            mode: Mode::Series,
        }
    }
}

/// ln r_m, r_m = t_{m+1}/t_m = g m/(m+1)² e^{a/(m(m+1))}, decreasing in m.
#[inline]
pub(super) fn ln_ratio(m: f64, ln_g: f64, a: f64) -> f64 {
    ln_g + m.ln() - 2.0 * (m + 1.0).ln() + a / (m * (m + 1.0))
}

/// The term ratio r_m = t_{m+1}/t_m = g m/(m+1)² e^{a/(m(m+1))} as its factor
/// g m/(m+1)² and its exponent a/(m(m+1)) (the caller picks the `exp`).
#[inline(always)]
pub(super) fn ratio_parts(g: f64, a: f64, m: f64) -> (f64, f64) {
    let mp1 = m + 1.0;
    (g * m / (mp1 * mp1), a / (m * mp1))
}

/// e^x for x ∈ [−700, 700] (clamped), without a table (so that it vectorises): x = k ln2 + r
/// with |r| ≤ ln2/2, e^r by its degree-13 Taylor polynomial (truncation < 4e-18) in fused
/// multiply-adds, times 2^k through the exponent bits. Error ≤ 2 ulp (unit-tested).
#[inline(always)]
pub(super) fn exp_poly<V: F64x4>(x: f64) -> f64 {
    use super::super::lanes::exp_parts::{C, INV_LN2, LN2_HI, LN2_LO, MAGIC};
    let x = x.clamp(-700.0, 700.0);
    let kd = V::fma1(x, INV_LN2, MAGIC);
    let k = kd - MAGIC;
    let r = V::fma1(k, -LN2_LO, V::fma1(k, -LN2_HI, x));
    let ki = (kd.to_bits() as i64).wrapping_sub(MAGIC.to_bits() as i64);
    // Estrin's scheme in r² (shorter dependency chains than Horner).
    let r2 = r * r;
    let r4 = r2 * r2;
    let r8 = r4 * r4;
    let p01 = V::fma1(r, C[1], C[0]);
    let p23 = V::fma1(r, C[3], C[2]);
    let p45 = V::fma1(r, C[5], C[4]);
    let p67 = V::fma1(r, C[7], C[6]);
    let p89 = V::fma1(r, C[9], C[8]);
    let p1011 = V::fma1(r, C[11], C[10]);
    let p1213 = V::fma1(r, C[13], C[12]);
    let q0 = V::fma1(r2, p23, p01);
    let q1 = V::fma1(r2, p67, p45);
    let q2 = V::fma1(r2, p1011, p89);
    let lo = V::fma1(r4, q1, q0);
    let hi = V::fma1(r4, p1213, q2);
    let p = V::fma1(r8, hi, lo);
    // 2^k as two factors so that k down to −1010 stays normal.
    let k1 = ki >> 1;
    p * f64::from_bits(((k1 + 1023) << 52) as u64) * f64::from_bits(((ki - k1 + 1023) << 52) as u64)
}
