//! A default fit ends at the best known optimum, `converged`: where a mixed model's extra
//! term is absent from the data (its amplitude at the bound 0), where the weights span fifty
//! decades (σ_L ∝ L), and on the rough ridge of a Cornell channel; and a fit of the data in
//! any unit of L (10⁻⁹⁰ … 10⁹⁰, with σ_L scaled alike) gives the same parameters in that
//! unit, for every model and residual kind. The best known costs are in
//! tests/ref/optimum_trust.csv (an independent multi-start reference).

use crate::common;

use common::{data, run_json};

/// Relative cost above the best known within which a fit is at it.
const TOL: f64 = 1e-4;

/// The cases of tests/ref/optimum_trust.csv: (arguments after `fit`, best known cost).
fn cases() -> Vec<(Vec<String>, f64)> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ref/optimum_trust.csv");
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split(';').collect();
            let mut args: Vec<String> = f[0].split_whitespace().map(String::from).collect();
            let file = args.pop().unwrap();
            args.push(data(&file).to_string_lossy().into_owned());
            (args, f[1].parse().unwrap())
        })
        .collect()
}

#[test]
fn default_fits_converge_at_the_best_known_optimum() {
    let mut bad = Vec::new();
    for (args, best) in cases() {
        let mut full = vec!["fit".to_string(), "--no-intervals".to_string()];
        full.extend(args.iter().cloned());
        let (code, v) = run_json(&full);
        let cost = v["cost"].as_f64().unwrap();
        if code != Some(0) || v["converged"] != true || cost > best * (1.0 + TOL) {
            bad.push(format!(
                "{}: exit {code:?}, {} at cost {cost} (best known {best})",
                args.join(" "),
                v["termination"]
            ));
        }
    }
    assert!(bad.is_empty(), "{bad:#?}");
}

/// garnet_red by channel with absolute residuals (the `fit --help` example): every channel
/// converges, and 550 nm reaches the reference optimum on the rough ridge.
#[test]
fn every_garnet_red_channel_converges_with_absolute_residuals() {
    let dir = tempfile::tempdir().unwrap();
    let summary = dir.path().join("fits.csv");
    let out = common::goniofit()
        .args([
            "fit",
            "--model",
            "kbs+lambert",
            "--by-group",
            "--no-intervals",
            "--summary",
        ])
        .arg(&summary)
        .arg(data("cornell/garnet_red.astm"))
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&summary).unwrap();
    let mut rows = text.lines();
    let header: Vec<&str> = rows.next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (converged, cost, group) = (col("converged"), col("cost"), col("group"));
    let rows: Vec<Vec<&str>> = rows.map(|r| r.split(',').collect()).collect();
    assert_eq!(rows.len(), 31);
    for r in &rows {
        assert_eq!(r[converged], "true", "{}", r[group]);
    }
    let at_550 = rows.iter().find(|r| r[group].contains("[550nm]")).unwrap();
    let c: f64 = at_550[cost].parse().unwrap();
    assert!(c <= 123.010 * (1.0 + TOL), "550 nm cost {c}");
}

/// `path` with the columns `cols` multiplied by `factor` (written to `out`).
fn scaled(path: &std::path::Path, out: &std::path::Path, cols: &[&str], factor: f64) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap();
    let idx: Vec<usize> = header
        .split(',')
        .enumerate()
        .filter(|(_, h)| cols.contains(h))
        .map(|(i, _)| i)
        .collect();
    let mut s = format!("{header}\n");
    for l in lines {
        let f: Vec<String> = l
            .split(',')
            .enumerate()
            .map(|(i, v)| {
                if idx.contains(&i) {
                    format!("{:e}", v.parse::<f64>().unwrap() * factor)
                } else {
                    v.to_string()
                }
            })
            .collect();
        s.push_str(&f.join(","));
        s.push('\n');
    }
    std::fs::write(out, s).unwrap();
}

/// The fitted values of a report (name → value).
fn values(v: &serde_json::Value) -> Vec<(String, f64)> {
    let mut p: Vec<(String, f64)> = v["params"]
        .as_object()
        .unwrap()
        .iter()
        .map(|(k, x)| (k.clone(), x["value"].as_f64().unwrap()))
        .collect();
    p.sort_by(|a, b| a.0.cmp(&b.0));
    p
}

