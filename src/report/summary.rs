//! One line per fit: the overview after `--by-group`, several files or `--channel all`, as a
//! text table and as CSV rows (`--summary FILE.csv`).

use super::setting::Units;
use super::text::fixed;
use crate::fit::driver::{FitResult, Verdict};
use std::fmt::Write;

/// A fit's summary.
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// The dataset (file, with `[group]`).
    pub group: String,
    pub n: usize,
    pub converged: bool,
    pub cost: f64,
    pub r2: f64,
    /// σ, T, T/σ: value and whether the data determines it (None: not in the model).
    pub sigma: Option<(f64, bool)>,
    pub t: Option<(f64, bool)>,
    pub ratio: Option<(f64, bool)>,
    pub verdict: Verdict,
    /// Unit of σ and T.
    pub length_unit: String,
}

/// The summary row of one fit.
pub fn row(group: &str, r: &FitResult, units: &Units) -> Row {
    let param = |name: &str| {
        r.params
            .iter()
            .find(|p| p.name == name)
            .map(|p| (p.value, p.determined))
    };
    Row {
        group: group.to_string(),
        n: r.n,
        converged: r.converged(),
        cost: r.cost,
        r2: r.r2,
        sigma: param("sigma"),
        t: param("T"),
        ratio: r
            .derived
            .iter()
            .find(|d| d.name == "T/sigma")
            .map(|d| (d.value, d.determined)),
        verdict: r.verdict,
        length_unit: units.length_name(),
    }
}

/// The short word for a verdict, as in the table and CSV.
pub fn verdict_word(v: Verdict) -> &'static str {
    match v {
        Verdict::Full => "determined",
        Verdict::Rough => "rough: T/σ only",
        Verdict::Smooth => "smooth: T only",
        Verdict::Partial => "partial",
        Verdict::NotComputed => "not computed",
    }
}

/// A value for the table: 4 significant digits, in parentheses when undetermined, `-` when
/// the model has no such parameter.
fn cell(v: Option<(f64, bool)>) -> String {
    match v {
        Some((x, true)) => format!("{x:.4e}"),
        Some((x, false)) => format!("({x:.3e})"),
        None => "-".into(),
    }
}

/// The summary as a text table (`[[Summary]]`), one line per fit; values the data does not
/// determine are in parentheses.
pub fn table(rows: &[Row]) -> String {
    let mut s = String::new();
    let unit = rows
        .first()
        .map_or(String::new(), |r| r.length_unit.clone());
    let _ = writeln!(
        s,
        "[[Summary]] ({} fits; σ, T in {unit}; values in parentheses are not determined by the data)",
        rows.len()
    );
    let gw = rows
        .iter()
        .map(|r| r.group.chars().count())
        .max()
        .unwrap_or(5)
        .max(5);
    let _ = writeln!(
        s,
        "    {:<gw$} {:>6} {:>5} {:>12} {:>10} {:>11} {:>11} {:>11}  verdict",
        "group", "n", "conv", "cost", "R²", "σ", "T", "T/σ"
    );
    for r in rows {
        let _ = writeln!(
            s,
            "    {:<gw$} {:>6} {:>5} {:>12} {:>10} {:>11} {:>11} {:>11}  {}",
            r.group,
            r.n,
            if r.converged { "yes" } else { "NO" },
            format!("{:.5e}", r.cost),
            fixed(r.r2, 6),
            cell(r.sigma),
            cell(r.t),
            cell(r.ratio),
            verdict_word(r.verdict)
        );
    }
    s
}

/// The CSV header of [`csv_rows`].
pub const CSV_HEADER: [&str; 14] = [
    "group",
    "n",
    "converged",
    "cost",
    "r2",
    "sigma",
    "sigma_determined",
    "T",
    "T_determined",
    "T_over_sigma",
    "T_over_sigma_determined",
    "verdict",
    "length_unit",
    "verdict_text",
];

/// The rows as CSV fields (full precision; empty fields where the model has no σ or T).
pub fn csv_rows(rows: &[Row]) -> Vec<Vec<String>> {
    let split = |v: Option<(f64, bool)>| match v {
        Some((x, d)) => (format!("{x:e}"), d.to_string()),
        None => (String::new(), String::new()),
    };
    rows.iter()
        .map(|r| {
            let (s, sd) = split(r.sigma);
            let (t, td) = split(r.t);
            let (q, qd) = split(r.ratio);
            vec![
                r.group.clone(),
                r.n.to_string(),
                r.converged.to_string(),
                format!("{:e}", r.cost),
                if r.r2.is_finite() {
                    format!("{:e}", r.r2)
                } else {
                    String::new()
                },
                s,
                sd,
                t,
                td,
                q,
                qd,
                format!("{:?}", r.verdict).to_lowercase(),
                r.length_unit.clone(),
                verdict_word(r.verdict).to_string(),
            ]
        })
        .collect()
}
