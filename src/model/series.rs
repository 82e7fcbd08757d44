//! The KBS sum S(g, a) = Σ_{m≥1} g^m / (m! m) · e^{−a/m} (Peters 2000, eq. 37), evaluated
//! as Q(g, a) = e^{−g} S(g, a) / g in log form, with its partial derivatives.
//!
//! Q is finite for every g > 0 (Q → e^{−a} as g → 0, Q → e^{−a/g}/g² as g → ∞), so the
//! models form L = s π (T/λ)² h² (kσ)² Q without the 0·∞ of cos²θi · F² · S at grazing
//! geometry. Working with ln Q avoids the overflow of g^m/m! and the underflow of e^{−g}
//! and e^{−a/m}.
//!
//! Three evaluations (the series also on a stride), and `auto` picks the cheapest that meets the tolerance per sample:
//!
//! * [`series`]: the sum, from its largest term outward, stopped by rigorous tail bounds
//!   (the term ratio t_{m+1}/t_m = g m/(m+1)² e^{a/(m(m+1))} decreases in m, so the upper
//!   tail is bounded by a geometric series and the lower terms fall monotonically). The
//!   normalisation e^{−g} t_{m*} is formed with the large cancelling logarithms removed
//!   analytically (Stirling, `ln_1p`), so ln Q keeps its accuracy up to g = 1e6 and beyond.
//!   Cost: O(1) terms for small g, O(√g) for large g (one `exp` per term when a > 0; the
//!   ratios of eight consecutive terms are computed together, so their `exp`s vectorise).
//!   For g < 60 and a < 600 it sums upward from m = 1 instead: no peak search, no lgamma,
//!   each term t_m = g^{m−1}/(m! m) e^{−a/m} computed on its own from tabulated
//!   constants, eight terms at a time in independent lanes (vectorised in the AVX2 copy,
//!   with a table-free `exp`), the tail bounded once per eight terms with the ratio of
//!   the last two.
//! * [`smooth`]: m = 1 only (eq. 42). `auto` uses it when the bound on the rest,
//!   u/(1−u) with u = t2/t1 = (g/4) e^{a/2}, is below `tol`; it then returns derivatives
//!   corrected by the m = 2 term (exact to O(u)).
//! * [`rough`]: e^{−g} S ≈ e^{−a/g}/g (eq. 43). `auto` uses its asymptotic completion
//!   ([`asymptotic`]): e^{−g} S = E[f(M)], M ~ Poisson(g), f(m) = e^{−a/m}/m. Writing
//!   M = g(1 + x), f(g(1+x)) = f(g) (1+x)^{−1} exp(b x/(1+x)) with b = a/g; the Taylor
//!   coefficients c_k(b) of that function times the Poisson central moments μ_k(g)/g^k,
//!   regrouped by powers of 1/g, give e^{−g} S = (e^{−a/g}/g) Σ_n P_n(b) g^{−n} with
//!   polynomials P_n of degree 2n (P_0 = 1, P_1 = 1 − 2b + b²/2, and P_n(0) = n!, the
//!   expansion of Ei at a = 0). The table of P_n is built at compile time. The series is
//!   asymptotic: orders are added while they shrink; the error estimate is the first
//!   omitted order (with its derivative weights), extrapolated from the last order by the
//!   larger of the last two decay ratios. `auto` accepts it only when g ≥ 40 (so the
//!   neglected e^{−g}-size effects of the M = 0 end are below 1e-17), a < 3 g^1.5, the
//!   orders decay by at least 2× per step, and the estimate is below 0.15 tol. Unlike the
//!   series' tail bounds this estimate is not a proof; it is checked against the mpmath
//!   grid (worst error found 0.13 of the claim) and against the series at 3000 random
//!   (g, a) (`tests/lib/model_props.rs`). Work: the orders are evaluated four at a time, in
//!   four-lane vectors (`src/model/lanes.rs`): Horner in b² on four vectors (even and odd parts
//!   of P_n and P_n'), 4k+4 fused multiply-adds of four lanes for the k-th group of four
//!   orders, then the group's sums and acceptance tests as vector operations (no branch
//!   per order); n ≈ 3 orders at g = 1e4, ≈ 6–9 at g = 100 and moderate b. It fails, and
//!   `auto` falls back to the series, when b²/g is not small (far from the specular peak
//!   at moderate g).
//!
//! `auto`: smooth if its bound holds (possible only for g ≤ 2 tol); else the asymptotic
//! completion if it is accepted; else the series, and where the series' peak is wide
//! (width W ≥ 18 terms: large g far from the specular direction, a ≳ 3 g^1.5) only every
//! h-th term of it, h = ⌊W/1.5⌋, times h (module `strided`: ~31 terms instead of ~13 W,
//! ~60× faster at g = 7e5 in the off_specular bench; the stride's error, ≈ 2 e^{−2π²·1.5²}
//! = 5e-20 relative, is an estimate from Poisson summation, measured in 30 digits and
//! tested against the mpmath grid and the plain sum).
//!
//! Work is bounded at every (g, a), so that an evaluation ends at any parameter value: the
//! peak search takes a bounded number of steps (also above 2⁵³, where unit steps no longer
//! advance); the forced series, too, sums every h-th term where h ≥ 4096 (a peak wider than
//! ~6000 terms); a strided side stops after 1000 terms; and far from the specular
//! direction on a surface with T ≳ 1e6 λ (a ≥ 1e12, a ≥ 64 g²) Q is below e^{−999 999}
//! (proof at `beyond_sums`) and is returned as 0, with NaN only for NaN arguments.
//!
//! Batches ([`ln_q_batch`], what the models call): the same results bit for bit as one
//! sample at a time; on x86-64 CPUs with AVX2 and FMA both run in a copy of this code
//! compiled for them, chosen at run time, which gives the same bits as the portable code
//! with fused multiply-adds (unit-tested). That copy, and the portable code where the target always has FMA
//! (aarch64), fuse their multiply-adds; on a CPU without FMA (x86-64 before 2013) the
//! portable code rounds products and sums separately, which changes results by rounding
//! only (unit-tested: within `tol` of the fused code) and keeps it fast.
//!
//! Accuracy (`series`, and `auto` at every switch): |Δ ln Q| ≤ tol (the relative error of
//! Q, also when Q itself under- or overflows), |Δ(g ∂lnQ/∂g)| ≤ tol (1 + |g ∂lnQ/∂g|) and
//! |Δ(a ∂lnQ/∂a)| ≤ tol (1 + |a ∂lnQ/∂a|), plus rounding: a few ulps times the condition
//! (|ln Q| for Q, √g for the derivatives). These are the quantities the model's Jacobian
//! uses (∂ln L/∂ln σ = 2 + 2g ∂lnQ/∂g, ∂ln L/∂ln T = 2 + 2a ∂lnQ/∂a). Verified against the
//! 60-digit mpmath reference in `tests/ref/` (g 1e-12..1e6, a 0..1e8).

