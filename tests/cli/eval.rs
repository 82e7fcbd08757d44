//! `goniofit eval` end to end: values equal the library's, pass-through of every column,
//! options, exit code 2 with file/line/column for bad input, atomic `--out`.

use assert_cmd::Command;
use goniofit::{read as read_dataset, ReadOptions};
use goniofit::{EvalMode, ModelOptions};
use goniofit::{Geometry, Quantity};
use predicates::prelude::*;
use std::path::{Path, PathBuf};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data").join(p)
}

fn goniofit() -> Command {
    Command::cargo_bin("goniofit").unwrap()
}

/// Standard output of a successful `goniofit ARGS FILE`.
fn stdout_of(args: &[&str], file: impl AsRef<std::ffi::OsStr>) -> Vec<u8> {
    goniofit()
        .args(args)
        .arg(file)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone()
}

/// Parse eval output: header and rows (simple CSV, no quoted fields in these tests).
fn parse_out(stdout: &[u8]) -> (Vec<String>, Vec<Vec<String>>) {
    let text = String::from_utf8(stdout.to_vec()).unwrap();
    let mut lines = text.lines();
    let header = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let rows = lines
        .map(|l| l.split(',').map(str::to_string).collect())
        .collect();
    (header, rows)
}

/// The library's values for a file, model and parameters.
fn library_values(
    file: &Path,
    name: &str,
    params: &str,
    wavelength: f64,
    quantity: Quantity,
    mopts: ModelOptions,
) -> Vec<f64> {
    let ds = read_dataset(file, &ReadOptions::default()).unwrap();
    let m = goniofit::model(name, &mopts).unwrap();
    let p = goniofit::parse_params(m.as_ref(), params).unwrap();
    let geo = Geometry::new(&ds.samples, &[wavelength], quantity).unwrap();
    let mut out = vec![0.0; geo.len()];
    m.eval(&geo, &p, &mut out, None);
    out
}

const MODELS: [(&str, &str); 6] = [
    ("kbs", "sigma=0.3,T=2,scale=1"),
    ("kbs-smooth", "sigma=0.05,T=1.5,scale=2"),
    ("kbs-rough", "sigma=2,T=10,scale=0.5"),
    ("kbs+lambert", "sigma=0.3,T=2,scale=1,scale_d=0.1"),
    ("lambert", "scale=0.7"),
    ("lambert-specular", "scale=0.2,B=1,w=0.1"),
];

#[test]
fn eval_matches_the_library_for_every_model() {
    let file = data("angles_inplane.csv");
    let original = std::fs::read_to_string(&file).unwrap();
    let original_rows: Vec<&str> = original
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .collect();
    for (name, params) in MODELS {
        let out = stdout_of(
            &[
                "eval",
                "--model",
                name,
                "--params",
                params,
                "--wavelength",
                "1",
            ],
            &file,
        );
        let (header, rows) = parse_out(&out);
        assert_eq!(header, ["id", "theta_i", "theta_r", "phi_r", "L_model"]);
        let want = library_values(
            &file,
            name,
            params,
            1.0,
            Quantity::Radiance,
            ModelOptions::default(),
        );
        assert_eq!(rows.len(), want.len());
        for (k, (row, w)) in rows.iter().zip(&want).enumerate() {
            // Every original column passes through unchanged.
            assert_eq!(row[..4].join(","), original_rows[k + 1], "{name}");
            let got: f64 = row[4].parse().unwrap();
            assert_eq!(
                got, *w,
                "{name} row {k}: exact round trip of the printed value"
            );
            assert!(got.is_finite() && got >= 0.0);
        }
        assert!(want.iter().any(|&v| v > 0.0), "{name}");
    }
}

#[test]
fn eval_options_brdf_patch_mode_tol() {
    let file = data("angles_inplane.csv");
    let out = stdout_of(
        &[
            "eval",
            "--model",
            "kbs",
            "--params",
            "sigma=0.3,T=2,scale=1",
            "--wavelength",
            "0.5",
            "--quantity",
            "brdf",
            "--patch",
            "3,4",
            "--mode",
            "series",
            "--tol",
            "1e-12",
        ],
        &file,
    );
    let (_, rows) = parse_out(&out);
    let want = library_values(
        &file,
        "kbs",
        "sigma=0.3,T=2,scale=1",
        0.5,
        Quantity::Brdf,
        ModelOptions {
            mode: EvalMode::Series,
            tol: 1e-12,
            patch: Some((3.0, 4.0)),
            ..ModelOptions::default()
        },
    );
    for (row, w) in rows.iter().zip(&want) {
        assert_eq!(row[4].parse::<f64>().unwrap(), *w);
    }
}

