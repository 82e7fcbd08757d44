//! One line per fit: the overview after `--by-group`, several files or `--channel all`, as a
//! text table and as CSV rows (`--summary FILE.csv`).

use super::setting::Units;
use super::text::fixed;
use crate::fit::driver::{FitResult, Verdict};
use crate::fit::stats::adequacy::AdequacyVerdict;
use std::fmt::Write;

/// A fit's summary.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Row {
    /// The dataset (file, with `[group]`).
    pub group: String,
    /// Number of samples fitted.
    pub n: usize,
    /// Whether the fit is a usable optimum ([`FitResult::converged`]).
    pub converged: bool,
    /// Why the solver stopped, as in JSON (`ftol`, `maxiterations`, `degenerate`, …).
    pub termination: String,
    /// The minimised cost ½ Σ C²ρ(wᵢrᵢ²/C²) (½χ² for the linear loss).
    pub cost: f64,
    /// Weighted R² in the residuals' space (NaN when undefined or not computed).
    pub r2: f64,
    /// σ, T, T/σ: value and whether the data determines it (None: not in the model).
    pub sigma: Option<(f64, bool)>,
    /// The fitted T, in [`Row::length_unit`], and whether the data determines it.
    pub t: Option<(f64, bool)>,
    /// The derived T/σ and whether the data determines it.
    pub ratio: Option<(f64, bool)>,
    /// What the data determines.
    pub verdict: Verdict,
    /// Whether the model describes the data, and the codes of the reasons when not.
    pub adequacy: AdequacyVerdict,
    /// The adequacy reason codes, comma-separated (empty when none).
    pub adequacy_reasons: String,
    /// Unit of σ and T.
    pub length_unit: String,
}

/// The summary row of one fit.
pub(crate) fn row(group: &str, r: &FitResult, units: &Units) -> Row {
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
        termination: format!("{:?}", r.termination).to_lowercase(),
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
        adequacy: r.adequacy.verdict,
        adequacy_reasons: r.adequacy.codes(),
        length_unit: units.length_name(),
    }
}

/// The short word for a verdict, as in the table and CSV.
pub(crate) fn verdict_word(v: Verdict) -> &'static str {
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
pub(crate) fn cell(v: Option<(f64, bool)>) -> String {
    match v {
        Some((x, true)) => format!("{x:.4e}"),
        Some((x, false)) => format!("({x:.3e})"),
        None => "-".into(),
    }
}

/// A column's cell of one row.
type Cell = fn(&Row) -> String;

/// The text table's columns between the group and the verdict: header, width (right
/// aligned) and cell. A new column is one more entry here (and in [`CSV_COLUMNS`]).
const TABLE_COLUMNS: [(&str, usize, Cell); 8] = [
    ("n", 6, |r| r.n.to_string()),
    ("conv", 5, |r| {
        (if r.converged { "yes" } else { "NO" }).into()
    }),
    ("termination", 13, |r| r.termination.clone()),
    ("cost", 12, |r| format!("{:.5e}", r.cost)),
    ("R²", 10, |r| fixed(r.r2, 6)),
    ("σ", 11, |r| cell(r.sigma)),
    ("T", 11, |r| cell(r.t)),
    ("T/σ", 11, |r| cell(r.ratio)),
];

/// How many fits did not converge and why, e.g. `2 did not converge (maxiterations 1,
/// degenerate 1)`; None when every fit converged.
pub(crate) fn not_converged(rows: &[Row]) -> Option<String> {
    let mut why: Vec<(&str, usize)> = Vec::new();
    for r in rows.iter().filter(|r| !r.converged) {
        match why.iter_mut().find(|(t, _)| *t == r.termination) {
            Some((_, k)) => *k += 1,
            None => why.push((&r.termination, 1)),
        }
    }
    let total: usize = why.iter().map(|(_, k)| k).sum();
    (total > 0).then(|| {
        let list: Vec<String> = why.iter().map(|(t, k)| format!("{t} {k}")).collect();
        format!("{total} did not converge ({})", list.join(", "))
    })
}