use super::lanes::{F64x4, PortableNative};
use super::{EvalMode, Mode};

mod asymptotic;
mod small;
mod strided;
mod terms;
#[cfg(test)]
mod work_bounds;

use asymptotic::{asymptotic_body, ASYM_G_MIN};
use small::{series_from_one, SMALL_A_MAX, SMALL_G_MAX};
pub use terms::LnQ;
use terms::{exp_poly, ln_poisson, ln_ratio, ratio_parts, Sums};

/// Smooth approximation (eq. 42): only the m = 1 term, Q = e^{−g} e^{−a}.
#[inline]
pub fn smooth(g: f64, a: f64) -> LnQ {
    LnQ {
        ln_q: -g - a,
        d_g: -1.0,
        d_a: -1.0,
        mode: Mode::Smooth,
    }
}

/// Rough approximation (eq. 43): e^{−g} S ≈ e^{−a/g}/g, so Q = e^{−a/g}/g².
#[inline]
pub fn rough(g: f64, a: f64) -> LnQ {
    LnQ {
        ln_q: -a / g - 2.0 * g.ln(),
        d_g: a / (g * g) - 2.0 / g,
        d_a: -1.0 / g,
        mode: Mode::Rough,
    }
}

/// The index of the largest term: the smallest m ≥ 1 with r_m < 1.
///
/// f(m) = ln r_m is decreasing for m > 1 and convex for m ≥ 3, and f(g − 3) ≥ 0 for g ≥ 6
/// (g m/(m+1)² ≥ 1 there, and the a term is positive): Newton's iteration on f from
/// m = g − 3 stays left of the root and converges to it from below (quadratically near it;
/// ~4 steps), and the first integer with f < 0 is then found upward from the last iterate.
/// Where that start does not apply, or the iteration is slow (a ≫ g², where the peak moves
/// far above g), by bisection. Either way the same integer: the result does not depend on
/// the search.
///
/// Bounded work at every (g, a): at most [`PEAK_NEWTON_STEPS`] Newton steps and
/// [`PEAK_UPWARD_STEPS`] unit steps, and a bisection of at most ~2100 halvings. Above 2⁵³,
/// where consecutive integers are no longer all doubles, the result is the double nearest
/// the crossing that bisection reaches (only the strided sum, which needs no integer peak,
/// is summed from such a peak).
fn peak_index(g: f64, ln_g: f64, a: f64) -> f64 {
    if ln_ratio(1.0, ln_g, a) < 0.0 {
        return 1.0;
    }
    let mut m = g - 3.0;
    let mut f = if m >= 3.0 { ln_ratio(m, ln_g, a) } else { -1.0 };
    if f >= 0.0 {
        for _ in 0..PEAK_NEWTON_STEPS {
            let mp1 = m + 1.0;
            let df = 1.0 / m - 2.0 / mp1 - a * (2.0 * m + 1.0) / (m * m * mp1 * mp1);
            let step = -f / df;
            m += step;
            if step < 0.5 {
                let mut k = m.ceil();
                for _ in 0..PEAK_UPWARD_STEPS {
                    if ln_ratio(k, ln_g, a) < 0.0 {
                        return k;
                    }
                    k += 1.0;
                }
                break;
            }
            f = ln_ratio(m, ln_g, a);
        }
    }
    peak_by_bisection(g, ln_g, a)
}

