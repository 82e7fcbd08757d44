//! The `validity` section: whether the fitted surface satisfies the paper's assumptions
//! (radius of curvature ≫ λ, shadowing negligible), a warning that never fails the fit.

use crate::common;

use common::{fit_json, success_stdout};

/// Synthesise a KBS scan (1 % noise) into `dir` with the extra synth arguments, fit it with
/// kbs, and return the JSON report.
fn synth_and_fit(dir: &std::path::Path, params: &str, layout: &[&str]) -> serde_json::Value {
    let csv = dir.join("scan.csv");
    let csv = csv.to_str().unwrap();
    let mut synth = vec![
        "synth", "--model", "kbs", "--params", params, "--noise", "0.01", "--seed", "4", "--out",
        csv,
    ];
    synth.extend_from_slice(layout);
    success_stdout(&synth);
    // Exit 0 either way: a violated assumption is a warning, not a failure.
    fit_json(&["fit", "--model", "kbs", "--no-intervals", "--json", csv])
}

#[test]
fn a_gentle_surface_seen_below_60_degrees_satisfies_both_assumptions() {
    let dir = tempfile::tempdir().unwrap();
    // T/σ = 20 (rms slope √2σ/T = 0.071), R = T²/(√12σ) = 11.5 λ, θ ≤ 60°.
    let layout = [
        "--layout",
        "inplane",
        "--theta-i",
        "15,30,45,60",
        "--theta-r-max",
        "60",
    ];
    let j = synth_and_fit(dir.path(), "sigma=0.1,T=2,scale=1", &layout);
    assert_eq!(j["verdict"], "full");
    let v = &j["validity"];
    assert_eq!(v["curvature"]["satisfied"], true, "{v}");
    assert_eq!(v["shadowing"]["satisfied"], true, "{v}");
    let r = v["curvature"]["value"].as_f64().unwrap();
    assert!((r / 11.547 - 1.0).abs() < 0.01, "R/λ = {r}");
    assert!(v["shadowing"]["value"].as_f64().unwrap() < 1e-3);
}

#[test]
fn a_steep_surface_seen_to_grazing_violates_both_and_the_text_says_so() {
    let dir = tempfile::tempdir().unwrap();
    // T/σ = 2.7 (rms slope 0.53), R = 0.62 λ, θ up to 86°.
    let layout = ["--layout", "hemisphere", "--grid", "4x12x24"];
    let j = synth_and_fit(dir.path(), "sigma=0.3,T=0.8,scale=1", &layout);
    assert_eq!(j["converged"], true);
    let v = &j["validity"];
    assert_eq!(v["curvature"]["satisfied"], false, "{v}");
    assert_eq!(v["shadowing"]["satisfied"], false, "{v}");
    assert!(v["curvature"]["value"].as_f64().unwrap() < 1.0);
    assert!(v["shadowing"]["value"].as_f64().unwrap() > 0.5);
    let csv = dir.path().join("scan.csv");
    let text = success_stdout(&[
        "fit",
        "--model",
        "kbs",
        "--no-intervals",
        csv.to_str().unwrap(),
    ]);
    assert!(text.contains("[[Validity]]"), "{text}");
    assert!(
        text.contains("    curvature       = violated: rms radius of curvature"),
        "{text}"
    );
    assert!(text.contains("the model ignores shadowing there"), "{text}");
}

#[test]
fn in_the_rough_regime_only_the_slope_check_is_decided() {
    let path = common::data("synthetic/kbs_rough.csv");
    let j = fit_json(&[
        "fit",
        "--model",
        "kbs-rough",
        "--wavelength",
        "1",
        "--no-intervals",
        "--json",
        path.to_str().unwrap(),
    ]);
    let v = &j["validity"];
    assert!(v["curvature"]["satisfied"].is_null(), "{v}");
    assert!(v["curvature"]["text"]
        .as_str()
        .unwrap()
        .starts_with("not determined"));
    assert!(v["shadowing"]["satisfied"].is_boolean(), "{v}");
}
