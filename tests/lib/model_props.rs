//! Model properties: analytic Jacobians against central differences for every model, no
//! NaN/inf/panic anywhere in the domain, continuity of `auto` across its switch points,
//! the paper's Figures 6–7 facts, the coherent (patch) term, and the lobe times its
//! Fresnel and shadowing factors (the product of the parts, and its Jacobian).

use crate::geometry::{Geometry, Quantity, Sample};
use crate::model::fresnel::Fresnel;
use crate::model::series::{self, LnQ};
use crate::model::shadowing::Shadowing;
use crate::model::{self, kbs::Kbs, EvalMode, Mode, Model, ModelOptions};
use proptest::prelude::*;
use std::f64::consts::PI;

const TOL: f64 = 1e-10;

fn geo1(ti: f64, tr: f64, pr: f64, lambda: f64) -> Geometry {
    Geometry::new(
        &[Sample::from_degrees(ti, tr, pr)],
        &[lambda],
        Quantity::Radiance,
    )
    .unwrap()
}

fn kbs(mode: EvalMode, patch: Option<(f64, f64)>) -> Kbs {
    Kbs::new(ModelOptions {
        mode,
        tol: TOL,
        patch,
        ..ModelOptions::default()
    })
    .unwrap()
}

/// The KBS models and modes the Fresnel and shadowing factors are checked on.
const FACTOR_MODELS: [(&str, EvalMode); 5] = [
    ("kbs", EvalMode::Auto),
    ("kbs", EvalMode::Series),
    ("kbs-smooth", EvalMode::Smooth),
    ("kbs-rough", EvalMode::Rough),
    ("kbs+lambert", EvalMode::Auto),
];

/// Every Fresnel form, each with a shadowing form.
const FACTORS: [(Fresnel, Shadowing); 4] = [
    (Fresnel::Dielectric, Shadowing::Smith),
    (Fresnel::Conductor, Shadowing::SmithCorrelated),
    (Fresnel::Schlick, Shadowing::None),
    (Fresnel::None, Shadowing::Smith),
];

fn with_factors(
    name: &str,
    mode: EvalMode,
    fresnel: Fresnel,
    shadowing: Shadowing,
) -> Box<dyn Model> {
    let opts = ModelOptions {
        mode,
        tol: TOL,
        fresnel,
        shadowing,
        ..ModelOptions::default()
    };
    model::by_name(name, &opts).unwrap()
}

/// Analytic Jacobian column j against a central difference in ln p_j (relative step h).
/// `jump` is the relative size of a possible discontinuity of the value (the tolerance of
/// `auto` at a switch point), which a difference quotient magnifies by 1/h.
fn check_jacobian(m: &dyn Model, geo: &Geometry, p: &[f64], jump: f64) -> Result<(), String> {
    let np = p.len();
    let mut out = vec![0.0];
    let mut jac = vec![0.0; np];
    m.radiance(geo, p, &mut out, Some(&mut jac));
    let l = out[0];
    if !(l.is_normal() && l > 1e-250) {
        return Ok(()); // nothing to difference
    }
    let h = 1e-6;
    for j in 0..np {
        let mut pp = p.to_vec();
        let mut pm = p.to_vec();
        pp[j] = p[j] * (1.0 + h);
        pm[j] = p[j] * (1.0 - h);
        let (mut lp, mut lm) = (vec![0.0], vec![0.0]);
        m.radiance(geo, &pp, &mut lp, None);
        m.radiance(geo, &pm, &mut lm, None);
        // d L / d ln p_j
        let fd = (lp[0] - lm[0]) / (2.0 * h);
        let an = jac[j] * p[j];
        // Truncation O(h² L''') and rounding O(ε L / h), plus a possible mode jump.
        let allow = 1e-5 * (an.abs() + l) + 2.0 * jump * l / h;
        if (fd - an).abs() > allow {
            return Err(format!(
                "{}: ∂L/∂ln {} analytic {an:e} vs central difference {fd:e} (L = {l:e}, p = {p:?})",
                m.name(),
                m.params()[j].name
            ));
        }
    }
    Ok(())
}