/// Newton steps [`peak_index`] takes before it falls back to bisection.
const PEAK_NEWTON_STEPS: usize = 12;

/// Unit steps [`peak_index`] takes upward from the converged Newton iterate (one or two
/// where the iterate is exact; many only where m + 1 rounds to m) before bisection.
const PEAK_UPWARD_STEPS: usize = 64;

/// [`peak_index`] by bisection: bracket [lo, hi] with r_lo ≥ 1 > r_hi from the a = 0
/// peak m ≈ g upward by doubling, then halve it (r_1 ≥ 1 on entry) until no double lies
/// between lo + 1 and hi (so that it ends above 2⁵³ too).
fn peak_by_bisection(g: f64, ln_g: f64, a: f64) -> f64 {
    let mut lo = 1.0f64;
    let mut hi = (g.floor()).max(2.0);
    if ln_ratio(hi, ln_g, a) >= 0.0 {
        lo = hi;
        hi *= 2.0;
        while ln_ratio(hi, ln_g, a) >= 0.0 && hi < 1e300 {
            lo = hi;
            hi *= 2.0;
        }
    }
    while hi - lo > 1.0 {
        let mid = (0.5 * (lo + hi)).floor();
        if mid <= lo || mid >= hi {
            break;
        }
        if ln_ratio(mid, ln_g, a) >= 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// The series, summed outward from its largest term until rigorous bounds on the omitted
/// terms are below `tol`/10 relative to S and to the derivative sums (see the module doc).
pub fn series(g: f64, a: f64, tol: f64) -> LnQ {
    ln_q(g, a, EvalMode::Series, tol)
}

#[inline(always)]
fn series_body<V: F64x4>(g: f64, a: f64, tol: f64) -> LnQ {
    if let Some(q) = beyond_sums(g, a) {
        return q;
    }
    if g < SMALL_G_MAX && a < SMALL_A_MAX {
        return series_from_one::<V>(g, a, tol);
    }
    let ln_g = g.ln();
    let m0 = peak_index(g, ln_g, a);
    from_peak::<V>(g, a, tol, ln_g, m0, PLAIN_STRIDE_MAX)
}

/// The sum from its peak `m0`: every h-th term (module `strided`) where the stride h is at
/// least `min_stride`, else (or where the strided sum cannot be formed) every term. Every
/// term is summed only where the stride is below [`PLAIN_STRIDE_MAX`], so that the work is
/// bounded at every (g, a): ≲ 14 · 1.5 · PLAIN_STRIDE_MAX terms for the plain sum, a few
/// dozen for the strided one. (A peak so wide that the strided sum fails there has no
/// finite sum: NaN.)
#[inline(always)]
fn from_peak<V: F64x4>(g: f64, a: f64, tol: f64, ln_g: f64, m0: f64, min_stride: f64) -> LnQ {
    let h = strided::stride(m0, a);
    if let Some(h) = h.filter(|&h| h >= min_stride) {
        if let Some(q) = strided::sum(g, a, tol, ln_g, m0, h) {
            return q;
        }
    }
    if h.is_some_and(|h| h >= PLAIN_STRIDE_MAX) || !m0.is_finite() {
        return LnQ {
            ln_q: f64::NAN,
            d_g: f64::NAN,
            d_a: f64::NAN,
            mode: Mode::Series,
        };
    }
    series_from_peak::<V>(g, a, tol, ln_g, m0)
}

/// Stride from which even the forced series (`--mode series`) sums the strided terms: a
/// peak of width W ≥ 1.5 × 4096 (beyond g ≈ 4e7 near the specular direction, or a ≫ g²
/// far from it, T ≳ 1e4 λ there) would need ~14 W terms per sample, and where the peak
/// index passes 2⁵³ the unit steps of the plain sum no longer advance. The strided sum
/// meets the same accuracy (module `strided`).
const PLAIN_STRIDE_MAX: f64 = 4096.0;

/// Smallest a of the flat-surface limit (see [`beyond_sums`]): √a = 1e6.
const FLAT_A_MIN: f64 = 1e12;

/// ln Q where no sum is formed, None where the sums apply: NaN for a NaN argument; the
/// rough limit for g = ∞ (Q = e^{−a/g}/g² = 0); Q = e^{−a} at g = 0; and the flat-surface limit, Q = 0
/// (ln Q = −∞, derivatives 0), where a ≥ [`FLAT_A_MIN`] and a ≥ 64 g² (a = ∞ included:
/// far from the specular direction on a surface whose correlation length is ≳ 1e6 λ).
/// There, with M = √a ≥ 8 g, the terms m ≤ M carry e^{−a/m} ≤ e^{−√a} and sum (with
/// e^{−g}/g) to at most e^{−√a}, and those above M to at most g^{M−1}/M! ≤ e^{−M}: so
/// Q ≤ 2 e^{−√a} < e^{−999 999}, and s π (T/λ)² h² (kσ)² Q, the prefactor below e^{710},
/// is 0 in double precision, as the sums themselves give there (where rounding would
/// spoil them: the peak index passes 2⁵³ near a = 1e33).
#[inline(always)]
fn beyond_sums(g: f64, a: f64) -> Option<LnQ> {
    if g.is_nan() || a.is_nan() || (g.is_infinite() && a.is_infinite()) {
        return Some(LnQ {
            ln_q: f64::NAN,
            d_g: f64::NAN,
            d_a: f64::NAN,
            mode: Mode::Series,
        });
    }
    if g.is_infinite() {
        return Some(rough(g, a));
    }
    if a >= FLAT_A_MIN && a >= 64.0 * g * g {
        return Some(LnQ {
            ln_q: f64::NEG_INFINITY,
            d_g: 0.0,
            d_a: 0.0,
            mode: Mode::Series,
        });
    }
    // g = 0 (σ so small that g underflows): only m = 1 is left, Q = e^{−a}, and
    // ∂lnQ/∂g = −1 + e^{a/2}/4 from the m = 2 term (the smooth limit, exact here).
    (g == 0.0).then(|| LnQ {
        ln_q: -a,
        d_g: -1.0 + 0.25 * (0.5 * a).exp(),
        d_a: -1.0,
        mode: Mode::Smooth,
    })
}

/// The series summed outward from its largest term `m0` (from [`peak_index`]; `ln_g` = ln g).
#[inline(always)]
fn series_from_peak<V: F64x4>(g: f64, a: f64, tol: f64, ln_g: f64, m0: f64) -> LnQ {
    // ln(e^{−g} t_{m0}).
    let ln_t0 = ln_poisson(m0, g, ln_g) - m0.ln() - a / m0;
    let sum = PeakSum {
        g,
        a,
        m0,
        eps: 0.1 * tol.max(1e-17),
        // The inline exp (≤ 2 ulp) is used while the accumulated rounding of the ratio
        // products over the O(√g) terms stays far below tol; the libm exp otherwise.
        inline_exp: tol >= 1e-12 && g < 1e4,
    };
    let mut s = Sums::at_peak(g, m0);
    sum.upward::<V>(&mut s);
    sum.downward::<V>(&mut s);
    s.ln_q(ln_t0, 1.0, g, ln_g)
}

/// The plain sum outward from its peak `m0`: its arguments, the relative bound `eps` its
/// tails must meet, and which `exp` the ratios use.
struct PeakSum {
    g: f64,
    a: f64,
    m0: f64,
    eps: f64,
    inline_exp: bool,
}

/// Terms per block of the plain sum.
const L: usize = 8;

/// Most blocks the plain sum adds on either side of its peak: ~30 times the ~14 W terms a
/// peak of the widest width it is used for (W ≈ 1.5 × [`PLAIN_STRIDE_MAX`]) needs, so
/// that rounding or a NaN that keeps the tail tests from passing cannot make it run on.
const PLAIN_BLOCKS_MAX: usize = 1 << 16;

impl PeakSum {
    /// The ratios r_m for eight consecutive m (`m_first`, then by `step`), in independent
    /// lanes (the `exp`s vectorise in the AVX2 copy); m below 1 (past the bottom of the sum)
    /// gives unused lanes. Inlined into the caller (compiled on its own it would miss the
    /// caller's FMA, and `exp_poly`'s fused multiply-adds would become calls).
    #[inline(always)]
    fn ratios_at<V: F64x4>(&self, m_first: f64, step: f64) -> [f64; L] {
        let mut e = [0.0f64; L];
        let mut rs = [0.0f64; L];
        for l in 0..L {
            (rs[l], e[l]) = ratio_parts(self.g, self.a, (m_first + step * l as f64).max(1.0));
        }
        if self.a != 0.0 {
            if self.inline_exp {
                for l in 0..L {
                    rs[l] *= exp_poly::<V>(e[l]);
                }
            } else {
                for l in 0..L {
                    rs[l] *= e[l].exp();
                }
            }
        }
        rs
    }

    /// Add the terms above the peak. After adding t_m (rel = t_m/t0) with r = r_m < 1,
    /// Σ_{j>m} t_j ≤ rel r/(1−r), Σ_{j>m} |j−1−g| t_j ≤ rel [(m+g) r/(1−r) + r/(1−r)²],
    /// Σ_{j>m} t_j/j ≤ tail/(m+1). The bounds are tested once per eight terms, after the
    /// last (a few more terms than a test per term would add, each below the bound); 1/m is
    /// formed eight at a time, off the serial chain of products.
    #[inline(always)]
    fn upward<V: F64x4>(&self, s: &mut Sums) {
        let (g, a, eps) = (self.g, self.a, self.eps);
        let mut m = self.m0;
        let mut rel = 1.0f64;
        let mut rs = self.ratios_at::<V>(m, 1.0);
        for _ in 0..PLAIN_BLOCKS_MAX {
            let next = self.ratios_at::<V>(m + L as f64, 1.0);
            let inv_m: [f64; L] = std::array::from_fn(|l| 1.0 / (m + (l + 1) as f64));
            for l in 0..L {
                rel *= rs[l];
                m += 1.0;
                s.s0 += rel;
                s.s_c += (m - 1.0 - g) * rel;
                s.s_inv += rel * inv_m[l];
            }
            let r = next[0];
            if r < 1.0 && s.upper_tail_below(rel, r, m, 1.0, g, a, eps) {
                return;
            }
            if rel == 0.0 || !rel.is_finite() {
                return;
            }
            rs = next;
        }
    }

    /// Add the terms below the peak: they fall monotonically; after adding t_m, the m−1
    /// terms left are each ≤ t_{m−1} = rel/r_{m−1} (tested once per eight terms; 1/r_m
    /// and 1/m formed eight at a time).
    #[inline(always)]
    fn downward<V: F64x4>(&self, s: &mut Sums) {
        let (g, a, eps) = (self.g, self.a, self.eps);
        let mut m = self.m0;
        let mut rel = 1.0f64;
        let mut rs = self.ratios_at::<V>(m - 1.0, -1.0);
        for _ in 0..PLAIN_BLOCKS_MAX {
            if m <= 1.0 {
                return;
            }
            let next = self.ratios_at::<V>(m - 1.0 - L as f64, -1.0);
            let inv_r: [f64; L] = std::array::from_fn(|l| 1.0 / rs[l]);
            let inv_m: [f64; L] = std::array::from_fn(|l| 1.0 / (m - (l + 1) as f64).max(1.0));
            for l in 0..L {
                rel *= inv_r[l];
                m -= 1.0;
                s.s0 += rel;
                s.s_c += (m - 1.0 - g) * rel;
                s.s_inv += rel * inv_m[l];
                if m <= 1.0 || rel == 0.0 {
                    return;
                }
            }
            let left = (m - 1.0) * (rel / next[0]);
            if s.lower_tail_below(left, m, g, a, eps) {
                return;
            }
            rs = next;
        }
    }
}

/// The asymptotic completion of the rough approximation (module doc), or `None` when its
/// error estimate does not reach `tol` within `ASYM_ORDERS` orders.
pub fn asymptotic(g: f64, a: f64, tol: f64) -> Option<LnQ> {
    struct Call(f64, f64, f64);
    impl LanesFn for Call {
        type Out = Option<LnQ>;
        #[inline(always)]
        fn call<V: F64x4>(self) -> Option<LnQ> {
            asymptotic_body::<V>(self.0, self.1, self.2)
        }
    }
    with_lanes(Call(g, a, tol))
}

/// The smooth approximation with the m = 2 correction of its derivatives, when the bound
/// on the omitted terms (u/(1−u), u = (g/4) e^{a/2}) meets `tol`.
#[inline]
fn smooth_checked(g: f64, a: f64, tol: f64) -> Option<LnQ> {
    let e2 = 0.25 * (0.5 * a).exp();
    let u = g * e2;
    if u <= 0.5 * tol {
        // g ∂lnQ/∂g = −g + u (1 + O(u)); a ∂lnQ/∂a = −a (1 − u/2 + O(u)).
        Some(LnQ {
            ln_q: -g - a,
            d_g: -1.0 + e2,
            d_a: -1.0 + 0.5 * u,
            mode: Mode::Smooth,
        })
    } else {
        None
    }
}

/// The cheapest evaluation whose error bound meets `tol`: smooth (m = 1 with its bound),
/// the rough approximation's asymptotic completion, else the series.
pub fn auto(g: f64, a: f64, tol: f64) -> LnQ {
    ln_q(g, a, EvalMode::Auto, tol)
}

#[inline(always)]
fn auto_with<V: F64x4>(g: f64, a: f64, tol: f64) -> LnQ {
    if g > G_DOMAIN_MAX && a.is_finite() && g.is_finite() {
        // Beyond the stated domain (a fit's trial step can go there): no O(√g) series;
        // the asymptotic expansion where it applies, else the rough approximation, whose
        // relative error is O(1/g) < 1e-6 here. Best effort, not held to `tol`.
        if a < g * g.sqrt() {
            if let Some(q) = asymptotic_body::<V>(g, a, tol.max(1e-6)) {
                return q;
            }
        }
        return rough(g, a);
    }
    if let Some(q) = beyond_sums(g, a) {
        return q;
    }
    // u = (g/4) e^{a/2} ≥ g/4, so smooth can only pass when g ≤ 2 tol.
    if g <= 2.0 * tol {
        if let Some(q) = smooth_checked(g, a, tol) {
            return q;
        }
    } else if tries_asymptotic(g, a) {
        if let Some(q) = asymptotic_body::<V>(g, a, tol) {
            return q;
        }
    }
    if g < SMALL_G_MAX && a < SMALL_A_MAX {
        return series_from_one::<V>(g, a, tol);
    }
    // A wide peak: every h-th term (module `strided`), else every term.
    let ln_g = g.ln();
    let m0 = peak_index(g, ln_g, a);
    from_peak::<V>(g, a, tol, ln_g, m0, strided::STRIDE_MIN)
}

/// ln Q for a batch of samples: `out[i]` = [`ln_q`]`(g[i], a[i], mode, tol)`, identical
/// results, faster: on x86-64 CPUs with AVX2 and FMA the batch runs in a copy of the
/// evaluation compiled for them (chosen at run time; the binary stays portable), where the
/// series' lanes of eight terms or ratios vectorise.
/// Panics if the slices differ in length.
pub fn ln_q_batch(g: &[f64], a: &[f64], mode: EvalMode, tol: f64, out: &mut [LnQ]) {
    assert!(g.len() == a.len() && g.len() == out.len());
    struct Call<'s>(&'s [f64], &'s [f64], EvalMode, f64, &'s mut [LnQ]);
    impl LanesFn for Call<'_> {
        type Out = ();
        #[inline(always)]
        fn call<V: F64x4>(self) {
            let Call(g, a, mode, tol, out) = self;
            for ((o, &gi), &ai) in out.iter_mut().zip(g).zip(a) {
                *o = ln_q_with::<V>(gi, ai, mode, tol);
            }
        }
    }
    with_lanes(Call(g, a, mode, tol, out));
}