#[test]
fn eval_radians_signed_and_column_mapping() {
    let dir = tempfile::tempdir().unwrap();
    let f = dir.path().join("in.csv");
    std::fs::write(&f, "Inc,View,keep\n0.5,-0.3,a\n0.5,0.5,b\n").unwrap();
    let out = stdout_of(
        &[
            "eval",
            "--model",
            "lambert-specular",
            "--params",
            "scale=1e-300,
            B=1,
            w=0.1",
            "--radians",
            "--signed-theta-r",
            "--columns",
            "theta_i=Inc,
            theta_r=View",
        ],
        &f,
    );
    let (header, rows) = parse_out(&out);
    assert_eq!(header, ["Inc", "View", "keep", "L_model"]);
    assert_eq!(rows[1][2], "b");
    let back: f64 = rows[0][3].parse().unwrap();
    let mirror: f64 = rows[1][3].parse().unwrap();
    let peak = 1.0 / (0.1 * (2.0 * std::f64::consts::PI).sqrt());
    assert!((mirror - peak).abs() < 1e-12 * peak, "{mirror} vs {peak}");
    // θr = −0.3 rad means θr = 0.3 at φr = π: the lobe's value there.
    let pi = std::f64::consts::PI;
    let want_back = peak * (-0.5 * ((0.2f64 / 0.1).powi(2) + (pi / 0.2).powi(2))).exp();
    assert!(
        (back - want_back).abs() < 1e-9 * want_back,
        "{back} vs {want_back}"
    );
}

#[test]
fn eval_astm_channel_gives_the_wavelength() {
    let out = stdout_of(
        &[
            "eval",
            "--model",
            "kbs-rough",
            "--params",
            "sigma=300,
            T=1500,
            scale=1",
            "--channel",
            "550nm",
            "--quantity",
            "brdf",
        ],
        data("cornell/garnet_red.astm"),
    );
    let (header, rows) = parse_out(&out);
    assert_eq!(
        header,
        ["theta_i", "phi_i", "theta_s", "phi_s", "channel", "BRDF", "L_model"]
    );
    assert_eq!(rows.len(), 1439);
    assert_eq!(
        rows[0][..6].join(","),
        "0.872665,0.000000,0.573513,0.000000,550nm,0.004352"
    );
}

#[test]
fn eval_writes_out_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("model.csv");
    let stdout = stdout_of(
        &["eval", "--model", "lambert", "--params", "scale=1"],
        data("angles_inplane.csv"),
    );
    goniofit()
        .args(["eval", "--model", "lambert", "--params", "scale=1", "--out"])
        .arg(&out)
        .arg(data("angles_inplane.csv"))
        .assert()
        .success()
        .stdout(predicate::str::is_empty());
    assert_eq!(std::fs::read(&out).unwrap(), stdout);
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "no temporary left"
    );
}

#[test]
fn eval_out_in_missing_directory_leaves_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("no").join("such").join("model.csv");
    goniofit()
        .args(["eval", "--model", "lambert", "--params", "scale=1", "--out"])
        .arg(&out)
        .arg(data("angles_inplane.csv"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("model.csv"));
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
}

/// Bad input files: exit 2, and stderr names the file, line, column and value.
#[test]
fn eval_bad_input_exit_2_names_line_and_column() {
    let cases: &[(&str, &str, &str)] = &[
        (
            "theta_i,theta_r,phi_r\n10,20,0\n10,abc,0\n",
            ":3: column theta_r:",
            "'abc'",
        ),
        (
            "theta_i,theta_r,phi_r\n95,20,0\n",
            ":2: column theta_i:",
            "95",
        ),
        (
            "theta_i,theta_r,phi_r\n10,91,0\n",
            ":2: column theta_r:",
            "91",
        ),
        (
            "theta_i,theta_r,phi_r\n10,-5,0\n",
            ":2: column theta_r:",
            "--signed-theta-r",
        ),
        (
            "theta_i,theta_r,phi_r\n10,20,720\n",
            ":2: column phi_r:",
            "720",
        ),
        (
            "theta_i,theta_r,phi_r\n10,20,nan\n",
            ":2: column phi_r:",
            "'nan'",
        ),
        (
            "theta_i,theta_r,phi_r\n10,20\n",
            ":2: column (row):",
            "2 fields",
        ),
        (
            "theta_i,theta_r\n10,20\n",
            ":1: column phi_r:",
            "missing column phi_r",
        ),
        (
            "theta_i,theta_r,phi_r,weight\n10,20,0,-1\n",
            ":2: column weight:",
            "-1",
        ),
        (
            "theta_i,theta_r,phi_r,sigma_L\n10,20,0,0\n",
            ":2: column sigma_L:",
            "sigma_L 0",
        ),
    ];
    let dir = tempfile::tempdir().unwrap();
    for (k, (text, place, value)) in cases.iter().enumerate() {
        let f = dir.path().join(format!("bad{k}.csv"));
        std::fs::write(&f, text).unwrap();
        goniofit()
            .args(["eval", "--model", "lambert", "--params", "scale=1"])
            .arg(&f)
            .assert()
            .code(2)
            .stdout(predicate::str::is_empty())
            .stderr(predicate::str::contains(format!("bad{k}.csv{place}")))
            .stderr(predicate::str::contains(*value));
    }
    // Whole-file problems.
    for (text, says) in [
        ("", "empty file"),
        ("theta_i,theta_r,phi_r\n", "no data rows"),
    ] {
        let f = dir.path().join("whole.csv");
        std::fs::write(&f, text).unwrap();
        goniofit()
            .args(["eval", "--model", "lambert", "--params", "scale=1"])
            .arg(&f)
            .assert()
            .code(2)
            .stderr(predicate::str::contains("whole.csv").and(predicate::str::contains(says)));
    }
}

