//! The Fresnel and Smith factors of the KBS lobe against the 30-digit mpmath reference in
//! `tests/ref/` (`tests/ref/fresnel_shadowing.py`, committed with its output: the textbook
//! Snell/r_s/r_p and erf forms, derivatives by high-precision numerical differentiation),
//! closed forms, and central differences.
//!
//! The lobe with its factors is checked as the product of the plain lobe and the factors,
//! values and every Jacobian column, at θ up to 89.9°. Smith's G is also compared with
//! NIST SCATMECH's shadowed facet model
//! (`tests/ref/scatmech_shadowing.py` and its output).
//!
//! Claims checked (module docs of `src/model/fresnel.rs` and `src/model/shadowing.rs`):
//! F and G to 1e-13 relative; ∂F/∂n, ∂F/∂κ to 1e-12 (|∂F| + F); ∂ln G/∂ln T to
//! 1e-13 (1 + |·|); Λ(ν) to 1e-15 (1 + Λ) (`tests/ref/smith_lambda.py`). Run with `-- --nocapture` to see the worst errors found.

use crate::model::fresnel::{complex_ratio, schlick_ratio, Fresnel};
use crate::model::shadowing::{lambda, Shadowing};

fn parse(s: &str) -> Option<f64> {
    (!s.is_empty()).then(|| s.parse::<f64>().unwrap())
}

fn rows(text: &str) -> Vec<Vec<Option<f64>>> {
    text.lines()
        .skip(1)
        .map(|l| l.split(',').map(parse).collect())
        .collect()
}

fn rel(got: f64, want: f64, scale: f64) -> f64 {
    (got - want).abs() / scale
}

#[test]
fn fresnel_matches_the_reference_at_extreme_angles_and_indices() {
    let (mut worst_f, mut worst_d) = (0.0f64, 0.0f64);
    for r in rows(include_str!("../ref/fresnel_reference.csv")) {
        let [c, n, k, f, dn, dk, s, ds] = r[..] else {
            panic!("row {r:?}")
        };
        let (c, n, k) = (c.unwrap(), n.unwrap(), k.unwrap());
        let (f, dn, dk) = (f.unwrap(), dn.unwrap(), dk.unwrap());
        let got = complex_ratio(c, n, k);
        let ef = rel(got.f, f, f);
        let ed = rel(got.d_n, dn, dn.abs() + f).max(rel(got.d_kappa, dk, dk.abs() + f));
        assert!(ef < 1e-13, "c={c} n={n} κ={k}: F {} vs {f}", got.f);
        assert!(ed < 1e-12, "c={c} n={n} κ={k}: {got:?} vs {dn}, {dk}");
        (worst_f, worst_d) = (worst_f.max(ef), worst_d.max(ed));
        if let (Some(s), Some(ds)) = (s, ds) {
            let got = schlick_ratio(c, n);
            assert!(
                rel(got.f, s, s) < 1e-13,
                "Schlick c={c} n={n}: {} vs {s}",
                got.f
            );
            assert!(
                rel(got.d_n, ds, ds.abs() + s) < 1e-12,
                "Schlick c={c} n={n}"
            );
            let via = Fresnel::Dielectric.eval(c, &[n]);
            let ed = rel(via.d_n, dn, dn.abs() + f);
            assert!(
                rel(via.f, f, f) < 1e-13 && ed < 1e-12,
                "dielectric c={c} n={n}: {via:?}"
            );
        }
    }
    println!("Fresnel: worst relative error of F {worst_f:.1e}, of ∂F {worst_d:.1e}");
}

#[test]
fn smith_matches_the_reference_at_extreme_angles() {
    let (mut worst_g, mut worst_d) = (0.0f64, 0.0f64);
    for r in rows(include_str!("../ref/smith_reference.csv")) {
        let [ci, cr, t, g, dg, gc, dgc] = r[..] else {
            panic!("row {r:?}")
        };
        let (ci, cr, t) = (ci.unwrap(), cr.unwrap(), t.unwrap());
        for (kind, g, d) in [
            (Shadowing::Smith, g.unwrap(), dg.unwrap()),
            (Shadowing::SmithCorrelated, gc.unwrap(), dgc.unwrap()),
        ] {
            // The cotangent path and the lobe's path from cot θ and tan θ = 1/cot θ.
            for got in [
                kind.eval(ci, cr, t),
                kind.eval_cot_tan((ci, 1.0 / ci), (cr, 1.0 / cr), t),
            ] {
                let (eg, ed) = (rel(got.g, g, g), rel(got.d_ln_t, d, 1.0 + d.abs()));
                assert!(
                    eg < 1e-13,
                    "{kind:?} cot {ci}, {cr}, T/σ {t}: {} vs {g}",
                    got.g
                );
                assert!(
                    ed < 1e-11,
                    "{kind:?} cot {ci}, {cr}, T/σ {t}: {got:?} vs {d}"
                );
                (worst_g, worst_d) = (worst_g.max(eg), worst_d.max(ed));
            }
        }
    }
    println!("Smith: worst relative error of G {worst_g:.1e}, of ∂lnG/∂lnT {worst_d:.1e}");
}

