//! Robust losses end to end: a KBS hemisphere scan with 1 % noise and 5 % gross outliers
//! (each a factor 3–20 too high or too low: a saturated pixel, a stray reflection, a
//! dropout), fitted with `--residual relative --loss soft_l1 --f-scale 0.03`, recovers σ and
//! T within 3 %; plain least squares (`--loss linear`) on the same file does not.

use crate::common;

use common::{fit_json, goniofit, success_stdout};
use rand::{Rng, SeedableRng};

const SIGMA: f64 = 0.25;
const T: f64 = 2.5;

/// The scan: `goniofit synth` (σ = 0.25λ, T = 2.5λ, intermediate regime, 3240 samples, 1 %
/// relative noise), then round(5 % · n) samples drawn without replacement (seed 7) and
/// multiplied or divided (even odds) by a factor uniform in [3, 20]. Returns the CSV path
/// and the number of outliers.
fn outlier_scan(dir: &std::path::Path) -> (std::path::PathBuf, usize) {
    let clean = dir.join("clean.csv");
    let params = format!("sigma={SIGMA},T={T},scale=1");
    let args = [
        "synth",
        "--model",
        "kbs",
        "--params",
        &params,
        "--layout",
        "hemisphere",
        "--noise",
        "0.01",
        "--seed",
        "5",
        "--out",
    ];
    let out = goniofit().args(args).arg(&clean).output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&clean).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    let header: Vec<&str> = lines[0].split(',').collect();
    let col = header.iter().position(|h| *h == "L").unwrap();
    let n = lines.len() - 1;
    let k = (0.05 * n as f64).round() as usize;
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let mut idx: Vec<usize> = (1..=n).collect();
    for i in 0..k {
        let j = rng.gen_range(i..n);
        idx.swap(i, j);
    }
    for &row in &idx[..k] {
        let factor: f64 = rng.gen_range(3.0..20.0);
        let up: bool = rng.gen();
        let mut fields: Vec<String> = lines[row].split(',').map(String::from).collect();
        let v: f64 = fields[col].parse().unwrap();
        fields[col] = format!("{:e}", if up { v * factor } else { v / factor });
        lines[row] = fields.join(",");
    }
    let path = dir.join("outliers.csv");
    std::fs::write(&path, lines.join("\n") + "\n").unwrap();
    (path, k)
}

/// `fit --model kbs --residual relative --loss LOSS --f-scale 0.03` of `path`, as text or
/// JSON, without intervals.
fn fit_args(path: &std::path::Path, loss: &str, json: bool) -> Vec<String> {
    let mut a: Vec<String> =
        "fit --model kbs --residual relative --f-scale 0.03 --no-intervals --loss"
            .split(' ')
            .map(String::from)
            .collect();
    a.push(loss.into());
    if json {
        a.push("--json".into());
    }
    a.push(path.to_str().unwrap().into());
    a
}

fn fit(path: &std::path::Path, loss: &str) -> serde_json::Value {
    let args = fit_args(path, loss, true);
    fit_json(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

fn rel_err(j: &serde_json::Value, name: &str, truth: f64) -> f64 {
    (j["params"][name]["value"].as_f64().unwrap() / truth - 1.0).abs()
}

#[test]
fn soft_l1_recovers_sigma_and_t_within_3_percent_where_linear_fails() {
    let dir = tempfile::tempdir().unwrap();
    let (path, k) = outlier_scan(dir.path());
    let robust = fit(&path, "soft_l1");
    assert_eq!(robust["converged"], true, "{robust}");
    let (es, et) = (rel_err(&robust, "sigma", SIGMA), rel_err(&robust, "T", T));
    assert!(
        es < 0.03 && et < 0.03,
        "soft_l1: σ off {es:.4}, T off {et:.4}"
    );
    assert_eq!(robust["setting"]["loss"], "soft_l1");
    assert_eq!(robust["setting"]["f_scale"], 0.03);
    assert_eq!(robust["loss"]["kind"], "soft_l1");
    // Every outlier (residual ≥ 2/3 of the value, ≫ C = 0.03) is beyond the soft margin,
    // and hardly any of the 1 %-noise samples (|z| > 3 at 1 %: 0.3 %).
    let beyond = robust["loss"]["beyond_f_scale"].as_u64().unwrap() as usize;
    assert!(
        beyond >= k && beyond <= k + 30,
        "{beyond} beyond C, {k} outliers"
    );

    println!("soft_l1: sigma off {es:.4}, T off {et:.4}, {beyond} beyond C, {k} outliers");
    let linear = fit(&path, "linear");
    let (ls, lt) = (rel_err(&linear, "sigma", SIGMA), rel_err(&linear, "T", T));
    println!("linear: sigma off {ls:.4}, T off {lt:.4}");
    assert!(
        ls > 0.03 || lt > 0.03,
        "linear: σ off {ls:.4}, T off {lt:.4}"
    );
    assert_eq!(linear["setting"]["loss"], "linear");
    assert!(linear["setting"]["f_scale"].is_null());
    // The robust fit's covariance comes from the corrected Jacobian (scipy's curve_fit):
    // its standard errors reflect the inlier scatter, far below the outlier-inflated ones.
    let se = |j: &serde_json::Value| j["params"]["T"]["stderr"].as_f64().unwrap();
    assert!(
        se(&robust) < 0.5 * se(&linear),
        "{} vs {}",
        se(&robust),
        se(&linear)
    );
    // ... and T's robust error bar covers the truth (2.5 standard errors).
    let t = robust["params"]["T"]["value"].as_f64().unwrap();
    assert!(
        (t - T).abs() < 2.5 * se(&robust),
        "T = {t} ± {}",
        se(&robust)
    );
}

#[test]
fn every_robust_loss_recovers_the_scan_and_the_text_report_names_it() {
    let dir = tempfile::tempdir().unwrap();
    let (path, _) = outlier_scan(dir.path());
    for loss in ["huber", "cauchy", "arctan"] {
        let j = fit(&path, loss);
        assert_eq!(j["converged"], true, "{loss}: {j}");
        let (es, et) = (rel_err(&j, "sigma", SIGMA), rel_err(&j, "T", T));
        assert!(
            es < 0.03 && et < 0.03,
            "{loss}: σ off {es:.4}, T off {et:.4}"
        );
    }
    let text = success_stdout(&fit_args(&path, "soft_l1", false));
    assert!(
        text.contains("    loss            = soft_l1 (f_scale C = 3.0000e-2"),
        "{text}"
    );
    assert!(text.contains("    cost ½ΣC²ρ      = "), "{text}");
    assert!(text.contains("    beyond f_scale  = "), "{text}");
}

#[test]
fn a_bad_loss_scale_is_refused_as_usage() {
    let p = common::data("synthetic/kbs_inplane.csv");
    for bad in ["0", "-1", "nan", "inf"] {
        let out = goniofit()
            .args("fit --model kbs --wavelength 1 --loss cauchy".split(' '))
            .arg(format!("--f-scale={bad}"))
            .arg(&p)
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "--f-scale {bad}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("--f-scale") && err.contains("finite number > 0"),
            "{err}"
        );
    }
}
