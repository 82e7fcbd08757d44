//! The adequacy verdict through the CLI: planted misfits built with `goniofit synth` are
//! flagged with the reason that fits them, clean fits with the right model and weights are
//! not, real data that the model misses is, and a misfit never changes the exit code.

use crate::common;
use common::{data, goniofit, run_json, success_stdout};
use std::path::{Path, PathBuf};

/// `goniofit synth` into `dir/name` (in-plane layout, 1 % relative noise), with `extra`
/// arguments; returns the file.
fn synth(dir: &Path, name: &str, model: &str, params: &str, seed: &str, extra: &[&str]) -> PathBuf {
    let out = dir.join(name);
    let mut args = vec![
        "synth", "--model", model, "--params", params, "--layout", "inplane", "--noise", "0.01",
        "--seed", seed, "--out",
    ];
    args.push(out.to_str().unwrap());
    args.extend_from_slice(extra);
    success_stdout(&args);
    out
}

/// Rewrite the L column of a synth CSV: L ← f(θi, θr, L) (angles in degrees).
fn rewrite_l(src: &Path, dst: &Path, f: impl Fn(f64, f64, f64) -> f64) {
    let text = std::fs::read_to_string(src).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (ti, tr, l) = (col("theta_i"), col("theta_r"), col("L"));
    let mut out = header.join(",") + "\n";
    for line in lines {
        let mut cells: Vec<String> = line.split(',').map(String::from).collect();
        let num = |k: usize| cells[k].parse::<f64>().unwrap();
        let v = f(num(ti), num(tr), num(l));
        cells[l] = format!("{v:e}");
        out += &(cells.join(",") + "\n");
    }
    std::fs::write(dst, out).unwrap();
}

/// The adequacy verdict, the reason codes and the exit code of a fit.
fn adequacy(args: &[&str]) -> (String, Vec<String>, Option<i32>) {
    let mut all = vec!["fit", "--no-intervals"];
    all.extend_from_slice(args);
    let (code, v) = run_json(&all);
    let a = &v["adequacy"];
    let codes = a["reasons"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["code"].as_str().unwrap().to_string())
        .collect();
    (a["verdict"].as_str().unwrap().to_string(), codes, code)
}

const KBS: &str = "sigma=0.3,T=2,scale=1";

#[test]
fn clean_fits_with_the_right_model_and_weights_are_not_flagged() {
    let dir = tempfile::tempdir().unwrap();
    for seed in ["1", "2", "3"] {
        let stated = synth(
            dir.path(),
            &format!("s{seed}.csv"),
            "kbs",
            KBS,
            seed,
            &["--write-sigma"],
        );
        let (verdict, codes, code) = adequacy(&[stated.to_str().unwrap()]);
        assert_eq!((verdict.as_str(), code), ("adequate", Some(0)), "{codes:?}");
        // Relative noise without σ_L, fitted with relative residuals: the right weights.
        let plain = synth(dir.path(), &format!("p{seed}.csv"), "kbs", KBS, seed, &[]);
        let (verdict, codes, _) = adequacy(&["--residual", "relative", plain.to_str().unwrap()]);
        assert_eq!(verdict, "adequate", "{codes:?}");
    }
    // The bundled hemisphere scan with its stated σ_L.
    let hemi = data("synthetic/kbs_hemisphere.csv");
    let (verdict, codes, _) = adequacy(&["--wavelength", "633nm", hemi.to_str().unwrap()]);
    assert_eq!(verdict, "adequate", "{codes:?}");
}

#[test]
fn a_lobe_and_floor_fitted_without_the_floor_is_flagged_as_missing_a_floor() {
    let dir = tempfile::tempdir().unwrap();
    let f = synth(
        dir.path(),
        "floor.csv",
        "kbs+lambert",
        "sigma=0.3,T=2,scale=1,scale_d=0.02",
        "2",
        &[],
    );
    for residual in ["relative", "absolute"] {
        let (verdict, codes, code) = adequacy(&["--residual", residual, f.to_str().unwrap()]);
        assert_eq!((verdict.as_str(), code), ("misfit", Some(0)), "{residual}");
        assert!(
            codes.contains(&"floor".to_string()),
            "{residual}: {codes:?}"
        );
    }
    // With the floor in the model the same data are described.
    let (verdict, codes, _) = adequacy(&[
        "--model",
        "kbs+lambert",
        "--residual",
        "relative",
        f.to_str().unwrap(),
    ]);
    assert_eq!(verdict, "adequate", "{codes:?}");
}

#[test]
fn proportional_noise_fitted_with_absolute_residuals_is_flagged() {
    let dir = tempfile::tempdir().unwrap();
    let f = synth(dir.path(), "prop.csv", "kbs", KBS, "3", &[]);
    let (_, codes, code) = adequacy(&[f.to_str().unwrap()]);
    assert_eq!(
        codes.first().map(String::as_str),
        Some("proportional_noise"),
        "{codes:?}"
    );
    assert_eq!(code, Some(0));
    // A rough scene: σ = 3.77 λ, T = 147 λ, exact KBS, 1 % proportional noise, 315 samples.
    let rough = dir.path().join("rough.csv");
    success_stdout(&[
        "synth",
        "--model",
        "kbs",
        "--params",
        "sigma=3.77,T=147,scale=1",
        "--layout",
        "inplane theta_i=25,45,65 max=75 step=1",
        "--samples",
        "315",
        "--noise",
        "0.01",
        "--seed",
        "5",
        "--out",
        rough.to_str().unwrap(),
    ]);
    let (_, codes, _) = adequacy(&[rough.to_str().unwrap()]);
    assert!(
        codes.contains(&"proportional_noise".to_string()),
        "{codes:?}"
    );
    let (verdict, codes, _) = adequacy(&["--residual", "relative", rough.to_str().unwrap()]);
    assert_eq!(verdict, "adequate", "{codes:?}");
}

