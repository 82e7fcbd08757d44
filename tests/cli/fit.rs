//! `goniofit fit` from the command line: the report (snapshot), JSON keys, residuals file,
//! exit codes for each kind of bad input, and batch fits.

use crate::common;

use common::{data, fit_json, goniofit, success_stdout, without_progress};
use predicates::prelude::*;
use std::path::Path;

/// The text report without the lines that vary between runs (timings, the command path).
fn stable(report: &str) -> String {
    report
        .lines()
        .filter(|l| !l.contains("run time") && !l.contains("command "))
        .collect::<Vec<_>>()
        .join("\n")
        + "\n"
}

#[test]
fn report_snapshot() {
    let text = stable(&success_stdout(&[
        "fit",
        "--model",
        "kbs",
        "--wavelength",
        "1",
        "data/synthetic/kbs_hemisphere.csv",
    ]));
    let snap = Path::new("tests/snapshots/fit_kbs_hemisphere.txt");
    if std::env::var_os("UPDATE_SNAPSHOTS").is_some() {
        std::fs::write(snap, &text).unwrap();
    }
    let want = std::fs::read_to_string(snap).expect("snapshot (UPDATE_SNAPSHOTS=1 writes it)");
    assert_eq!(
        text, want,
        "report changed; review and rerun with UPDATE_SNAPSHOTS=1"
    );
    // The file carries sigma_L, so the weights are inverse variances: reduced χ² ≈ 1.
    assert!(text.contains("reduced chi-sq  = 1.0"), "{text}");
}

#[test]
fn json_report_has_the_documented_keys() {
    let v = fit_json(&[
        "fit",
        "--model",
        "lambert-specular",
        "--json",
        "data/synthetic/lambert_specular.csv",
    ]);
    for key in [
        "model",
        "params",
        "derived",
        "cost",
        "rms",
        "n",
        "termination",
        "iterations",
        "evaluations",
        "seconds",
        "modes",
    ] {
        assert!(v.get(key).is_some(), "missing {key}");
    }
    let w = &v["params"]["w"];
    assert!(w["determined"].as_bool().unwrap());
    let (value, se) = (w["value"].as_f64().unwrap(), w["stderr"].as_f64().unwrap());
    assert!(
        (value - 0.12).abs() < 4.0 * se,
        "w = {value} ± {se}, truth 0.12"
    );
    assert_eq!(v["n"].as_u64(), Some(855));
}

#[test]
fn residuals_file_has_the_fit_columns() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("res.csv");
    goniofit()
        .args(["fit", "--model", "kbs", "--wavelength", "1", "--residuals"])
        .arg(&path)
        .arg("data/synthetic/kbs_inplane.csv")
        .assert()
        .code(0);
    let text = std::fs::read_to_string(&path).unwrap();
    let header = text.lines().next().unwrap();
    assert_eq!(
        header,
        "theta_i,theta_r,phi_r,L,L_fit,residual,std_residual,mode"
    );
    assert_eq!(text.lines().count(), 856);
}

/// The residuals and standardized residuals a fit with profile intervals reports (they
/// are released while the intervals run and computed again from the fitted values) are
/// those of the same fit without intervals, to the bit; so is a robust fit's.
#[test]
fn residuals_file_is_the_same_with_and_without_intervals() {
    let dir = tempfile::tempdir().unwrap();
    for loss in ["linear", "cauchy"] {
        let written: Vec<String> = ["--no-intervals", "--quiet"]
            .iter()
            .map(|flag| {
                let path = dir.path().join(format!("res-{loss}{flag}.csv"));
                goniofit()
                    .args(["fit", "--model", "kbs", "--wavelength", "1", "--loss", loss])
                    .args([*flag, "--residuals"])
                    .arg(&path)
                    .arg("data/synthetic/kbs_inplane.csv")
                    .assert()
                    .code(0);
                std::fs::read_to_string(&path).unwrap()
            })
            .collect();
        assert_eq!(written[0].lines().count(), 856);
        assert_eq!(written[0], written[1], "loss {loss}");
    }
}