/// Smith's G against NIST SCATMECH's shadowed facet model (`tests/ref/scatmech_shadowing.py`,
/// its header says what is compared): SCATMECH's shadow function as its BRDF applies it,
/// divided by Smith's illumination factor (1 − ½ erfc(a)) per direction, at θ up to 89.5°,
/// in and out of the plane, T/σ from 1 to 20; G to 1e-13 relative, down to G ≈ 2e-4.
#[test]
fn smith_matches_scatmech_shadowed_facet_model() {
    let (mut worst, mut smallest, mut count) = (0.0f64, 1.0f64, 0);
    for r in rows(include_str!("../ref/scatmech_shadowing.csv")) {
        let [ti, tr, _phi, t, f, ill, g] = r[..] else {
            panic!("row {r:?}")
        };
        let [ti, tr, t, f, ill, g] = [ti, tr, t, f, ill, g].map(Option::unwrap);
        assert!(rel(g * ill, f, f) < 1e-15, "table row {r:?}");
        let ct = |deg: f64| crate::geometry::cot_tan(deg.to_radians());
        let got = Shadowing::Smith.eval_cot_tan(ct(ti), ct(tr), t).g;
        let e = rel(got, g, g);
        assert!(
            e < 1e-13,
            "θi {ti}°, θr {tr}°, T/σ {t}: G {got} vs SCATMECH {g}"
        );
        (worst, smallest, count) = (worst.max(e), smallest.min(g), count + 1);
    }
    assert!(
        count > 1000 && smallest < 1e-3,
        "{count} rows, smallest G {smallest}"
    );
    println!("SCATMECH: {count} rows, worst relative difference of G {worst:.1e}");
}

/// Λ(ν) across its three evaluations (libm's erfc below ν = 1.25, the Chebyshev pieces
/// [1.25, 2], [2, 3.5], [3.5, 6] and their edges, 0 beyond 6) against the dense table of
/// `tests/ref/smith_lambda.py`: Λ to 1e-15 (1 + Λ), ν ∂Λ/∂ν to 1e-15 (1 + |·|).
#[test]
fn smith_lambda_matches_the_dense_reference() {
    let (mut worst_l, mut worst_d) = (0.0f64, 0.0f64);
    for r in rows(include_str!("../ref/lambda_reference.csv")) {
        let [nu, l, d] = r[..] else {
            panic!("row {r:?}")
        };
        let (nu, l, d) = (nu.unwrap(), l.unwrap(), d.unwrap());
        let (got_l, got_d) = lambda(nu);
        let (el, ed) = (rel(got_l, l, 1.0 + l), rel(got_d, d, 1.0 + d.abs()));
        assert!(el < 1e-15, "ν = {nu}: Λ {got_l} vs {l}");
        assert!(ed < 1e-15, "ν = {nu}: ν∂Λ/∂ν {got_d} vs {d}");
        (worst_l, worst_d) = (worst_l.max(el), worst_d.max(ed));
    }
    println!(
        "Smith Λ: worst error of Λ {worst_l:.1e}, of ν∂Λ/∂ν {worst_d:.1e} (relative to 1 + |·|)"
    );
}