#[test]
fn a_fresnel_like_rise_at_grazing_angles_is_flagged_as_grazing() {
    let dir = tempfile::tempdir().unwrap();
    let base = synth(dir.path(), "base.csv", "kbs", KBS, "3", &[]);
    let f = dir.path().join("fresnel.csv");
    // Data rising above the model beyond 60°, up to 4× at 90°.
    rewrite_l(&base, &f, |ti, tr, l| {
        let t = ti.max(tr);
        if t > 60.0 {
            l * (1.0 + 3.0 * ((t - 60.0) / 30.0).powi(3))
        } else {
            l
        }
    });
    let (verdict, codes, code) = adequacy(&["--residual", "relative", f.to_str().unwrap()]);
    assert_eq!((verdict.as_str(), code), ("misfit", Some(0)));
    assert!(codes.contains(&"grazing_above".to_string()), "{codes:?}");
}

#[test]
fn a_saturated_peak_is_flagged() {
    let dir = tempfile::tempdir().unwrap();
    let base = synth(dir.path(), "base.csv", "kbs", KBS, "3", &[]);
    let max = std::fs::read_to_string(&base)
        .unwrap()
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(3).unwrap().parse::<f64>().unwrap())
        .fold(0.0f64, f64::max);
    let f = dir.path().join("clip.csv");
    rewrite_l(&base, &f, |_, _, l| l.min(0.6 * max));
    let (verdict, codes, code) = adequacy(&["--residual", "relative", f.to_str().unwrap()]);
    assert_eq!((verdict.as_str(), code), ("misfit", Some(0)));
    assert!(codes.contains(&"runs".to_string()), "{codes:?}");
}

#[test]
fn curet_surface_8_at_defaults_is_a_misfit_with_exit_code_0() {
    let curet = data("curet/curet.csv");
    let (verdict, codes, code) = adequacy(&[
        "--channel",
        "8",
        "--wavelength",
        "550nm",
        curet.to_str().unwrap(),
    ]);
    assert_eq!((verdict.as_str(), code), ("misfit", Some(0)), "{codes:?}");
}

#[test]
fn the_text_report_and_summary_csv_carry_the_verdict() {
    let garnet = data("cornell/garnet_red.astm");
    let text = success_stdout(&[
        "fit",
        "--model",
        "kbs+lambert",
        "--quantity",
        "brdf",
        "--channel",
        "550nm",
        "--residual",
        "log",
        "--no-intervals",
        garnet.to_str().unwrap(),
    ]);
    let lines: Vec<&str> = text.lines().collect();
    let conv = lines
        .iter()
        .position(|l| l.trim_start().starts_with("converged"))
        .unwrap();
    assert!(
        lines[conv + 1].contains("adequacy        = misfit"),
        "{}",
        lines[conv + 1]
    );
    assert!(text.contains("as unmodelled Fresnel reflection would"));
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("s.csv");
    let out = goniofit()
        .args([
            "fit",
            "--model",
            "kbs+lambert",
            "--quantity",
            "brdf",
            "--residual",
            "log",
        ])
        .args([
            "--by-group",
            "--no-intervals",
            "--summary",
            csv.to_str().unwrap(),
        ])
        .arg(garnet.to_str().unwrap())
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert!(stdout.contains(" adequacy") && stdout.contains("misfit (runs,"));
    let summary = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = summary.lines().next().unwrap().split(',').collect();
    assert!(
        header.ends_with(&["adequacy", "adequacy_reasons"]),
        "{header:?}"
    );
    assert!(summary.lines().nth(1).unwrap().contains(",misfit,\"runs,"));
}

/// Values computed from the model itself (no noise): every residual is rounding error, and
/// the verdict says so instead of testing the rounding's signs.
#[test]
fn values_computed_from_the_model_are_exact_not_misfit() {
    let dir = tempfile::tempdir().unwrap();
    let mut csv = String::from("theta_i,theta_r,phi_r,L\n");
    for ti in [0.0f64, 20.0, 40.0, 60.0, 75.0] {
        for k in 0..40 {
            let tr = 88.0 * k as f64 / 39.0;
            for pr in [0.0, 90.0, 180.0] {
                // lambert in radiance: scale × cos θi.
                csv += &format!("{ti},{tr},{pr},{:e}\n", 0.3 * ti.to_radians().cos());
            }
        }
    }
    let path = dir.path().join("exact.csv");
    std::fs::write(&path, csv).unwrap();
    for residual in ["absolute", "relative", "log"] {
        let (verdict, reasons, code) = adequacy(&[
            "--model",
            "lambert",
            "--residual",
            residual,
            path.to_str().unwrap(),
        ]);
        assert_eq!(verdict, "exact", "{residual}: {reasons:?}");
        assert!(reasons.is_empty());
        assert_eq!(code, Some(0));
    }
}