#[test]
fn bad_inputs_exit_2_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.csv");
    std::fs::write(&bad, "theta_i,theta_r,phi_r,L\n10,20,0,1\n10,abc,0,2\n").unwrap();
    let out = goniofit()
        .args(["fit", "--model", "lambert"])
        .arg(&bad)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.csv:3") && err.contains("theta_r") && err.contains("abc"),
        "{err}"
    );

    let cases: [(&[&str], &str); 5] = [
        (
            &["fit", "--model", "kbs", "data/synthetic/kbs_inplane.csv"],
            "wavelength",
        ),
        (
            &[
                "fit",
                "--model",
                "beckmann",
                "data/synthetic/kbs_inplane.csv",
            ],
            "unknown model",
        ),
        (
            &[
                "fit",
                "--model",
                "kbs",
                "--wavelength",
                "1",
                "--fix",
                "roughness=1",
                "data/synthetic/kbs_inplane.csv",
            ],
            "roughness",
        ),
        (
            &[
                "fit",
                "--model",
                "kbs",
                "--wavelength",
                "1",
                "--init",
                "sigma=-1",
                "data/synthetic/kbs_inplane.csv",
            ],
            "sigma",
        ),
        (
            &[
                "fit",
                "--model",
                "kbs",
                "--wavelength=-1",
                "data/synthetic/kbs_inplane.csv",
            ],
            "wavelength",
        ),
    ];
    for (args, needle) in cases {
        let out = goniofit().args(args).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.to_lowercase().contains(needle), "{args:?}: {err}");
    }

    let few = dir.path().join("few.csv");
    std::fs::write(&few, "theta_i,theta_r,phi_r,L\n10,20,0,1\n20,20,0,2\n").unwrap();
    let out = goniofit()
        .args(["fit", "--model", "kbs", "--wavelength", "1"])
        .arg(&few)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("more samples than free parameters"));

    let zero = dir.path().join("zero.csv");
    std::fs::write(
        &zero,
        "theta_i,theta_r,phi_r,L\n10,20,0,0\n20,20,0,0\n30,20,0,0\n40,20,0,0\n",
    )
    .unwrap();
    let out = goniofit()
        .args(["fit", "--model", "lambert"])
        .arg(&zero)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_fit_that_stops_early_exits_3_with_its_report() {
    let out = goniofit()
        .args([
            "fit",
            "--model",
            "kbs",
            "--wavelength",
            "1",
            "--max-iter",
            "0",
            "data/synthetic/kbs_inplane.csv",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("converged       = false") && text.contains("maxiterations"),
        "{text}"
    );
}

#[test]
fn several_files_are_fitted_in_one_run() {
    let out = goniofit()
        .args([
            "fit",
            "--model",
            "kbs",
            "--wavelength",
            "1",
            "--json",
            "--threads",
            "2",
        ])
        .args([
            "data/synthetic/kbs_inplane.csv",
            "data/synthetic/kbs_hemisphere.csv",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let fits = v["fits"].as_array().unwrap();
    assert_eq!(fits.len(), 2);
    for f in fits {
        let sigma = f["params"]["sigma"]["value"].as_f64().unwrap();
        assert!((sigma / 0.25 - 1.0).abs() < 0.02, "sigma {sigma}");
    }
}

#[test]
fn rough_data_reports_undetermined_sigma() {
    let v = fit_json(&[
        "fit",
        "--model",
        "kbs",
        "--wavelength",
        "1",
        "--residual",
        "relative",
        "--json",
        "data/synthetic/kbs_rough.csv",
    ]);
    assert_eq!(v["verdict"], "rough");
    assert_eq!(v["params"]["sigma"]["determined"], false);
    let ratio = v["derived"]["T/sigma"]["value"].as_f64().unwrap();
    assert!((ratio / 5.0 - 1.0).abs() < 0.01, "T/sigma {ratio}");
}

/// Every channel of both rough Cornell paints either converges or says `degenerate` with
/// its reason (`--by-group`; exit 3 when any is degenerate). In the 580 nm channel of
/// garnet red the refined rough-valley candidate drifts to σ ≈ 2.6e2 λ, where g exceeds the
/// fit's limit on samples outside the refinement's subsample, so that start lies outside
/// the model's domain; the fit takes the next start inside the domain.
#[test]
fn every_cornell_channel_converges() {
    let out = goniofit()
        .args(common::PAINT_BRDF_LOG)
        .args([
            "--channel",
            "all",
            "--by-group",
            "data/cornell/garnet_red.astm",
            "data/cornell/krylon_blue.astm",
        ])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    let terminations: Vec<&str> = text
        .lines()
        .filter(|l| l.trim_start().starts_with("termination") && l.contains(" = "))
        .collect();
    assert_eq!(terminations.len(), 62);
    let degenerate = terminations
        .iter()
        .filter(|l| l.contains("= degenerate"))
        .count();
    assert!(
        terminations
            .iter()
            .all(|l| l.contains("(converged") || l.contains("= degenerate")),
        "{terminations:?}"
    );
    // Each degenerate fit names its reason; the exit code says whether any was.
    let reasons = text
        .lines()
        .filter(|l| {
            l.contains("note: the data shows no") || l.contains("note: the Jacobian lost rank")
        })
        .count();
    assert!(
        reasons >= degenerate,
        "{degenerate} degenerate, {reasons} reasons"
    );
    let want = if degenerate > 0 { 3 } else { 0 };
    assert_eq!(
        out.status.code(),
        Some(want),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn hostile_file_and_group_names_are_escaped_in_the_report() {
    // A file name with a line break and a group name with a right-to-left override: the
    // report shows them escaped, so neither can fake a report line or reverse the text.
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("scan\n    verdict = fake.csv");
    let mut text = String::from("theta_i,theta_r,phi_r,L,group\n");
    let src = std::fs::read_to_string(data("synthetic/lambert_specular.csv")).unwrap();
    for (k, line) in src.lines().skip(1).enumerate() {
        let g = if k % 2 == 0 {
            "left\u{202e}txt.exe"
        } else {
            "right"
        };
        text += &format!("{line},{g}\n");
    }
    std::fs::write(&file, text).unwrap();
    let args = ["fit", "--model", "lambert", "--by-group"].map(std::ffi::OsString::from);
    let report = success_stdout(&[&args[..], &[file.clone().into_os_string()]].concat());
    assert!(!report.contains('\u{202e}'), "{report}");
    assert!(
        !report.lines().any(|l| l.starts_with("    verdict = fake")),
        "{report}"
    );
    assert!(
        report.contains("scan\\n    verdict = fake.csv [left\\u{202e}txt.exe]"),
        "{report}"
    );
    assert!(
        report.contains("scan\\n    verdict = fake.csv [right]"),
        "{report}"
    );
    // And in an error message.
    goniofit()
        .args(["fit", "--model", "kbs"])
        .arg(&file)
        .assert()
        .code(2)
        .stderr(
            predicate::str::contains("scan\\n    verdict = fake.csv")
                .and(predicate::str::contains('\u{202e}').not()),
        );
}

#[test]
fn overflowing_values_and_weights_are_refused_at_input() {
    // One L = 1e200, every L × 1e160, one weight 1e308, and −1e308 in one ASTM channel:
    // each refused before any fit (exit 2), naming line and column.
    let dir = tempfile::tempdir().unwrap();
    let src = std::fs::read_to_string(data("synthetic/lambert_specular.csv")).unwrap();
    let rows: Vec<&str> = src.lines().skip(1).collect();
    let with_l = |f: &dyn Fn(usize, f64) -> f64| -> String {
        let mut t = String::from("theta_i,theta_r,phi_r,L\n");
        for (k, r) in rows.iter().enumerate() {
            let (angles, l) = r.rsplit_once(',').unwrap();
            t += &format!("{angles},{:e}\n", f(k, l.parse().unwrap()));
        }
        t
    };
    let one = dir.path().join("one.csv");
    std::fs::write(&one, with_l(&|k, l| if k == 5 { 1e200 } else { l })).unwrap();
    let all = dir.path().join("all.csv");
    std::fs::write(&all, with_l(&|_, l| l * 1e160)).unwrap();
    let weighted = dir.path().join("weighted.csv");
    let mut t = String::from("theta_i,theta_r,phi_r,L,weight\n");
    for (k, r) in rows.iter().enumerate() {
        t += &format!("{r},{}\n", if k == 7 { "1e308" } else { "1" });
    }
    std::fs::write(&weighted, t).unwrap();
    let astm_src = std::fs::read_to_string(data("cornell/garnet_red.astm")).unwrap();
    let mut lines: Vec<String> = astm_src.lines().map(String::from).collect();
    let first = 1 + lines.iter().position(|l| l.starts_with("VARS")).unwrap();
    let first = first
        + lines[first..]
            .iter()
            .position(|l| !l.trim().is_empty())
            .unwrap();
    let mut fields: Vec<String> = lines[first].split(',').map(String::from).collect();
    fields[10] = "-1e308".into();
    lines[first] = fields.join(",");
    let astm = dir.path().join("neg.astm");
    std::fs::write(&astm, lines.join("\n") + "\n").unwrap();
    let cases = [
        (
            &one,
            "lambert",
            "one.csv:7: column L: value 1e200 is beyond ±1e100",
        ),
        (
            &all,
            "lambert",
            "all.csv:2: column L: value 1.9338475483963342e159 is beyond ±1e100",
        ),
        (
            &weighted,
            "lambert",
            "weighted.csv:9: column weight: weight 1e308",
        ),
        (
            &astm,
            "kbs",
            &format!(
                "neg.astm:{}: column 460nm: value -1e308 is beyond ±1e100",
                first + 1
            ),
        ),
    ];
    for (file, model, says) in cases {
        let astm = file.extension().is_some_and(|e| e == "astm");
        goniofit()
            .args(["fit", "--model", model])
            .args(if astm {
                &["--channel", "all"][..]
            } else {
                &[][..]
            })
            .arg(file)
            .assert()
            .code(2)
            .stdout("")
            .stderr(predicate::str::contains(says));
    }
    // Just inside the limit (all L × 1e90): the fit runs and every number it prints is finite.
    let inside = dir.path().join("inside.csv");
    std::fs::write(&inside, with_l(&|_, l| l * 1e90)).unwrap();
    let out = goniofit()
        .args(["fit", "--model", "lambert"])
        .arg(&inside)
        .output()
        .unwrap();
    let report = String::from_utf8(out.stdout).unwrap();
    assert!(report.contains("R-squared"), "{report}");
    assert!(
        !report.contains("NaN") && !report.contains("inf"),
        "{report}"
    );
}

/// Progress goes to a terminal only: with standard error piped (as here) a `--by-group`
/// batch draws no bar (no carriage returns, no "datasets fitted" line) and ends with its
/// one summary line; `--quiet` is accepted and leaves standard error empty.
#[test]
fn piped_stderr_has_no_progress_and_quiet_silences_the_summary() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("groups.csv");
    let mut text = String::from("theta_i,theta_r,phi_r,L,group\n");
    let src = std::fs::read_to_string(data("synthetic/lambert_specular.csv")).unwrap();
    for (k, line) in src.lines().skip(1).enumerate() {
        text += &format!("{line},{}\n", ["a", "b", "c"][k % 3]);
    }
    std::fs::write(&file, text).unwrap();
    let run = |quiet: bool| {
        let mut cmd = goniofit();
        cmd.args(["fit", "--model", "lambert", "--by-group", "--json"]);
        if quiet {
            cmd.arg("--quiet");
        }
        let out = cmd.arg(&file).output().unwrap();
        assert_eq!(out.status.code(), Some(0), "quiet {quiet}");
        let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        assert_eq!(v["datasets"], 3, "quiet {quiet}");
        without_progress(&String::from_utf8(out.stderr).unwrap())
    };
    let err = run(false);
    assert!(
        !err.contains('\r') && !err.contains("datasets fitted"),
        "{err:?}"
    );
    assert_eq!(err.lines().count(), 1, "{err:?}");
    assert!(
        err.starts_with("goniofit: fitted 3 datasets in "),
        "{err:?}"
    );
    assert_eq!(run(true), "", "--quiet");
}
