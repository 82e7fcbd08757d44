//! The trust matrix's slice that CI runs: goniofit's default fit of one case per model and
//! residual kind (and an honestly degenerate one), each either at the best optimum an
//! independent multi-start found (tests/ref/trust_reference.py, its table
//! tests/ref/trust_reference.csv: numpy model, scipy least_squares, ≥ 20 starts) or
//! `degenerate` where that optimum lies at an edge of the domain. `benches/trust.py` runs
//! the whole matrix and classes every case the same way.

use crate::common;

use common::goniofit;
use std::collections::HashMap;

/// Relative cost within which a fit is at the best known optimum.
const TOL: f64 = 1e-4;

/// (dataset, model, residual): every model × residual kind once, on the smallest files
/// (synthetic scans, CUReT surfaces of 205 samples, the PTFE 633 nm channel), and a case of
/// each kind of valley the start search must not miss.
const SLICE: [(&str, &str, &str); 21] = [
    ("synthetic/kbs_inplane", "kbs", "absolute"),
    ("curet/8", "kbs", "relative"),
    ("curet/8", "kbs", "log"),
    ("synthetic/kbs_inplane", "kbs+lambert", "absolute"),
    ("curet/6", "kbs+lambert", "relative"),
    ("curet/1", "kbs+lambert", "log"),
    ("synthetic/lambert_specular", "lambert-specular", "absolute"),
    ("curet/4", "lambert-specular", "relative"),
    ("curet/6", "lambert-specular", "log"),
    ("synthetic/kbs_inplane", "lambert", "absolute"),
    ("synthetic/kbs_inplane", "lambert", "relative"),
    ("curet/7", "lambert", "log"),
    ("synthetic/kbs_rough", "kbs-rough", "absolute"),
    ("curet/7", "kbs-rough", "relative"),
    ("synthetic/kbs_hemisphere", "kbs-rough", "log"),
    ("nist-ptfe/633nm", "lambert", "log"),
    // Its best point is the Lambertian term alone: the lobe's amplitude B at 0.
    ("synthetic/kbs_hemisphere", "lambert-specular", "relative"),
    // A Lambertian term whose log-residual optimum lies just above the floor.
    ("synthetic/kbs_hemisphere", "lambert", "log"),
    // A broad lobe that a subsample of the file ranks below a narrow one.
    ("cornell/garnet_red/650nm", "lambert-specular", "log"),
    // The smooth valley (σ → 0 at fixed sσ²), below a rougher one.
    ("cornell/acryl_blue/550nm", "kbs", "relative"),
    // A log-residual cost rugged on the scale of a per cent.
    ("cornell/acryl_blue/650nm", "kbs-rough", "log"),
];

/// The reference table's rows by (dataset, model, residual).
fn reference() -> HashMap<(String, String, String), HashMap<String, String>> {
    common::reference_rows("trust_reference.csv")
        .into_iter()
        .map(|row| {
            let key = (
                row["dataset"].clone(),
                row["model"].clone(),
                row["residual"].clone(),
            );
            (key, row)
        })
        .collect()
}

/// Why goniofit's default fit of this case is not at the reference's best optimum (or
/// honestly degenerate), or None when it is.
fn failure(row: &HashMap<String, String>) -> Option<String> {
    let mut cmd = goniofit();
    cmd.args([
        "fit",
        "--model",
        &row["model"],
        "--residual",
        &row["residual"],
    ])
    .args(row["args"].split_whitespace())
    .args(["--json", "--no-intervals", "--threads", "1"])
    .current_dir(env!("CARGO_MANIFEST_DIR"));
    let out = cmd.output().unwrap();
    let case = format!("{} {} {}", row["dataset"], row["model"], row["residual"]);
    let Ok(v) = serde_json::from_slice::<serde_json::Value>(&out.stdout) else {
        return Some(format!(
            "{case}: no report: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    };
    let reference: f64 = row["cost_best"].parse().unwrap();
    let cost = v["cost"].as_f64().unwrap_or(f64::INFINITY);
    let best = reference.min(cost);
    let at_edge = !matches!(row["edge_best"].as_str(), "none" | "sigma-cap");
    let term = v["termination"].as_str().unwrap_or("");
    match (term, v["converged"].as_bool()) {
        ("degenerate", _) if at_edge => None,
        ("degenerate", _) => Some(format!(
            "{case}: degenerate at cost {cost:e}; the reference's best {reference:e} is inside the domain"
        )),
        (_, Some(true)) if cost <= best * (1.0 + TOL) => None,
        (_, Some(true)) => Some(format!(
            "{case}: converged ({term}) at cost {cost:e}, above the reference's {reference:e}"
        )),
        _ => Some(format!("{case}: {term} at cost {cost:e}")),
    }
}

#[test]
fn default_fits_reach_the_best_known_optimum_or_say_degenerate_at_its_edge() {
    let table = reference();
    let mut models = std::collections::BTreeSet::new();
    let mut kinds = std::collections::BTreeSet::new();
    let failures: Vec<String> = SLICE
        .iter()
        .filter_map(|&(d, m, r)| {
            models.insert(m);
            kinds.insert(r);
            let row = table
                .get(&(d.into(), m.into(), r.into()))
                .unwrap_or_else(|| panic!("{d} {m} {r} is not in the reference table"));
            failure(row)
        })
        .collect();
    assert_eq!(models.len(), 5, "every model");
    assert_eq!(kinds.len(), 3, "every residual kind");
    assert!(failures.is_empty(), "{failures:#?}");
}