/// The summary as a text table (`[[Summary]]`), one line per fit; values the data does not
/// determine are in parentheses. The title counts the fits that did not converge, and each
/// row gives its termination.
pub(crate) fn table(rows: &[Row]) -> String {
    let mut s = String::new();
    let unit = rows
        .first()
        .map_or(String::new(), |r| r.length_unit.clone());
    let failed = not_converged(rows).map_or(String::new(), |t| format!(", {t}"));
    let _ = writeln!(
        s,
        "[[Summary]] ({} fits{failed}; σ, T in {unit}; values in parentheses are not determined by the data)",
        rows.len()
    );
    let gw = rows
        .iter()
        .map(|r| r.group.chars().count())
        .max()
        .unwrap_or(5)
        .max(5);
    let mut line = |group: &str, cells: Vec<String>, verdict: &str, adequacy: &str| {
        let _ = write!(s, "    {group:<gw$}");
        for ((_, w, _), c) in TABLE_COLUMNS.iter().zip(cells) {
            let _ = write!(s, " {c:>w$}");
        }
        let _ = writeln!(s, "  {verdict:<16} {adequacy}");
    };
    line(
        "group",
        TABLE_COLUMNS.iter().map(|c| c.0.to_string()).collect(),
        "verdict",
        "adequacy",
    );
    for r in rows {
        let cells = TABLE_COLUMNS.iter().map(|c| (c.2)(r)).collect();
        line(&r.group, cells, verdict_word(r.verdict), &adequacy_cell(r));
    }
    s
}

/// The adequacy verdict with its reason codes, as in the table: `misfit (runs,floor)`; past
/// `ADEQUACY_WIDTH` characters of codes the rest are counted (`+2`; the CSV has them all).
pub(crate) fn adequacy_cell(r: &Row) -> String {
    if r.adequacy_reasons.is_empty() {
        return r.adequacy.name().to_string();
    }
    let mut shown = String::new();
    let codes: Vec<&str> = r.adequacy_reasons.split(',').collect();
    let mut k = 0;
    while k < codes.len() && (k == 0 || shown.len() + 1 + codes[k].len() <= ADEQUACY_WIDTH) {
        if k > 0 {
            shown.push(',');
        }
        shown.push_str(codes[k]);
        k += 1;
    }
    if k < codes.len() {
        shown.push_str(&format!(" +{}", codes.len() - k));
    }
    format!("{} ({shown})", r.adequacy.name())
}

/// Characters of reason codes the table shows.
const ADEQUACY_WIDTH: usize = 32;

/// A value with its determination as two CSV fields (full precision; empty fields where
/// the model has no such parameter).
fn split(v: Option<(f64, bool)>) -> (String, String) {
    match v {
        Some((x, d)) => (format!("{x:e}"), d.to_string()),
        None => (String::new(), String::new()),
    }
}

/// The CSV columns ([`csv_rows`]): name and cell. A new column is one more entry here.
const CSV_COLUMNS: [(&str, Cell); 17] = [
    ("group", |r| r.group.clone()),
    ("n", |r| r.n.to_string()),
    ("converged", |r| r.converged.to_string()),
    ("termination", |r| r.termination.clone()),
    ("cost", |r| format!("{:e}", r.cost)),
    ("r2", |r| {
        if r.r2.is_finite() {
            format!("{:e}", r.r2)
        } else {
            String::new()
        }
    }),
    ("sigma", |r| split(r.sigma).0),
    ("sigma_determined", |r| split(r.sigma).1),
    ("T", |r| split(r.t).0),
    ("T_determined", |r| split(r.t).1),
    ("T_over_sigma", |r| split(r.ratio).0),
    ("T_over_sigma_determined", |r| split(r.ratio).1),
    ("verdict", |r| format!("{:?}", r.verdict).to_lowercase()),
    ("length_unit", |r| r.length_unit.clone()),
    ("verdict_text", |r| verdict_word(r.verdict).to_string()),
    ("adequacy", |r| r.adequacy.name().to_string()),
    ("adequacy_reasons", |r| r.adequacy_reasons.clone()),
];

/// The CSV header of [`csv_rows`].
pub(crate) fn csv_header() -> Vec<String> {
    CSV_COLUMNS.iter().map(|c| c.0.to_string()).collect()
}

/// The rows as CSV fields (full precision; empty fields where the model has no σ or T).
pub(crate) fn csv_rows(rows: &[Row]) -> Vec<Vec<String>> {
    use rayon::prelude::*;
    rows.par_iter()
        .map(|r| CSV_COLUMNS.iter().map(|c| (c.1)(r)).collect())
        .collect()
}