/// A computation written for any [`F64x4`], run by [`with_lanes`] with the lanes this CPU
/// has.
pub(crate) trait LanesFn {
    type Out;
    fn call<V: F64x4>(self) -> Self::Out;
}

/// Run `f` with AVX2 + FMA lanes, compiled for them, where the CPU has both; with the
/// portable lanes this build runs otherwise (`PortableNative`: fused where the target
/// always has FMA). On one CPU every entry point (batch or single sample) therefore runs
/// the same code and returns the same bits; the AVX2 + FMA lanes give the bits of the
/// fused portable lanes (tested op by op, and the scalar code around them is the same).
#[inline(always)]
pub(crate) fn with_lanes<F: LanesFn>(f: F) -> F::Out {
    #[cfg(target_arch = "x86_64")]
    if super::lanes::has_avx2_fma() {
        #[target_feature(enable = "avx2,fma")]
        unsafe fn run<F: LanesFn>(f: F) -> F::Out {
            f.call::<super::lanes::Avx>()
        }
        // SAFETY: the CPU has AVX2 and FMA (checked just above).
        return unsafe { run(f) };
    }
    f.call::<PortableNative>()
}

/// Whether `auto` tries the asymptotic expansion (at the requested `tol`) before the series.
#[inline(always)]
fn tries_asymptotic(g: f64, a: f64) -> bool {
    (ASYM_G_MIN..=G_DOMAIN_MAX).contains(&g) && a < ASYM_S_MAX * g * g.sqrt()
}