#[test]
fn eval_usage_errors_exit_2() {
    let file = data("angles_inplane.csv");
    let run = |args: &[&str], says: &str| {
        goniofit()
            .arg("eval")
            .args(args)
            .arg(&file)
            .assert()
            .code(2)
            .stderr(predicate::str::contains(says.to_string()));
    };
    run(
        &["--model", "kbs", "--params", "sigma=0.3,T=2,scale=1"],
        "needs a wavelength",
    );
    run(&["--model", "nope", "--params", "scale=1"], "unknown model");
    run(
        &["--model", "lambert", "--params", "scale=x"],
        "'x' is not a number",
    );
    run(&["--model", "lambert", "--params", ""], "missing");
    run(
        &[
            "--model",
            "lambert",
            "--params",
            "scale=1",
            "--columns",
            "speed=v",
        ],
        "unknown role",
    );
    run(
        &[
            "--model",
            "lambert",
            "--params",
            "scale=1",
            "--quantity",
            "lux",
        ],
        "lux",
    );
    run(
        &[
            "--model",
            "kbs",
            "--params",
            "sigma=0.3,T=2,scale=1",
            "--wavelength",
            "1",
            "--patch",
            "3",
        ],
        "--patch",
    );
    run(
        &[
            "--model",
            "kbs",
            "--params",
            "sigma=0.3,T=2,scale=1",
            "--wavelength",
            "-1",
        ],
        "wavelength",
    );
    // A missing input file.
    goniofit()
        .args([
            "eval",
            "--model",
            "lambert",
            "--params",
            "scale=1",
            "/no/such/file.csv",
        ])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("/no/such/file.csv"));
    // A multi-channel ASTM file without --channel lists the channels.
    goniofit()
        .args(["eval", "--model", "lambert", "--params", "scale=1"])
        .arg(data("cornell/krylon_blue.astm"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--channel").and(predicate::str::contains("550nm")));
}

#[cfg(unix)]
#[test]
fn eval_into_a_closed_pipe_is_quiet() {
    use std::io::Read;
    use std::process::Stdio;
    // ~2 MB of output, far more than a pipe buffer: the writer meets the closed pipe.
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("goniofit"))
        .args(["eval", "--model", "lambert", "--params", "scale=1"])
        .arg(data("nist-ptfe/PTFE.data.csv"))
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 16];
    child
        .stdout
        .as_mut()
        .unwrap()
        .read_exact(&mut first)
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    assert_eq!(&first[..6], b"lambda");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn eval_output_fed_back_replaces_l_model() {
    let dir = tempfile::tempdir().unwrap();
    let first = dir.path().join("first.csv");
    let second = dir.path().join("second.csv");
    goniofit()
        .args(["eval", "--model", "lambert", "--params", "scale=1", "-o"])
        .arg(&first)
        .arg(data("angles_inplane.csv"))
        .assert()
        .success();
    goniofit()
        .args(["eval", "--model", "lambert", "--params", "scale=2", "-o"])
        .arg(&second)
        .arg(&first)
        .assert()
        .success();
    let (h1, r1) = parse_out(&std::fs::read(&first).unwrap());
    let (h2, r2) = parse_out(&std::fs::read(&second).unwrap());
    assert_eq!(h1, h2);
    for (a, b) in r1.iter().zip(&r2) {
        let (a, b): (f64, f64) = (a[4].parse().unwrap(), b[4].parse().unwrap());
        assert_eq!(b, 2.0 * a);
    }
}
