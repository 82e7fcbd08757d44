//! Stiff and extreme cases: grazing incidence, huge g, extreme T/σ, nearly flat
//! data, a 1e6 dynamic range, gross outliers, starting points far off. Each fit either
//! succeeds — the truth is recovered within the reported uncertainty or a stated tolerance —
//! or stops with a clear reason; never NaN in a reported value, never a panic.

use crate::fit::driver::{fit, FitConfig, FitInput, FitResult, Verdict};
use crate::fit::problem::ResidualKind;
use crate::geometry::{Geometry, Quantity};
use crate::harness::synth::{generate, AnglesDeg, Layout, Noise, NoiseKind};
use crate::model::{by_name, ModelOptions};
use goniofit_lm::LmConfig;
use std::time::Duration;

/// Angles: every θi with θr in `theta_r` and φr in `phi_r` (degrees).
fn grid(theta_i: &[f64], theta_r: &[f64], phi_r: &[f64]) -> Vec<AnglesDeg> {
    let mut v = Vec::new();
    for &ti in theta_i {
        for &tr in theta_r {
            for &pr in phi_r {
                v.push(AnglesDeg {
                    theta_i: ti,
                    theta_r: tr,
                    phi_r: pr,
                });
            }
        }
    }
    v
}

fn steps(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|k| lo + (hi - lo) * k as f64 / (n - 1) as f64)
        .collect()
}

/// KBS data (σ, T, scale) on `angles`, λ = 1, relative noise `level`, weights 1/σ_L².
fn data(truth: [f64; 3], angles: &[AnglesDeg], level: f64, seed: u64) -> FitInput {
    let model = by_name("kbs", &ModelOptions::default()).unwrap();
    let noise = Noise {
        kind: NoiseKind::Relative,
        level,
        seed,
    };
    let d = generate(
        model.as_ref(),
        &truth,
        angles,
        1.0,
        Quantity::Radiance,
        &noise,
    )
    .unwrap();
    let max_sd = d.sigma_l.iter().fold(0.0f64, |m, v| m.max(*v));
    let weight = d
        .sigma_l
        .iter()
        .map(|s| {
            if max_sd > 0.0 {
                1.0 / s.max(1e-9 * max_sd).powi(2)
            } else {
                1.0
            }
        })
        .collect();
    FitInput {
        geo: Geometry::new(&d.samples, &[1.0], Quantity::Radiance).unwrap(),
        y: d.value.into(),
        weight,
        channel: vec![0; d.samples.len()].into(),
        channel_names: vec![String::new()],
    }
}

fn config() -> FitConfig {
    FitConfig {
        weights_are_uncertainties: true,
        lm: LmConfig {
            timeout: Some(Duration::from_secs(20)),
            ..LmConfig::default()
        },
        ..FitConfig::default()
    }
}

/// No NaN anywhere in what a report shows.
fn assert_finite(r: &FitResult) {
    for p in &r.params {
        assert!(p.value.is_finite(), "{} = {}", p.name, p.value);
        if let Some(se) = p.stderr {
            assert!(se.is_finite() && se >= 0.0, "se({}) = {se}", p.name);
        }
    }
    for d in &r.derived {
        assert!(!d.value.is_nan(), "{} = {}", d.name, d.value);
        if let Some(se) = d.stderr {
            assert!(!se.is_nan(), "se({}) = {se}", d.name);
        }
    }
    assert!(r.cost.is_finite(), "cost {}", r.cost);
    assert!(r.fitted.iter().all(|v| v.is_finite()));
}

fn param(r: &FitResult, name: &str) -> (f64, Option<f64>) {
    let p = r.params.iter().find(|p| p.name == name).unwrap();
    (p.value, p.stderr)
}

fn derived(r: &FitResult, name: &str) -> (f64, Option<f64>) {
    let d = r.derived.iter().find(|d| d.name == name).unwrap();
    (d.value, d.stderr)
}

/// |value − truth| within k standard errors or a relative tolerance, whichever is larger.
fn assert_close(name: &str, (v, se): (f64, Option<f64>), truth: f64, k: f64, rel: f64) {
    let allowed = (k * se.unwrap_or(0.0)).max(rel * truth.abs());
    assert!(
        (v - truth).abs() <= allowed,
        "{name}: {v} vs truth {truth} (se {se:?}, allowed {allowed})"
    );
}