/// Largest a/g^1.5 for which `auto` tries the asymptotic expansion (beyond it the
/// expansion needs more orders than tabulated even at g = 40, and is rejected).
const ASYM_S_MAX: f64 = 3.0;

/// Largest g of the stated domain; `auto` does not sum the series beyond it.
pub const G_DOMAIN_MAX: f64 = 1e6;

/// ln Q by the given evaluation mode.
pub fn ln_q(g: f64, a: f64, mode: EvalMode, tol: f64) -> LnQ {
    let mut out = [smooth(0.0, 0.0)];
    ln_q_batch(&[g], &[a], mode, tol, &mut out);
    out[0]
}

#[inline(always)]
fn ln_q_with<V: F64x4>(g: f64, a: f64, mode: EvalMode, tol: f64) -> LnQ {
    match mode {
        EvalMode::Auto => auto_with::<V>(g, a, tol),
        EvalMode::Series => series_body::<V>(g, a, tol),
        EvalMode::Smooth => smooth(g, a),
        EvalMode::Rough => rough(g, a),
    }
}

/// What the tests of this module and its submodules share.
#[cfg(test)]
mod test_data {
    /// The rows (g, a, ln Q, ∂lnQ/∂g, ∂lnQ/∂a) of the 60-digit mpmath grid
    /// (`tests/ref/kbs_reference_q.csv`, made by `tests/ref/kbs_reference.py`).
    pub(super) fn mpmath_grid() -> Vec<[f64; 5]> {
        let text = include_str!("../../tests/ref/kbs_reference_q.csv");
        let field = |s: &str| s.parse::<f64>().unwrap();
        text.lines()
            .skip(1)
            .map(|line| {
                let f: Vec<f64> = line.split(',').take(5).map(field).collect();
                [f[0], f[1], f[2], f[3], f[4]]
            })
            .collect()
    }

