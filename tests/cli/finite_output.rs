//! No NaN or ±inf is ever printed with exit code 0: `eval`, `synth` and `render` refuse
//! parameters at which the model overflows (exit 2, naming the sample and the parameters),
//! warn on standard error outside the documented accuracy range, and say "not a number"
//! for `nan`.

use crate::common;

use common::{data, fit_json, goniofit};
use predicates::prelude::*;

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
    ] {
        eval(model, params, extra).code(2).stdout("").stderr(
            predicate::str::contains(format!("model {model} is not a finite number"))
                .and(predicate::str::contains(shown))
                .and(predicate::str::contains("theta_i = ")),
        );
    }
    // A wavelength beyond the lengths any option takes is refused before evaluating.
    eval("kbs", "sigma=0.3,T=2,scale=1", &["--wavelength", "1e-300"])
        .code(2)
        .stdout("")
        .stderr(predicate::str::contains(
            "'1e-300': a length must lie within [1e-30, 1e30]",
        ));
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

/// data/synthetic/kbs_hemisphere.csv with L (and sigma_L) multiplied by `c`, written to a
/// scratch file; `with_sigma` keeps the sigma_L column.
fn hemisphere_times(c: f64, with_sigma: bool) -> std::path::PathBuf {
    let text = std::fs::read_to_string(data("synthetic/kbs_hemisphere.csv")).unwrap();
    let mut out = String::new();
    for (k, line) in text.lines().enumerate() {
        let f: Vec<&str> = line.split(',').collect();
        let keep = if with_sigma { 5 } else { 4 };
        if k == 0 {
            out += &f[..keep].join(",");
        } else {
            let v: Vec<f64> = f.iter().map(|x| x.parse().unwrap()).collect();
            let mut row: Vec<String> = v[..3].iter().map(|x| x.to_string()).collect();
            row.extend(v[3..keep].iter().map(|x| format!("{:e}", x * c)));
            out += &row.join(",");
        }
        out.push('\n');
    }
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("units_of_l");
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(format!("h_{c:e}_{with_sigma}.csv"));
    std::fs::write(&p, out).unwrap();
    p
}

#[test]
fn the_verdict_does_not_depend_on_the_unit_of_l() {
    // The same scan in units 1e10 larger or smaller: the same verdict as ×1 (the rank
    // decision uses unit-norm Jacobian columns, so "scale not determined" never comes from
    // the unit), converged, and the same parameters in that unit.
    for with_sigma in [true, false] {
        let fit = |c: f64| {
            let p = hemisphere_times(c, with_sigma);
            let p = p.to_str().unwrap().to_string();
            fit_json(&["fit", "--wavelength", "1", "--no-intervals", "--json", &p])
        };
        let one = fit(1.0);
        assert_eq!(one["converged"], true);
        for c in [1e-10, 1e6, 1e10] {
            let v = fit(c);
            assert_eq!(
                v["verdict"], one["verdict"],
                "×{c:e} (sigma_L: {with_sigma})"
            );
            assert_eq!(v["converged"], true, "×{c:e}");
            for name in ["sigma", "T", "scale"] {
                let unit = if name == "scale" { c } else { 1.0 };
                let (a, b) = (&one["params"][name], &v["params"][name]);
                for key in ["value", "stderr"] {
                    let (x, y) = (a[key].as_f64().unwrap(), b[key].as_f64().unwrap() / unit);
                    assert!(
                        (x - y).abs() <= 1e-6 * x.abs(),
                        "{name}.{key}: {x} vs {y} at ×{c:e} (sigma_L: {with_sigma})"
                    );
                }
            }
        }
    }
}