/// The determined quantities of a converged fit match the truth (σ, T, scale).
fn assert_recovered(r: &FitResult, truth: [f64; 3], rel: f64) {
    assert!(r.converged(), "did not converge: {}", r.termination);
    let ratio = truth[1] / truth[0];
    match r.verdict {
        Verdict::Full => {
            assert_close("sigma", param(r, "sigma"), truth[0], 4.0, rel);
            assert_close("T", param(r, "T"), truth[1], 4.0, rel);
            assert_close("scale", param(r, "scale"), truth[2], 4.0, rel);
        }
        Verdict::Rough => {
            assert_close("T/sigma", derived(r, "T/sigma"), ratio, 4.0, rel);
            assert_close(
                "amplitude",
                derived(r, "amplitude"),
                truth[2] * ratio * ratio,
                4.0,
                rel,
            );
        }
        Verdict::Smooth => {
            assert_close("T", param(r, "T"), truth[1], 4.0, rel);
            assert_close(
                "amplitude",
                derived(r, "amplitude"),
                truth[2] * truth[0] * truth[0],
                4.0,
                rel,
            );
        }
        v @ (Verdict::Partial | Verdict::NotComputed) => panic!("verdict {v:?}: {:?}", r.notes),
    }
}

#[test]
fn grazing_incidence_85_to_89_9() {
    let angles = grid(
        &[85.0, 87.0, 88.5, 89.5, 89.9],
        &steps(2.0, 88.0, 12),
        &steps(-150.0, 180.0, 12),
    );
    let truth = [0.2, 1.5, 2.0];
    let input = data(truth, &angles, 0.01, 1);
    assert!(input.y.iter().all(|v| v.is_finite()));
    let r = fit(&input, &config()).unwrap();
    assert_finite(&r);
    assert_recovered(&r, truth, 0.02);
}

#[test]
fn huge_g_up_to_1e4() {
    // g = (2πσ)²(cos θi + cos θr)² reaches 1e4 at σ = 8 near normal incidence and view.
    let angles = Layout::parse("hemisphere 3x9x12").unwrap().angles();
    let truth = [8.0, 80.0, 1.0];
    let input = data(truth, &angles, 0.01, 2);
    let r = fit(&input, &config()).unwrap();
    assert_finite(&r);
    let (_, g_max) = r.g_range.unwrap();
    assert!(g_max > 5e3, "g up to {g_max}");
    // Whatever the verdict, T/σ is determined in the rough regime.
    assert!(r.converged(), "{}", r.termination);
    assert_close("T/sigma", derived(&r, "T/sigma"), 10.0, 4.0, 0.02);
}

#[test]
fn ratio_t_over_sigma_from_1_5_to_50() {
    let angles = Layout::parse("hemisphere 3x9x12").unwrap().angles();
    for (k, truth) in [[0.5, 0.75, 1.0], [0.5, 25.0, 1.0]].into_iter().enumerate() {
        let input = data(truth, &angles, 0.01, 3 + k as u64);
        let r = fit(&input, &config()).unwrap();
        assert_finite(&r);
        assert!(
            r.converged(),
            "T/σ = {}: {}",
            truth[1] / truth[0],
            r.termination
        );
        assert_close(
            "T/sigma",
            derived(&r, "T/sigma"),
            truth[1] / truth[0],
            4.0,
            0.02,
        );
    }
}

#[test]
fn nearly_flat_data() {
    // T ≪ λ: the lobe is wider than the hemisphere, L varies by a few percent at most per θi.
    let angles = Layout::parse("hemisphere 3x9x12").unwrap().angles();
    let truth = [0.01, 0.03, 1.0];
    let input = data(truth, &angles, 0.01, 5);
    let r = fit(&input, &config()).unwrap();
    assert_finite(&r);
    // Either the fit converges and says what it cannot determine, or it stops with a reason.
    if r.converged() {
        // The fitted values reproduce the data to the noise level.
        assert!(r.reduced_chi2 < 2.0, "reduced χ² {}", r.reduced_chi2);
        for p in r.params.iter().filter(|p| p.determined) {
            assert!(p.stderr.is_some());
        }
    } else {
        assert!(!r.notes.is_empty());
    }
}