#[test]
fn closed_forms_hold() {
    for n in [1.01, 1.2, 1.5, 2.0, 3.3, 4.0] {
        let r0 = ((n - 1.0) / (n + 1.0)) * ((n - 1.0) / (n + 1.0));
        // R(θ)/R(0) at normal incidence is 1; R → 1 at grazing, so F → 1/R(0).
        assert!((complex_ratio(1.0, n, 0.0).f - 1.0).abs() < 1e-14);
        for (c, within) in [(0.0, 1e-13), (1e-9, 1e-6)] {
            let r = complex_ratio(c, n, 0.0).f * r0;
            assert!((r - 1.0).abs() < within, "n={n}, c={c}: R = {r}");
        }
        // The conductor form with κ = 0 is the dielectric one, and it is continuous there.
        for c in [0.01, 0.3, 0.9] {
            let d = Fresnel::Dielectric.eval(c, &[n]);
            let k0 = Fresnel::Conductor.eval(c, &[n, 0.0]);
            assert!(
                (k0.f - d.f).abs() < 1e-14 * d.f
                    && (k0.d_n - d.d_n).abs() < 1e-13 * (d.f + d.d_n.abs())
            );
            assert_eq!(k0.d_kappa, 0.0);
            let k = Fresnel::Conductor.eval(c, &[n, 1e-9]);
            assert!(
                (k.f - d.f).abs() < 1e-11 * d.f,
                "n={n} c={c}: {k:?} vs {d:?}"
            );
        }
        // Schlick is exact at normal incidence and at grazing.
        assert_eq!(schlick_ratio(1.0, n).f, 1.0);
        assert!((schlick_ratio(0.0, n).f * r0 - 1.0).abs() < 1e-14);
    }
    // A perfect conductor (κ → ∞) reflects everything at every angle: F → 1.
    assert!((complex_ratio(0.3, 1.0, 1e6).f - 1.0).abs() < 1e-5);
    // G → 1 as σ/T → 0, at every angle below 90°; G = 0 at 90°; G = 1 at normal incidence.
    for kind in [Shadowing::Smith, Shadowing::SmithCorrelated] {
        let cot89 = 89.9f64.to_radians().cos() / 89.9f64.to_radians().sin();
        assert_eq!(kind.eval(cot89, cot89, 1e9).g, 1.0);
        assert_eq!(kind.eval(cot89, 0.0, 5.0).g, 0.0);
        assert_eq!(kind.eval(f64::INFINITY, f64::INFINITY, 0.1).g, 1.0);
        let g = kind.eval(cot89, 1.0, 1e-3).g;
        assert!(g > 0.0 && g < 1e-5, "{kind:?}: {g}");
    }
    // Λ at ν → 0 is 1/(2√π ν) − ½ + O(ν).
    let nu = 1e-8;
    let want = 1.0 / (2.0 * std::f64::consts::PI.sqrt() * nu) - 0.5;
    assert!((lambda(nu).0 - want).abs() < 1e-7);
}

/// Central difference of `f` at `x` with step `h`.
fn central(f: impl Fn(f64) -> f64, x: f64, h: f64) -> f64 {
    (f(x + h) - f(x - h)) / (2.0 * h)
}

#[test]
fn fresnel_derivatives_match_central_differences_over_the_domain() {
    for deg in [0.0, 20.0, 50.0, 70.0, 80.0, 88.0, 89.9] {
        let c = f64::to_radians(deg).cos();
        for n in [0.3, 1.01, 1.2, 1.7, 2.6, 4.0] {
            for k in [0.0, 0.05, 1.0, 4.0, 10.0] {
                if n < 1.0 && k == 0.0 {
                    // Beyond the critical angle F has a kink at κ = 0 (module doc).
                    continue;
                }
                let v = complex_ratio(c, n, k);
                let hn = 1e-6 * n;
                let dn = central(|x| complex_ratio(c, x, k).f, n, hn);
                let dk = central(|x| complex_ratio(c, n, x).f, k, 1e-6);
                let scale = v.f + v.d_n.abs() + v.d_kappa.abs();
                assert!(
                    (dn - v.d_n).abs() < 1e-6 * scale,
                    "∂n at {deg}°, n={n}, κ={k}"
                );
                assert!(
                    (dk - v.d_kappa).abs() < 1e-6 * scale,
                    "∂κ at {deg}°, n={n}, κ={k}"
                );
            }
            if n != 1.01 {
                let v = schlick_ratio(c, n);
                let d = central(|x| schlick_ratio(c, x).f, n, 1e-6 * n);
                assert!(
                    (d - v.d_n).abs() < 1e-6 * (v.f + v.d_n.abs()),
                    "Schlick {deg}° {n}"
                );
            }
        }
    }
}

#[test]
fn smith_derivatives_match_central_differences_over_the_domain() {
    let cots = [f64::INFINITY, 3.0, 1.0, 0.3, 0.05, 1.7e-3];
    for kind in [Shadowing::Smith, Shadowing::SmithCorrelated] {
        for ci in cots {
            for cr in cots {
                for t in [0.5, 2.0, 5.0, 30.0, 500.0] {
                    let v = kind.eval(ci, cr, t);
                    let ln_g = |lt: f64| kind.eval(ci, cr, lt.exp()).g.ln();
                    let d = central(ln_g, t.ln(), 1e-6);
                    assert!(
                        (d - v.d_ln_t).abs() < 1e-6 * (1.0 + v.d_ln_t.abs()),
                        "{kind:?} cot {ci} {cr} T/σ {t}: {d} vs {}",
                        v.d_ln_t
                    );
                }
            }
        }
    }
}