fn angle_ti() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), Just(89.99), Just(45.0), 0.0..89.99f64]
}
fn angle_tr() -> impl Strategy<Value = f64> {
    prop_oneof![Just(0.0), Just(90.0), Just(89.99), 0.0..=90.0f64]
}
fn angle_pr() -> impl Strategy<Value = f64> {
    prop_oneof![
        Just(0.0),
        Just(180.0),
        Just(-180.0),
        Just(90.0),
        -360.0..=360.0f64
    ]
}
fn log_uniform(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    (lo.ln()..hi.ln()).prop_map(f64::exp)
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 400,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// Jacobians of every model against central differences, over the domain (σ/λ with
    /// g up to ~1e4, T/λ 1e-2..1e3 so that the value stays representable often enough).
    #[test]
    fn jacobians_match_central_differences(
        ti in 0.0..85.0f64, tr in 0.0..88.0f64, pr in -180.0..180.0f64,
        sigma in log_uniform(1e-4, 15.0), tq in log_uniform(0.3, 30.0),
        s in log_uniform(0.1, 10.0), sd in log_uniform(0.01, 1.0),
        w in log_uniform(0.02, 1.0), n in 1.01..4.0f64, kappa in log_uniform(1e-3, 10.0),
    ) {
        let geo = geo1(ti, tr, pr, 1.0);
        let corr = sigma * tq;
        // The KBS lobe times the Fresnel and shadowing factors, in every mode and model.
        for (name, mode) in FACTOR_MODELS {
            for (fresnel, shadowing) in FACTORS {
                let m = with_factors(name, mode, fresnel, shadowing);
                let mut p = vec![sigma, corr, s];
                if name == "kbs+lambert" {
                    p.push(sd);
                }
                p.extend([n, kappa].into_iter().take(fresnel.param_count()));
                let jump = if mode == EvalMode::Auto { TOL } else { 1e-15 };
                check_jacobian(m.as_ref(), &geo, &p, jump).map_err(TestCaseError::fail)?;
            }
        }
        for mode in [EvalMode::Auto, EvalMode::Series, EvalMode::Smooth, EvalMode::Rough] {
            let jump = if mode == EvalMode::Auto { TOL } else { 1e-15 };
            let k = kbs(mode, None);
            check_jacobian(&k, &geo, &[sigma, corr, s], jump).map_err(TestCaseError::fail)?;
            let kp = kbs(mode, Some((50.0, 30.0)));
            check_jacobian(&kp, &geo, &[sigma, corr, s], jump).map_err(TestCaseError::fail)?;
        }
        let opts = ModelOptions::default();
        let kl = model::by_name("kbs+lambert", &opts).unwrap();
        check_jacobian(kl.as_ref(), &geo, &[sigma, corr, s, sd], TOL).map_err(TestCaseError::fail)?;
        let la = model::by_name("lambert", &opts).unwrap();
        check_jacobian(la.as_ref(), &geo, &[s], 1e-15).map_err(TestCaseError::fail)?;
        let ls = model::by_name("lambert-specular", &opts).unwrap();
        check_jacobian(ls.as_ref(), &geo, &[s, sd, w], 1e-15).map_err(TestCaseError::fail)?;
    }

    /// No NaN, inf or panic anywhere in the domain, including grazing, mirror and
    /// backscatter directions, g from ~1e-14 to ~1e6 and T/λ from 1e-3 to 1e5.
    #[test]
    fn finite_everywhere(
        ti in angle_ti(), tr in angle_tr(), pr in angle_pr(),
        mirror in prop::bool::ANY, back in prop::bool::ANY,
        sigma in log_uniform(1e-7, 80.0), t in log_uniform(1e-3, 1e5),
        lambda in log_uniform(0.3, 3.0), patch in prop::bool::ANY,
    ) {
        let (tr, pr) = if mirror { (ti, if back { 180.0 } else { 0.0 }) } else { (tr, pr) };
        let geo = geo1(ti, tr, pr, lambda);
        let patch = if patch { Some((1e4, 2e4)) } else { None };
        for mode in [EvalMode::Auto, EvalMode::Series, EvalMode::Smooth, EvalMode::Rough] {
            let k = kbs(mode, patch);
            let p = [sigma * lambda, t * lambda, 1.0];
            let mut out = [0.0];
            let mut jac = [0.0; 3];
            k.radiance(&geo, &p, &mut out, Some(&mut jac));
            prop_assert!(out[0].is_finite() && out[0] >= 0.0, "{mode:?}: L = {}", out[0]);
            prop_assert!(jac.iter().all(|v| v.is_finite()), "{mode:?}: J = {jac:?}");
            let mut out2 = [0.0];
            k.eval(&geo, &p, &mut out2, None);
            prop_assert_eq!(out2[0], out[0]);
            for (fresnel, shadowing) in FACTORS {
                let m = with_factors("kbs", mode, fresnel, shadowing);
                let p = [sigma * lambda, t * lambda, 1.0, 1.01 + 3.0 * t.fract(), 10.0 * t.fract()];
                let p = &p[..3 + fresnel.param_count()];
                let mut jac = [0.0; 5];
                m.radiance(&geo, p, &mut out, Some(&mut jac[..p.len()]));
                prop_assert!(out[0].is_finite() && out[0] >= 0.0, "{fresnel:?}: L = {}", out[0]);
                prop_assert!(jac.iter().all(|v| v.is_finite()), "{fresnel:?}: J = {jac:?}");
            }
        }
    }

    /// ln Q and its derivatives are finite for g in [1e-12, 1e6] and a in [0, 1e8].
    #[test]
    fn lnq_finite(lg in -12.0..6.0f64, la in -12.0..8.0f64, zero_a in prop::bool::ANY) {
        let g = 10f64.powf(lg);
        let a = if zero_a { 0.0 } else { 10f64.powf(la) };
        for mode in [EvalMode::Auto, EvalMode::Series] {
            let q = series::ln_q(g, a, mode, TOL);
            prop_assert!(q.ln_q.is_finite() && q.d_g.is_finite() && q.d_a.is_finite(),
                "{mode:?} g={g} a={a}: {q:?}");
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 3000,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    /// `auto` against the converged series (itself checked against mpmath) densely over
    /// the region where auto's cheap paths operate: every path meets the stated accuracy.
    #[test]
    fn auto_agrees_with_series(lg in -12.0..5.0f64, b in 0.0..4.0f64, wide in prop::bool::ANY) {
        let g = 10f64.powf(lg);
        // a = b g^1.5 spans the asymptotic region's edge (a < 3 g^1.5); `wide` adds a ≫ g.
        let a = if wide { b * 50.0 * (1.0 + g * g.sqrt()) } else { b * g * g.sqrt() };
        let qa = series::auto(g, a, TOL);
        let qs = series::series(g, a, 1e-14);
        let d_lnq = (qa.ln_q - qs.ln_q).abs();
        let gs = g * qs.d_g;
        let as_ = a * qs.d_a;
        let d_g = (g * qa.d_g - gs).abs() / (1.0 + gs.abs());
        let d_a = (a * qa.d_a - as_).abs() / (1.0 + as_.abs());
        let round = 64.0 * f64::EPSILON * (1.0 + qs.ln_q.abs() + g.sqrt());
        prop_assert!(
            d_lnq <= TOL + round && d_g <= TOL + round && d_a <= TOL + round,
            "g={g:e} a={a:e} mode {:?}: Δ ln Q {d_lnq:e}, Δ g d_g {d_g:e}, Δ a d_a {d_a:e}",
            qa.mode
        );
    }
}

/// Locate the g where `auto`'s mode changes between g_lo and g_hi (a fixed), by bisection.
fn switch_point(a: f64, mut g_lo: f64, mut g_hi: f64) -> Option<(f64, f64)> {
    let m_lo = series::auto(g_lo, a, TOL).mode;
    if series::auto(g_hi, a, TOL).mode == m_lo {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (g_lo + g_hi);
        if mid <= g_lo || mid >= g_hi {
            break;
        }
        if series::auto(mid, a, TOL).mode == m_lo {
            g_lo = mid;
        } else {
            g_hi = mid;
        }
    }
    Some((g_lo, g_hi))
}

#[test]
fn auto_is_continuous_across_its_switches() {
    let mut found = 0;
    for &a in &[0.0, 0.01, 1.0, 5.0, 30.0, 100.0, 400.0, 1e3, 3e3] {
        // Scan g on a log grid for mode changes, then bisect each to adjacent floats.
        let grid: Vec<f64> = (0..=360)
            .map(|i| 10f64.powf(-12.0 + i as f64 / 20.0))
            .collect();
        for w in grid.windows(2) {
            if let Some((lo, hi)) = switch_point(a, w[0], w[1]) {
                let (ql, qh): (LnQ, LnQ) = (series::auto(lo, a, TOL), series::auto(hi, a, TOL));
                assert_ne!(ql.mode, qh.mode);
                let d_lnq = (ql.ln_q - qh.ln_q).abs();
                let d_gdg = (lo * ql.d_g - hi * qh.d_g).abs() / (1.0 + (lo * ql.d_g).abs());
                let d_ada = (a * ql.d_a - a * qh.d_a).abs() / (1.0 + (a * ql.d_a).abs());
                assert!(
                    d_lnq <= 2.0 * TOL && d_gdg <= 2.0 * TOL && d_ada <= 2.0 * TOL,
                    "a={a}: switch {:?}→{:?} at g={lo:e}: Δ ln Q {d_lnq:e}, Δ g d_g {d_gdg:e}, Δ a d_a {d_ada:e}",
                    ql.mode,
                    qh.mode
                );
                found += 1;
            }
        }
    }
    println!("checked {found} switch points");
    assert!(found >= 10, "only {found} switch points found");
}

#[test]
fn auto_uses_cheap_modes_where_they_are_exact() {
    // Small g: smooth; large g with a/g^1.5 small: rough completion.
    assert_eq!(series::auto(1e-12, 1.0, TOL).mode, Mode::Smooth);
    assert_eq!(series::auto(1e3, 500.0, TOL).mode, Mode::Rough);
    assert_eq!(series::auto(1e6, 1e8, TOL).mode, Mode::Rough);
}

/// Figures 6–7: θi = 45°, T/σ = 5, rough approximation.
#[test]
fn figures_6_7_peak_moves_from_mirror_to_normal() {
    let m = kbs(EvalMode::Rough, None);
    let p = [1.0, 5.0, 1.0];
    let curve = |phi: f64| -> Vec<f64> {
        let samples: Vec<Sample> = (0..=900)
            .map(|i| Sample::from_degrees(45.0, i as f64 * 0.1, phi))
            .collect();
        let geo = Geometry::new(&samples, &[1.0], Quantity::Radiance).unwrap();
        let mut out = vec![0.0; samples.len()];
        m.radiance(&geo, &p, &mut out, None);
        out
    };
    let argmax = |v: &[f64]| -> usize {
        (0..v.len())
            .max_by(|&i, &j| v[i].partial_cmp(&v[j]).unwrap())
            .unwrap()
    };
    let c0 = curve(0.0);
    assert_eq!(
        argmax(&c0),
        450,
        "φr = 0 peaks at the mirror angle θr = 45°"
    );
    let mut last = 450;
    for phi in (5..=90).step_by(5) {
        let c = curve(phi as f64);
        let k = argmax(&c);
        assert!(k <= last, "peak moved back up at φr = {phi}: {k} > {last}");
        last = k;
        if phi == 90 {
            assert_eq!(k, 0, "φr = 90° peaks at θr = 0");
            let rel = (c[k] / c0[0] - 1.0).abs();
            assert!(
                rel < 1e-14,
                "peak value at φr = 90° equals φr = 0 at θr = 0 ({rel:e})"
            );
        }
    }
}

/// sin x / x.
fn sinc(x: f64) -> f64 {
    if x == 0.0 {
        1.0
    } else {
        x.sin() / x
    }
}

/// eq. 37 and 28 written directly in the paper's form (F, A = 4XY), with S summed naively
/// (fine for the small g used here).
#[allow(clippy::too_many_arguments)]
fn paper_form(ti: f64, tr: f64, pr: f64, lambda: f64, sigma: f64, t: f64, x: f64, y: f64) -> f64 {
    let (ti, tr, pr) = (ti.to_radians(), tr.to_radians(), pr.to_radians());
    let k = 2.0 * PI / lambda;
    let vx = k * (ti.sin() - tr.sin() * pr.cos());
    let vy = -k * tr.sin() * pr.sin();
    let vz = -k * (ti.cos() + tr.cos());
    let g = sigma * sigma * vz * vz;
    let a = (vx * vx + vy * vy) * t * t / 4.0;
    let f = (1.0 + ti.cos() * tr.cos() - ti.sin() * tr.sin() * pr.cos())
        / (ti.cos() * (ti.cos() + tr.cos()));
    let mut s_sum = 0.0;
    let mut gm_over_fact = 1.0;
    for m in 1..60 {
        gm_over_fact *= g / m as f64;
        s_sum += gm_over_fact / m as f64 * (-a / m as f64).exp();
    }
    let area = 4.0 * x * y;
    let rho0 = sinc(vx * x) * sinc(vy * y);
    let rho2 = (-g).exp() * (rho0 * rho0 + PI * t * t * f * f / area * s_sum);
    ti.cos().powi(2) * rho2
}

#[test]
fn coherent_term_with_patch() {
    let (x, y) = (3.0, 2.0); // patch half-sizes in λ (small, so the spike is visible)
    let (sigma, t) = (0.05, 0.8);
    let with = kbs(EvalMode::Auto, Some((x, y)));
    let series_m = kbs(EvalMode::Series, Some((x, y)));
    for &(ti, tr, pr) in &[
        (30.0, 30.0, 0.0), // mirror: ρ0 = 1
        (30.0, 32.0, 0.0),
        (30.0, 30.0, 3.0),
        (60.0, 20.0, 150.0),
    ] {
        let geo = geo1(ti, tr, pr, 1.0);
        let expect = paper_form(ti, tr, pr, 1.0, sigma, t, x, y);
        for m in [&with, &series_m] {
            let mut out = [0.0];
            m.radiance(&geo, &[sigma, t, 1.0], &mut out, None);
            assert!(
                (out[0] / expect - 1.0).abs() < 1e-9,
                "({ti},{tr},{pr}): {} vs paper form {expect}",
                out[0]
            );
        }
    }
    // At the mirror the coherent part is exactly s cos²θi e^{−g}.
    let geo = geo1(30.0, 30.0, 0.0, 1.0);
    let no_patch = kbs(EvalMode::Auto, None);
    let (mut lp, mut ln) = ([0.0], [0.0]);
    with.radiance(&geo, &[sigma, t, 2.0], &mut lp, None);
    no_patch.radiance(&geo, &[sigma, t, 2.0], &mut ln, None);
    let g = (2.0 * PI * sigma * 2.0 * 30f64.to_radians().cos()).powi(2);
    let coherent = lp[0] - ln[0] / (4.0 * x * y);
    let expect = 2.0 * 30f64.to_radians().cos().powi(2) * (-g).exp();
    assert!(
        (coherent / expect - 1.0).abs() < 1e-12,
        "{coherent} vs {expect}"
    );
}

#[test]
fn incoherent_model_matches_paper_form_without_patch() {
    // A = λ² without a patch: the paper form with 4XY = λ² and ρ0 → 0.
    for &(ti, tr, pr) in &[(10.0, 50.0, 30.0), (45.0, 45.0, 0.0), (80.0, 89.0, 170.0)] {
        let geo = geo1(ti, tr, pr, 0.5);
        let (sigma, t) = (0.02, 0.3);
        let m = kbs(EvalMode::Auto, None);
        let mut out = [0.0];
        m.radiance(&geo, &[sigma, t, 1.0], &mut out, None);
        let with_coh = paper_form(ti, tr, pr, 0.5, sigma, t, 0.25, 0.25);
        let k = 2.0 * PI / 0.5;
        let (tir, trr, prr) = (ti.to_radians(), tr.to_radians(), pr.to_radians());
        let rho0 = sinc(k * (tir.sin() - trr.sin() * prr.cos()) * 0.25)
            * sinc(-k * trr.sin() * prr.sin() * 0.25);
        let g = (sigma * k * (tir.cos() + trr.cos())).powi(2);
        let expect = with_coh - tir.cos().powi(2) * (-g).exp() * rho0 * rho0;
        assert!(
            (out[0] / expect - 1.0).abs() < 1e-9,
            "{} vs {expect}",
            out[0]
        );
    }
}

/// The extended lobe is the plain lobe times F(θ_loc) G(θi, θr), each factor as its module
/// computes it from the sample's angles: cos θ_loc = √((1 + ŝ·k̂₂)/2) from the vectors.
#[test]
fn extended_lobe_is_the_plain_lobe_times_its_factors() {
    use crate::model::shadowing::cot;
    let (sigma, corr, n, kappa) = (0.4, 3.0, 1.7, 0.8);
    for (ti, tr, pr) in [
        (10.0, 20.0, 0.0),
        (60.0, 70.0, 30.0),
        (85.0, 89.9, 0.0),
        (45.0, 30.0, 180.0),
    ] {
        let geo = geo1(ti, tr, pr, 1.0);
        let (ti_r, tr_r, pr_r) = (
            f64::to_radians(ti),
            f64::to_radians(tr),
            f64::to_radians(pr),
        );
        let s_hat = [-ti_r.sin(), 0.0, ti_r.cos()];
        let k2 = [tr_r.sin() * pr_r.cos(), tr_r.sin() * pr_r.sin(), tr_r.cos()];
        let dot: f64 = s_hat.iter().zip(&k2).map(|(a, b)| a * b).sum();
        let cos_loc = ((1.0 + dot) / 2.0).sqrt();
        let mut plain = [0.0];
        kbs(EvalMode::Series, None).radiance(&geo, &[sigma, corr, 1.0], &mut plain, None);
        for (fresnel, shadowing) in FACTORS {
            let m = with_factors("kbs", EvalMode::Series, fresnel, shadowing);
            let p = [sigma, corr, 1.0, n, kappa];
            let mut out = [0.0];
            m.radiance(&geo, &p[..3 + fresnel.param_count()], &mut out, None);
            let f = fresnel.eval(cos_loc, &[n, kappa]).f;
            let g = shadowing.eval(cot(ti_r), cot(tr_r), corr / sigma).g;
            let want = plain[0] * f * g;
            assert!(
                (out[0] - want).abs() <= 1e-12 * want,
                "{ti},{tr},{pr} {fresnel:?}: {} vs {want}",
                out[0]
            );
        }
    }
}
