//! The KBS sum S(g, a) = Σ_{m≥1} g^m / (m! m) · e^{−a/m} (Peters 2000, eq. 37), evaluated
//! as Q(g, a) = e^{−g} S(g, a) / g in log form, with its partial derivatives.
//!
//! Q is finite for every g > 0 (Q → e^{−a} as g → 0, Q → e^{−a/g}/g² as g → ∞), so the
//! models form L = s π (T/λ)² h² (kσ)² Q without the 0·∞ of cos²θi · F² · S at grazing
//! geometry. Working with ln Q avoids the overflow of g^m/m! and the underflow of e^{−g}
//! and e^{−a/m}.
//!
//! Accuracy: `Series` meets the relative tolerance `tol` on Q and on its derivatives (the
//! truncation is bounded by a geometric tail); rounding adds a few ulps per term summed.

use super::{EvalMode, Mode};

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

/// ln of the m-th term t_m = g^m/(m! m) e^{−a/m}.
#[inline]
fn ln_term(m: f64, ln_g: f64, a: f64) -> f64 {
    m * ln_g - libm::lgamma(m + 1.0) - m.ln() - a / m
}

/// The index of the largest term: the root of d/dm ln t_m ≈ ln g − ln(m + ½) − 1/m + a/m².
fn peak_index(ln_g: f64, a: f64) -> f64 {
    let slope = |m: f64| ln_g - (m + 0.5).ln() - 1.0 / m + a / (m * m);
    if slope(1.0) <= 0.0 {
        return 1.0;
    }
    let mut hi = 2.0;
    while slope(hi) > 0.0 && hi < 1e300 {
        hi *= 2.0;
    }
    let mut lo = hi / 2.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if slope(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 0.5 {
            break;
        }
    }
    lo.round().max(1.0)
}

/// The series, summed outward from its largest term until the bounded remainder is below
/// `tol` relative to both S and the derivative sums.
pub fn series(g: f64, a: f64, tol: f64) -> LnQ {
    let ln_g = g.ln();
    let m0 = peak_index(ln_g, a);
    let ln_t0 = ln_term(m0, ln_g, a);
    // Sums relative to the peak term: s0 = Σ t/t0, s_dm = Σ (m−1) t/t0, s_inv = Σ (t/m)/t0.
    let (mut s0, mut s_dm, mut s_inv) = (1.0, m0 - 1.0, 1.0 / m0);
    let stop = 0.1 * tol.max(1e-17);
    // Upward.
    let mut m = m0;
    let mut rel = 1.0f64;
    loop {
        let ratio_ln = ln_g - (m + 1.0).ln() - ((m + 1.0) / m).ln() + a / (m * (m + 1.0));
        rel *= ratio_ln.exp();
        m += 1.0;
        s0 += rel;
        s_dm += (m - 1.0) * rel;
        s_inv += rel / m;
        let ratio = ratio_ln.exp();
        if ratio < 1.0 && m >= 3.0 {
            let tail = rel * ratio / (1.0 - ratio);
            if tail * m < stop * s0 && tail * m < stop * s_dm.max(f64::MIN_POSITIVE) {
                break;
            }
        }
        if rel == 0.0 || m > m0 + 1e7 {
            break;
        }
    }
    // Downward.
    let mut m = m0;
    let mut rel = 1.0f64;
    while m > 1.0 {
        let ratio_ln = ln_g - m.ln() - (m / (m - 1.0)).ln() + a / ((m - 1.0) * m);
        rel /= ratio_ln.exp();
        m -= 1.0;
        s0 += rel;
        s_dm += (m - 1.0) * rel;
        s_inv += rel / m;
        if rel * m < stop * s0 && (m - 1.0) * rel * m < stop * s_dm.max(f64::MIN_POSITIVE) {
            break;
        }
    }
    LnQ {
        ln_q: -g + ln_t0 + s0.ln() - ln_g,
        d_g: -1.0 + s_dm / (g * s0),
        d_a: -s_inv / s0,
        mode: Mode::Series,
    }
}

/// The cheapest evaluation whose error bound meets `tol` (placeholder: always the series).
pub fn auto(g: f64, a: f64, tol: f64) -> LnQ {
    series(g, a, tol)
}

/// ln Q by the given evaluation mode.
#[inline]
pub fn ln_q(g: f64, a: f64, mode: EvalMode, tol: f64) -> LnQ {
    match mode {
        EvalMode::Auto => auto(g, a, tol),
        EvalMode::Series => series(g, a, tol),
        EvalMode::Smooth => smooth(g, a),
        EvalMode::Rough => rough(g, a),
    }
}