#[test]
fn dynamic_range_1e6_with_log_residuals() {
    // A sharp lobe (T = 12 λ, smooth surface): L spans more than six decades.
    let angles = Layout::parse("hemisphere 3x18x24").unwrap().angles();
    let truth = [0.03, 12.0, 1.0];
    let input = data(truth, &angles, 0.01, 6);
    let (lo, hi) = input.y.iter().fold((f64::INFINITY, 0.0f64), |(l, h), v| {
        (l.min(v.abs()), h.max(v.abs()))
    });
    assert!(hi / lo > 1e6, "dynamic range {}", hi / lo);
    // Relative noise: log residuals with unit weights are the natural fit.
    let cfg = FitConfig {
        residual: ResidualKind::Log,
        floor: Some(1e-300),
        weights_are_uncertainties: false,
        ..config()
    };
    let input = FitInput {
        weight: vec![1.0; input.y.len()].into(),
        ..input
    };
    let r = fit(&input, &cfg).unwrap();
    assert_finite(&r);
    assert_recovered(&r, truth, 0.05);
}

#[test]
fn gross_outliers() {
    let angles = Layout::parse("hemisphere 3x9x12").unwrap().angles();
    let truth = [0.3, 2.0, 1.5];
    let mut input = data(truth, &angles, 0.01, 7);
    // Five samples 10× too bright (a reflection off the sample holder, say).
    for i in [10, 77, 150, 201, 290] {
        input.y[i] *= 10.0;
    }
    let r = fit(&input, &config()).unwrap();
    assert_finite(&r);
    assert!(r.converged(), "{}", r.termination);
    // The outliers show up in the standardized residuals.
    let big = r.std_residuals.iter().filter(|z| z.abs() > 5.0).count();
    assert!(big >= 3, "{big} residuals beyond 5 s");
    // Robust enough in the determined quantities: within 25 %.
    let (t, _) = param(&r, "T");
    assert!((t / truth[1] - 1.0).abs() < 0.25, "T = {t}");
}

/// Starting values a factor 10–1000 away from the truth, on either side.
fn far_off_case(init: &[(&str, f64)]) {
    let angles = Layout::parse("hemisphere 3x9x12").unwrap().angles();
    let truth = [0.3, 2.0, 1.5];
    let input = data(truth, &angles, 0.01, 8);
    let cfg = FitConfig {
        init: init.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
        ..config()
    };
    let r = fit(&input, &cfg).unwrap();
    assert_finite(&r);
    if r.converged() && r.reduced_chi2 < 2.0 {
        assert_recovered(&r, truth, 0.02);
    } else {
        // A stop away from the truth must be visible: not converged (with a note saying
        // why), or a misfit far above the noise.
        assert!(
            (!r.converged() && !r.notes.is_empty()) || r.reduced_chi2 > 2.0,
            "init {init:?}: {} χ²/ν {}",
            r.termination,
            r.reduced_chi2
        );
    }
}

#[test]
fn starting_points_far_off_above() {
    far_off_case(&[("sigma", 3.0), ("T", 0.2), ("scale", 100.0)]);
}

#[test]
fn starting_points_far_off_below() {
    far_off_case(&[("sigma", 0.03), ("T", 20.0), ("scale", 0.01)]);
}

/// σ = λ/1000, T = 300 λ, scale = 1e-4: LM leaves the smooth corner towards σ ≫ λ, into the
/// same territory as [`starting_points_far_off_huge_sigma`].
#[test]
fn starting_points_far_off_extreme_below() {
    far_off_case(&[("sigma", 1e-3), ("T", 300.0), ("scale", 1e-4)]);
}

#[test]
fn starting_points_far_off_scale_only() {
    far_off_case(&[("scale", 1e6)]);
}

/// σ = 30 λ with T = λ/50. LM steps to σ ≫ λ, where the series sums O(√g) terms per sample
/// (up to 10⁷): one residual evaluation there would take minutes, and the LM time limit is
/// only checked between evaluations. `auto` does not sum the series beyond its stated
/// domain, and trial steps outside the model domain are rejected, so the fit ends promptly.
#[test]
fn starting_points_far_off_huge_sigma() {
    far_off_case(&[("sigma", 30.0), ("T", 0.02), ("scale", 1e4)]);
}
