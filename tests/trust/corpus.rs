//! The real-data corpus against its reference optima (tests/ref/corpus_reference.csv, made
//! by tests/ref/corpus_reference.py: 85 starts per fit with goniofit's solver, amplitudes
//! fitted by scipy). Every default fit (kbs+lambert, BRDF, log residuals) must be either
//! converged at the best known optimum — cost within [`TOL`] of the table's, inside the
//! physical domain — or `degenerate` with a note when the best known point lies at an edge
//! of the domain. CI runs a subset: the 61 CUReT samples and every channel of the Cornell
//! krylon_blue and acryl_blue paints (about 95 fits, ~15 s of one core); the whole corpus
//! is `python3 benches/corpus.py target/release/goniofit`.

use std::collections::HashMap;

use crate::common;

/// Relative cost above the reference's best within which a fit is at the best known
/// optimum: the reduced refit holds σ in a regime, and the solves stop off the rough and
/// smooth ridges (`RIDGE_G`, `SMOOTH_RIDGE_G`), which costs up to ~1e-5 of the cost.
const TOL: f64 = 1e-3;

struct Reference {
    cost_best: f64,
    edge_best: String,
}

/// The rows of a committed table in tests/ref (comment lines skipped), each as column
/// name → field.
fn table(name: &str) -> Vec<HashMap<String, String>> {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/ref")
        .join(name);
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let head: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines
        .map(|l| {
            head.iter()
                .cloned()
                .zip(l.split(',').map(String::from))
                .collect()
        })
        .collect()
}

fn reference() -> HashMap<(String, String), Reference> {
    table("corpus_reference.csv")
        .into_iter()
        .map(|row| {
            let r = Reference {
                cost_best: row["cost_best"].parse().unwrap(),
                edge_best: row["edge_best"].clone(),
            };
            ((row["file"].clone(), row["group"].clone()), r)
        })
        .collect()
}

/// The --by-group fits of one file: (group label, report).
fn fits(path: &str, extra: &[&str]) -> Vec<(String, serde_json::Value)> {
    let file = common::data(path);
    let out = common::goniofit()
        .args(common::PAINT_BRDF_LOG)
        .args(["--by-group", "--no-intervals", "--json", "--threads", "1"])
        .args(extra)
        .arg(&file)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout)
        .unwrap_or_else(|e| panic!("{path}: {e}: {}", String::from_utf8_lossy(&out.stderr)));
    v["fits"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let name = f["input"].as_str().unwrap();
            let group = name[name.rfind('[').unwrap() + 1..name.len() - 1].to_string();
            (group, f.clone())
        })
        .collect()
}

/// The physical domain of KBS as the fit states it (T/σ ≥ 0.1, 2πT/λ ≥ 0.1).
fn inside(f: &serde_json::Value, lambda: f64) -> bool {
    let p = |k: &str| f["params"][k]["value"].as_f64().unwrap();
    let (sigma, t) = (p("sigma"), p("T"));
    t / sigma >= 0.1 && 2.0 * std::f64::consts::PI * t / lambda >= 0.1 && p("scale") > 0.0
}

/// Check every fit of one file; returns the failures.
fn check(path: &str, extra: &[&str], lambda_of: &dyn Fn(&str) -> f64) -> Vec<String> {
    let reference = reference();
    let file = path.rsplit('/').next().unwrap().to_string();
    let mut bad = Vec::new();
    let all = fits(path, extra);
    assert!(all.len() >= 31, "{path}: {} fits", all.len());
    for (group, f) in all {
        let r = &reference[&(file.clone(), group.clone())];
        let cost = f["cost"].as_f64().unwrap();
        let excess = cost / r.cost_best - 1.0;
        let ok = match f["termination"].as_str().unwrap() {
            "degenerate" => r.edge_best != "none" && !f["notes"].as_array().unwrap().is_empty(),
            _ if f["converged"] != true || !inside(&f, lambda_of(&group)) => false,
            _ => excess <= TOL,
        };
        if !ok {
            bad.push(format!(
                "{file} {group}: {} cost {cost:.7e} vs best {:.7e} ({:+.3e}), best at edge: {}",
                f["termination"], r.cost_best, excess, r.edge_best,
            ));
        }
    }
    bad
}

fn nm(group: &str) -> f64 {
    group.trim_end_matches("nm").parse().unwrap()
}

#[test]
fn curet_fits_are_at_the_best_known_optimum_or_degenerate_at_an_edge() {
    let bad = check("curet/curet.csv", &["--wavelength", "550"], &|_| 550.0);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn cornell_krylon_blue_fits_are_at_the_best_known_optimum() {
    let bad = check("cornell/krylon_blue.astm", &[], &nm);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

#[test]
fn cornell_acryl_blue_fits_are_at_the_best_known_optimum() {
    let bad = check("cornell/acryl_blue.astm", &[], &nm);
    assert!(bad.is_empty(), "{}", bad.join("\n"));
}

/// The reference table against tests/ref/corpus_crosscheck.csv (an independent numpy
/// model and scipy's bounded trust-region solver from 13 starts, σ ≤ 10 λ): at the table's
/// point the two models give the same cost (to 1e-8), and scipy finds no optimum lower than
/// the table's best by more than 1e-6 of it (the smooth ridge of acryl_blue 550 nm still
/// descends by ~1e-8 towards σ → 0).
#[test]
fn the_reference_optima_agree_with_an_independent_scipy_fit() {
    let reference = reference();
    let rows = table("corpus_crosscheck.csv");
    for row in &rows {
        let r = &reference[&(row["file"].clone(), row["group"].clone())];
        let num = |name: &str| -> f64 { row[name].parse().unwrap() };
        let at_point = num("numpy_cost_at_table_point");
        let scipy = num("scipy_best_cost");
        assert!(
            (at_point / num("cost_inside") - 1.0).abs() < 1e-8,
            "{row:?}"
        );
        assert!(scipy >= r.cost_best * (1.0 - 1e-6), "{row:?}");
    }
    let rows = rows.len();
    assert!(rows >= 9, "{rows} rows");
}
