//! The series' work is bounded at every (g, a) (parent module doc): evaluations at extreme
//! arguments end, and the flat-surface limit and the forced series' stride agree with the
//! sums where both can be formed.

use super::*;

/// Arguments from 0 to ∞, far beyond the stated domain.
const EXTREMES: [f64; 16] = [
    0.0,
    1e-300,
    1e-12,
    1.0,
    40.0,
    1e4,
    1e6,
    1e8,
    1e15,
    1e17,
    1e33,
    1e100,
    1e200,
    1e300,
    f64::MAX,
    f64::INFINITY,
];

#[test]
fn every_evaluation_ends_at_extreme_arguments() {
    // Q = e^{−g} S / g ≤ (1 − e^{−g})/g ≤ 1, so ln Q ≤ 0 wherever it is a number; and
    // `auto` gives a number at every finite (g, a) and at either argument infinite.
    let t0 = std::time::Instant::now();
    for &g in &EXTREMES {
        for &a in &EXTREMES {
            for mode in [EvalMode::Auto, EvalMode::Series] {
                let q = ln_q(g, a, mode, 1e-10);
                assert!(
                    q.ln_q.is_nan() || q.ln_q <= 1e-9,
                    "{mode:?} g={g} a={a}: {q:?}"
                );
                if mode == EvalMode::Auto && !(g.is_infinite() && a.is_infinite()) {
                    assert!(!q.ln_q.is_nan(), "g={g} a={a}: {q:?}");
                }
            }
        }
    }
    // A generous bound: the whole grid takes milliseconds.
    assert!(t0.elapsed().as_secs_f64() < 10.0, "{:?}", t0.elapsed());
}

#[test]
fn the_sums_respect_the_flat_limit_bound() {
    // `beyond_sums` returns Q = 0 where a ≥ 1e12 and a ≥ 64 g², from Q ≤ 2 e^{−√a}, which
    // holds wherever a ≥ 64 g². Below a = 1e12 the sums are formed: they must obey it.
    let mut checked = 0;
    for g in [1e-6f64, 0.1, 1.0, 14.0, 100.0, 1e3, 1e4] {
        for k in [1.0f64, 3.0, 1e2, 1e4] {
            let a = (64.0 * g * g * k).max(1e3 * k);
            if a >= FLAT_A_MIN {
                continue;
            }
            for mode in [EvalMode::Auto, EvalMode::Series] {
                let q = ln_q(g, a, mode, 1e-10);
                let bound = 2f64.ln() - a.sqrt();
                assert!(
                    q.ln_q <= bound * (1.0 - 1e-9),
                    "{mode:?} g={g} a={a}: {q:?} > {bound}"
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 40, "{checked}");
    // At the threshold the limit is taken.
    assert_eq!(
        ln_q(1e4, FLAT_A_MIN, EvalMode::Series, 1e-10).ln_q,
        f64::NEG_INFINITY
    );
    assert!(ln_q(1e4, 0.99 * FLAT_A_MIN, EvalMode::Series, 1e-10)
        .ln_q
        .is_finite());
}

#[test]
fn the_forced_series_on_a_wide_peak_meets_tol_against_every_term() {
    // Peaks of width W ≈ 1e4 (stride h ≥ 4096): `--mode series` sums every h-th term; the
    // reference is the rough limit's asymptotic expansion at tol 1e-12, a method of its
    // own (the plain sum of every term, ~1.4e5 of them, accumulates rounding there: its
    // g ∂lnQ/∂g is 5e-9 off at g = 1e8).
    let tol = 1e-10;
    for (g, a) in [(1e8f64, 0.0f64), (1e8, 1e12 - 1.0), (3e8, 3e8), (1e8, 5e11)] {
        let ln_g = g.ln();
        let m0 = peak_index(g, ln_g, a);
        let h = strided::stride(m0, a).unwrap();
        assert!(h >= PLAIN_STRIDE_MAX, "g={g} a={a}: h={h}");
        let q = series(g, a, tol);
        let r = asymptotic(g, a, 1e-12).unwrap();
        let close = |x: f64, y: f64| (x - y).abs() <= tol * (1.0 + y.abs());
        assert!(
            close(q.ln_q, r.ln_q) && close(g * q.d_g, g * r.d_g) && close(a * q.d_a, a * r.d_a),
            "g={g} a={a}: {q:?} vs {r:?}"
        );
    }
}