/// Whether two fits of one data in units a factor `f` apart agree: the same termination,
/// the amplitudes scaled by `f`, the rest equal (to 10⁻⁴ relative: rounding in another
/// unit may end a solve one step apart).
fn same_in_unit(a: &serde_json::Value, b: &serde_json::Value, f: f64) -> Result<(), String> {
    if a["termination"] != b["termination"] {
        return Err(format!("{} vs {}", a["termination"], b["termination"]));
    }
    for ((name, x), (_, y)) in values(a).iter().zip(values(b)) {
        let amplitude = ["scale", "scale_d", "B"].contains(&name.as_str());
        let x = if amplitude { x * f } else { *x };
        let scale = x.abs().max(y.abs());
        // An amplitude at its bound 0 has no relative accuracy: compare to the other one.
        let floor = if amplitude {
            1e-6 * a["params"]["scale"]["value"].as_f64().unwrap_or(0.0).abs() * f
        } else {
            0.0
        };
        if (x - y).abs() > 1e-4 * scale + floor.abs() {
            return Err(format!("{name}: {x} vs {y}"));
        }
    }
    Ok(())
}

/// Every model and residual kind fitted to one file in units of L 10⁻⁹⁰ … 10⁹⁰ apart (with
/// σ_L scaled alike when the file has it) gives the same fit in that unit.
fn invariant_under_the_unit_of_l(file: &std::path::Path, extra: &[&str], factors: &[f64]) {
    let dir = tempfile::tempdir().unwrap();
    let mut bad = Vec::new();
    let scaled_files: Vec<_> = factors
        .iter()
        .map(|f| {
            let out = dir.path().join(format!("scaled{f:e}.csv"));
            scaled(file, &out, &["L", "sigma_L"], *f);
            out
        })
        .collect();
    for model in [
        "kbs",
        "kbs+lambert",
        "lambert-specular",
        "lambert",
        "kbs-rough",
    ] {
        for residual in ["absolute", "relative", "log"] {
            let fit = |path: &std::path::Path| {
                let mut args = vec![
                    "fit",
                    "--no-intervals",
                    "--model",
                    model,
                    "--residual",
                    residual,
                ];
                args.extend_from_slice(extra);
                let p = path.to_string_lossy().into_owned();
                let mut args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
                args.push(p);
                run_json(&args)
            };
            let (code, base) = fit(file);
            for (f, path) in factors.iter().zip(&scaled_files) {
                let (c, v) = fit(path);
                if c != code {
                    bad.push(format!("{model} {residual} ×{f:e}: exit {c:?} vs {code:?}"));
                } else if let Err(e) = same_in_unit(&base, &v, *f) {
                    bad.push(format!("{model} {residual} ×{f:e}: {e}"));
                }
            }
        }
    }
    assert!(bad.is_empty(), "{bad:#?}");
}

#[test]
fn every_fit_is_invariant_under_the_unit_of_l() {
    let dir = tempfile::tempdir().unwrap();
    let h = dir.path().join("h.csv");
    let out = common::goniofit()
        .args([
            "synth",
            "--model",
            "kbs",
            "--params",
            "sigma=0.3,T=2,scale=1",
        ])
        .args(["--noise", "0.01", "--seed", "1", "--out"])
        .arg(&h)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    invariant_under_the_unit_of_l(&h, &["--wavelength", "1"], &[1e-90, 1e-30, 1e30, 1e90]);
}

/// kbs_hemisphere.csv: σ_L = 1 % of L, so its weights 1/σ_L² span 10⁴ … 10⁴⁹; the factors
/// keep them inside what the fit accepts (a file beyond is refused, exit 2, saying so).
#[test]
fn every_fit_with_sigma_l_is_invariant_under_the_unit_of_l() {
    invariant_under_the_unit_of_l(
        &data("synthetic/kbs_hemisphere.csv"),
        &["--wavelength", "1"],
        &[1e-25, 1e-10, 1e10, 1e50],
    );
}