/// The lobe with its factors at extreme angles (θi, θr up to 89.9°, in and out of the
/// plane), n from 1.01 to 4, κ up to 10: its value is the plain lobe times F(θ_loc) and G
/// (each held to the references above), and every Jacobian column is the product rule's
/// from the plain lobe's columns and the factors' derivatives, to 1e-12 relative of the
/// column's terms. Series mode (the plain lobe's own accuracy is tests/lib/kbs_reference.rs').
#[test]
fn the_lobe_with_factors_is_the_product_at_extreme_angles() {
    use crate::geometry::{Geometry, Quantity, Sample};
    use crate::model::fresnel::cos_local;
    use crate::model::{by_name, EvalMode, ModelOptions};
    let lobe = |fresnel, shadowing| {
        let opts = ModelOptions {
            mode: EvalMode::Series,
            fresnel,
            shadowing,
            ..ModelOptions::default()
        };
        by_name("kbs", &opts).unwrap()
    };
    let plain = lobe(Fresnel::None, Shadowing::None);
    let close = |got: f64, want: f64, scale: f64| (got - want).abs() <= 1e-12 * scale.abs();
    let mut checked = 0;
    for (ti, tr, pr) in [
        (89.9, 89.9, 0.0),
        (89.9, 60.0, 0.0),
        (0.0, 89.9, 90.0),
        (85.0, 89.5, 180.0),
        (89.5, 30.0, 45.0),
        (70.0, 70.0, 0.0),
    ] {
        let geo = Geometry::new(
            &[Sample::from_degrees(ti, tr, pr)],
            &[1.0],
            Quantity::Radiance,
        )
        .unwrap();
        let cot = |t: f64| 1.0 / t.to_radians().tan();
        for (sigma, t_over_sigma) in [(0.05, 2.0), (0.3, 20.0), (2.0, 5.0)] {
            let p0 = [sigma, sigma * t_over_sigma, 1.0];
            let (mut l0, mut j0) = ([0.0], [0.0; 3]);
            plain.radiance(&geo, &p0, &mut l0, Some(&mut j0));
            assert!(
                l0[0] > 0.0,
                "θi {ti}, θr {tr}, σ {sigma}: L = 0 would check nothing"
            );
            for (fresnel, fp) in [
                (Fresnel::Dielectric, [1.01, 0.0]),
                (Fresnel::Dielectric, [4.0, 0.0]),
                (Fresnel::Conductor, [0.2, 10.0]),
                (Fresnel::Conductor, [1.5, 3.0]),
            ] {
                let m = lobe(fresnel, Shadowing::Smith);
                let p: Vec<f64> = p0
                    .iter()
                    .chain(&fp[..fresnel.param_count()])
                    .copied()
                    .collect();
                let (mut l, mut j) = ([0.0], vec![0.0; p.len()]);
                m.radiance(&geo, &p, &mut l, Some(&mut j));
                let f = fresnel.eval(cos_local(geo.h(0)), &fp);
                let g = Shadowing::Smith.eval(cot(ti), cot(tr), t_over_sigma);
                let what = format!("θi {ti}, θr {tr}, φr {pr}, σ {sigma}, {fresnel:?} {fp:?}");
                assert!(
                    close(l[0], l0[0] * f.f * g.g, l[0]),
                    "{what}: L {} vs {}",
                    l[0],
                    l0[0]
                );
                // ∂ln G/∂ln T = −∂ln G/∂ln σ.
                let dg_t = l[0] * g.d_ln_t / p[1];
                let dg_s = -l[0] * g.d_ln_t / p[0];
                let fg = f.f * g.g;
                let scale = |a: f64, b: f64| a.abs() + b.abs() + f64::MIN_POSITIVE;
                assert!(
                    close(j[0], j0[0] * fg + dg_s, scale(j0[0] * fg, dg_s)),
                    "{what}: ∂σ"
                );
                assert!(
                    close(j[1], j0[1] * fg + dg_t, scale(j0[1] * fg, dg_t)),
                    "{what}: ∂T"
                );
                assert!(close(j[2], j0[2] * fg, j[2]), "{what}: ∂s");
                // F's derivatives to their accuracy, 1e-12 (|∂F| + F) (the lobe's Jacobian
                // evaluates F in other lanes than `Fresnel::eval`).
                let (lit, d_n) = (l0[0] * g.g, l0[0] * g.g * f.d_n);
                assert!(
                    close(j[3], d_n, scale(d_n, lit * f.f)),
                    "{what}: ∂n {} vs {d_n}",
                    j[3]
                );
                if fresnel == Fresnel::Conductor {
                    let d_k = l0[0] * g.g * f.d_kappa;
                    assert!(
                        close(j[4], d_k, scale(d_k, lit * f.f)),
                        "{what}: ∂κ {} vs {d_k}",
                        j[4]
                    );
                }
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 72);
}