    /// Uniform numbers in [0, 1) from a xorshift generator started at `seed` (≠ 0).
    pub(super) fn uniform(seed: u64) -> impl FnMut() -> f64 {
        let mut state = seed;
        move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::lanes::Portable;
    use super::asymptotic::ASYM;
    use super::test_data::{mpmath_grid, uniform};
    use super::*;

    #[test]
    fn table_matches_known_orders() {
        // P_n(0) = n! (e^{−g} S(g, 0) ~ Σ n!/g^{n+1}); P_1(b) = 1 − 2b + b²/2.
        let mut f = 1.0;
        for (n, row) in ASYM.iter().enumerate() {
            if n > 0 {
                f *= n as f64;
            }
            // The table is built in binary64 with cancelling sums of size up to (2n−1)!!:
            // ~1e-10 relative at n = 18, in orders whose weight n!/g^n is < 1e-12 where used.
            assert!(
                (row[0] - f).abs() <= 1e-9 * f,
                "P_{n}(0) = {} != {f}",
                row[0]
            );
        }
        assert_eq!(&ASYM[1][..3], &[1.0, -2.0, 0.5]);
    }

    /// (g, a) spread over the domain: log-uniform g in [1e-12, 1e6], a zero, ~ g,
    /// up to g^1.5 (the asymptotic region) or log-uniform in [1e-3, 1e8].
    fn random_g_a(n: usize) -> (Vec<f64>, Vec<f64>) {
        let mut uniform = uniform(0x2545_f491_4f6c_dd1d);
        let g: Vec<f64> = (0..n)
            .map(|_| 10f64.powf(-12.0 + 18.0 * uniform()))
            .collect();
        let a = g
            .iter()
            .map(|&g| match (uniform() * 4.0) as u32 {
                0 => 0.0,
                1 => g * 10f64.powf(-3.0 + 4.0 * uniform()),
                2 => g.powf(1.5) * uniform(),
                _ => 10f64.powf(-3.0 + 11.0 * uniform()),
            })
            .collect();
        (g, a)
    }

    #[test]
    fn batch_equals_one_by_one() {
        // The lanes this CPU runs (AVX2 + FMA where it has them), batch and one sample at
        // a time, give the bits of the portable lanes with the same rounding (fused
        // multiply-adds with AVX2 + FMA): in every mode, on every path of `auto`. The
        // portable lanes with separate roundings (CPUs without FMA) agree within `tol`.
        let (g, a) = random_g_a(2003);
        let n = g.len();
        #[cfg(target_arch = "x86_64")]
        let fused = super::super::lanes::has_avx2_fma();
        #[cfg(not(target_arch = "x86_64"))]
        let fused = cfg!(target_arch = "aarch64");
        let reference = |g, a, mode, tol| {
            if fused {
                ln_q_with::<Portable<true>>(g, a, mode, tol)
            } else {
                ln_q_with::<Portable<false>>(g, a, mode, tol)
            }
        };
        for mode in [
            EvalMode::Auto,
            EvalMode::Series,
            EvalMode::Smooth,
            EvalMode::Rough,
        ] {
            for tol in [1e-10, 1e-13, 1e-6] {
                for len in [1, 2, 3, 5, 7, 9, n] {
                    let mut fast = vec![smooth(0.0, 0.0); len];
                    ln_q_batch(&g[..len], &a[..len], mode, tol, &mut fast);
                    for i in 0..len {
                        let (g, a) = (g[i], a[i]);
                        let portable = reference(g, a, mode, tol);
                        assert_eq!(fast[i], portable, "{mode:?} g={g} a={a} tol={tol}");
                        assert_eq!(ln_q(g, a, mode, tol), portable);
                        let other = if fused {
                            ln_q_with::<Portable<false>>(g, a, mode, tol)
                        } else {
                            ln_q_with::<Portable<true>>(g, a, mode, tol)
                        };
                        let close = |x: f64, y: f64| (x - y).abs() <= tol * (1.0 + y.abs());
                        assert!(
                            close(other.ln_q, portable.ln_q)
                                && close(g * other.d_g, g * portable.d_g)
                                && close(a * other.d_a, a * portable.d_a),
                            "{mode:?} g={g} a={a} tol={tol}: {other:?} vs {portable:?}"
                        );
                    }
                }
            }
        }
        // The sample exercises every path: smooth, asymptotic accepted and rejected, series.
        let tried = (0..n).filter(|&i| tries_asymptotic(g[i], a[i])).count();
        let count = |m: Mode| {
            (0..n)
                .filter(|&i| auto(g[i], a[i], 1e-10).mode == m)
                .count()
        };
        let rough = count(Mode::Rough);
        assert!(
            count(Mode::Smooth) > 20 && count(Mode::Series) > 100,
            "too few"
        );
        assert!(
            tried > 100 && rough > 20 && rough < tried,
            "{tried} {rough}"
        );
    }

    /// Both portable roundings (fused, and the separate roundings CPUs without FMA run)
    /// meet the accuracy claim of the module doc against the 60-digit mpmath reference
    /// (`tests/ref/kbs_reference_q.csv`, the grid `tests/lib/kbs_reference.rs` checks the
    /// dispatched code on), in `series` and `auto` modes at tol 1e-10.
    #[test]
    fn portable_lanes_meet_tol_against_mpmath() {
        fn worst<V: F64x4>(mode: EvalMode) -> f64 {
            let tol = 1e-10;
            let eps = f64::EPSILON;
            let mut worst = 0.0f64;
            for [g, a, ln_q, d_g, d_a] in mpmath_grid() {
                let q = ln_q_with::<V>(g, a, mode, tol);
                let rel = |x: f64, r: f64| (x - r).abs() / (1.0 + r.abs());
                let round_d = 64.0 * eps * (1.0 + g.sqrt());
                let ratio = ((q.ln_q - ln_q).abs() / (tol + 64.0 * eps * (1.0 + ln_q.abs())))
                    .max(rel(g * q.d_g, g * d_g) / (tol + round_d))
                    .max(rel(a * q.d_a, a * d_a) / (tol + round_d));
                assert!(ratio.is_finite(), "{mode:?} g={g} a={a}: {q:?}");
                worst = worst.max(ratio);
            }
            worst
        }
        for mode in [EvalMode::Series, EvalMode::Auto] {
            for w in [
                worst::<Portable<true>>(mode),
                worst::<Portable<false>>(mode),
            ] {
                println!("{mode:?}: worst error/allowance {w:.3}");
                assert!(w <= 1.0, "{mode:?}: worst error/allowance {w}");
            }
        }
    }

    #[test]
    fn exp_poly_is_accurate() {
        fn check<V: F64x4>() {
            let mut x = -700.0;
            while x <= 700.0 {
                let (f, e) = (exp_poly::<V>(x), x.exp());
                assert!(
                    (f / e - 1.0).abs() < 4.0 * f64::EPSILON,
                    "x={x}: {f} vs {e}"
                );
                x += 0.00731;
            }
            assert_eq!(exp_poly::<V>(0.0), 1.0);
            assert_eq!(exp_poly::<V>(-800.0), exp_poly::<V>(-700.0));
        }
        check::<Portable<true>>();
        check::<Portable<false>>();
    }

    /// The Newton search gives the bisection's integer over the whole domain (g 1e-12..1e6,
    /// a 0..1e8), its edges (g = 6..9 where the Newton start begins to apply) included.
    #[test]
    fn peak_search_by_newton_equals_bisection() {
        let (mut g, mut a) = random_g_a(20_000);
        for k in 0..400 {
            g.push(6.0 + 0.01 * k as f64);
            a.push(if k % 2 == 0 { 0.0 } else { 10f64.powi(k % 9) });
        }
        for (&g, &a) in g.iter().zip(&a) {
            let ln_g = g.ln();
            let want = if ln_ratio(1.0, ln_g, a) < 0.0 {
                1.0
            } else {
                peak_by_bisection(g, ln_g, a)
            };
            assert_eq!(peak_index(g, ln_g, a), want, "g={g} a={a}");
        }
    }

    #[test]
    fn ln_poisson_matches_lgamma_at_the_switch() {
        for &g in &[3.0, 29.0, 31.0, 100.0] {
            for &m in &[30.0, 31.0, 45.0] {
                let direct = m * f64::ln(g) - g - libm::lgamma(m + 1.0);
                let stable = ln_poisson(m, g, f64::ln(g));
                assert!((direct - stable).abs() < 1e-12 * direct.abs().max(1.0));
            }
        }
    }
}
