//! No NaN or ±inf is ever printed with exit code 0: `eval`, `synth` and `render` refuse
//! parameters at which the model overflows (exit 2, naming the sample and the parameters),
//! warn on standard error outside the documented accuracy range, and say "not a number"
//! for `nan`.

use assert_cmd::Command;
use predicates::prelude::*;
use std::path::{Path, PathBuf};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data").join(p)
}

fn goniofit() -> Command {
    Command::cargo_bin("goniofit").unwrap()
}

/// `eval --model M --params P [extra] angles_inplane.csv`.
fn eval(model: &str, params: &str, extra: &[&str]) -> assert_cmd::assert::Assert {
    goniofit()
        .args(["eval", "--model", model, "--params", params])
        .args(extra)
        .arg(data("angles_inplane.csv"))
        .assert()
}

#[test]
fn eval_refuses_parameters_where_the_model_overflows() {
    for (model, params, extra, shown) in [
        (
            "kbs",
            "sigma=1e300,T=1e300,scale=1",
            &["--wavelength", "1"][..],
            "sigma = 1e300, T = 1e300, scale = 1",
        ),
        (
            "lambert-specular",
            "scale=1,B=1e308,w=1e-300",
            &[][..],
            "B = 1e308, w = 1e-300",
        ),
        (
            "kbs",
            "sigma=0.3,T=2,scale=1",
            &["--wavelength", "1e-300"][..],
            "wavelength 1e-300",
        ),
    ] {
        eval(model, params, extra).code(2).stdout("").stderr(
            predicate::str::contains(format!("model {model} is not a finite number"))
                .and(predicate::str::contains(shown))
                .and(predicate::str::contains("theta_i = ")),
        );
    }
}

#[test]
fn eval_warns_outside_the_documented_accuracy_range() {
    // T/λ = 2e5 > 1e5: finite values, exit 0, a warning naming the range.
    let out = eval("kbs", "sigma=0.3,T=2e5,scale=1", &["--wavelength", "1"])
        .success()
        .stderr(predicate::str::contains(
            "warning: T/wavelength = 2.000e5 is outside [1e-3, 1e5]",
        ))
        .get_output()
        .stdout
        .clone();
    let text = String::from_utf8(out).unwrap();
    assert!(!text.contains("NaN") && !text.contains("inf"), "{text}");
    // Inside the range: no warning at all.
    eval("kbs", "sigma=0.3,T=2,scale=1", &["--wavelength", "1"])
        .success()
        .stderr("");
}

#[test]
fn nan_is_not_a_number_not_missing() {
    for v in ["nan", "NaN", "inf", "-inf", "1e400"] {
        eval(
            "kbs",
            &format!("sigma={v},T=2,scale=1"),
            &["--wavelength", "1"],
        )
        .code(2)
        .stdout("")
        .stderr(
            predicate::str::contains(format!("parameter sigma: '{v}' is not a finite number"))
                .and(predicate::str::contains("missing").not()),
        );
    }
    eval("kbs", "sigma=nan,T=2,scale=1", &["--wavelength", "1"])
        .stderr(predicate::str::contains("NaN: not a number"));
    // A parameter really left out is still "missing".
    eval("kbs", "T=2,scale=1", &["--wavelength", "1"])
        .code(2)
        .stderr(predicate::str::contains("parameter sigma: missing"));
}

#[test]
fn render_refuses_instead_of_a_black_sphere() {
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("s.png");
    for (model, params, says) in [
        (
            "kbs",
            "sigma=1e300,T=1e300,scale=1",
            "is not a finite number",
        ),
        (
            "lambert-specular",
            "scale=1,B=1e308,w=1e-300",
            "is not a finite number",
        ),
    ] {
        goniofit()
            .args([
                "render", "sphere", "--model", model, "--params", params, "--size", "16", "--out",
            ])
            .arg(&png)
            .assert()
            .code(2)
            .stdout("")
            .stderr(predicate::str::contains(says));
        assert!(!png.exists());
    }
}

#[test]
fn synth_refuses_noise_that_overflows() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("s.csv");
    goniofit()
        .args([
            "synth", "--model", "lambert", "--params", "scale=1", "--noise", "1e308", "--out",
        ])
        .arg(&out)
        .assert()
        .code(2)
        .stderr(
            predicate::str::contains("noise level 1e308 overflows double precision")
                .and(predicate::str::contains("inf")),
        );
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // Large but representable noise is fine, and every value written is finite.
    goniofit()
        .args([
            "synth", "--model", "lambert", "--params", "scale=1", "--noise", "1e100", "--out",
        ])
        .arg(&out)
        .assert()
        .success();
    let text = std::fs::read_to_string(&out).unwrap();
    for line in text.lines().skip(1) {
        for f in line.split(',') {
            assert!(f.parse::<f64>().unwrap().is_finite(), "{line}");
        }
    }
    // Model overflow in synth: the same refusal as eval.
    goniofit()
        .args([
            "synth",
            "--model",
            "kbs",
            "--params",
            "sigma=1e300,T=1e300,scale=1",
        ])
        .assert()
        .code(2)
        .stdout("")
        .stderr(predicate::str::contains("model kbs is not a finite number"));
}
