//! The text table of a recovery run ([`RecoverReport::table`]): per regime and quantity
//! the errors and the ±2 s.e. coverage, the run's totals, and every outlier.

use super::{outliers, RecoverReport, SceneResult, COVERAGE_K, NARROW_LAYOUT};
use std::collections::BTreeMap;

/// "k1 n1, k2 n2, …" of a tally.
fn counts(tally: &BTreeMap<String, usize>) -> String {
    tally
        .iter()
        .map(|(k, v)| format!("{k} {v}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Format a number for the table: 3 significant digits, or `-`.
fn fmt_num(v: Option<f64>) -> String {
    match v {
        Some(x) if x.is_finite() => {
            if x == 0.0 {
                "0".to_string()
            } else if (1e-3..1e4).contains(&x.abs()) {
                format!("{x:.3}")
            } else {
                format!("{x:.2e}")
            }
        }
        _ => "-".to_string(),
    }
}

impl RecoverReport {
    /// With a Fresnel factor: in how many scenes the fit says the data determines n, and
    /// how many of those without (those on [`NARROW_LAYOUT`] among them).
    pub(crate) fn index_line(&self) -> Option<String> {
        let with: Vec<&SceneResult> = self
            .results
            .iter()
            .filter(|r| r.n_determined.is_some())
            .collect();
        if with.is_empty() {
            return None;
        }
        let not: Vec<&SceneResult> = with
            .iter()
            .copied()
            .filter(|r| r.n_determined == Some(false))
            .collect();
        Some(format!(
            "n determined in {} of {} scenes; not determined in {} ({} of the {} scenes on '{NARROW_LAYOUT}', which reach θ_loc = 40° only)",
            with.len() - not.len(),
            with.len(),
            not.len(),
            not.iter().filter(|r| r.scene.layout == NARROW_LAYOUT).count(),
            with.iter().filter(|r| r.scene.layout == NARROW_LAYOUT).count(),
        ))
    }

    /// The report as a text table.
    pub(crate) fn table(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "{:<13} {:>6}  {:<18} {:<10} {:>3}  {:>12} {:>12}  {:>8}",
            "regime", "scenes", "verdicts", "quantity", "n", "median|err|", "max|err|", "coverage"
        );
        for r in &self.regimes {
            regime_rows(&mut s, r);
        }
        self.total_lines(&mut s);
        self.outlier_lines(&mut s);
        s
    }

    /// The run's totals under the regimes: coverage, terminations, convergence and times,
    /// adequacy flags, and the index line of [`Self::index_line`].
    fn total_lines(&self, s: &mut String) {
        use std::fmt::Write as _;
        let _ = writeln!(
            s,
            "\ncoverage (truth within ±2 se): {} of {} scored truths (nominal {:.3})",
            fmt_num(Some(self.coverage)),
            self.n_with_stderr,
            self.nominal_coverage
        );
        let _ = writeln!(s, "terminations: {}", counts(&self.terminations));
        let _ = writeln!(
            s,
            "converged {}/{}, errors {}, median fit time {} s, total {} s",
            self.converged,
            self.scenes,
            self.errors,
            fmt_num(Some(self.median_seconds)),
            fmt_num(Some(self.total_seconds))
        );
        let _ = writeln!(
            s,
            "adequacy: {} of {} scenes flagged (correct model and weights: expected at most {} %){}",
            self.adequacy_flagged,
            self.scenes,
            100.0 * crate::fit::stats::adequacy::ALPHA,
            if self.adequacy_reasons.is_empty() {
                String::new()
            } else {
                format!(
                    "; reasons: {}",
                    counts(&self.adequacy_reasons)
                )
            }
        );
        if let Some(line) = self.index_line() {
            let _ = writeln!(s, "{line}");
        }
    }

    /// The truths outside ±COVERAGE_K s.e. with the confidently wrong count, their table,
    /// and the scenes that ended in an error.
    fn outlier_lines(&self, s: &mut String) {
        use std::fmt::Write as _;
        let _ = writeln!(
            s,
            "truths outside ±{COVERAGE_K} se: {} scenes, {} of them converged and confidently wrong (> {} se and > {:.0} %)",
            self.outliers.len(),
            self.wrong_converged,
            outliers::WRONG_SE,
            100.0 * outliers::WRONG_REL
        );
        s.push_str(&outliers::table(&self.outliers));
        for r in self.results.iter().filter(|r| r.error.is_some()) {
            let _ = writeln!(
                s,
                "scene {} ({}): {}",
                r.scene.id,
                r.scene.regime.name(),
                r.error.as_deref().unwrap_or("")
            );
        }
    }
}

/// One regime's rows of the table: a row per scored quantity (the first naming the regime,
/// its scene count and verdicts), or "(nothing scored)", then its coverage, median fit time
/// and terminations.
fn regime_rows(s: &mut String, r: &super::RegimeSummary) {
    use std::fmt::Write as _;
    let verdicts = counts(&r.verdicts);
    let mut first = true;
    for q in &r.quantities {
        let (reg, sc, ver) = if first {
            (
                r.regime.name().to_string(),
                r.scenes.to_string(),
                verdicts.clone(),
            )
        } else {
            (String::new(), String::new(), String::new())
        };
        first = false;
        let _ = writeln!(
            s,
            "{:<13} {:>6}  {:<18} {:<10} {:>3}  {:>12} {:>12}  {:>8}",
            reg,
            sc,
            ver,
            q.name,
            q.n,
            fmt_num(Some(q.median_rel_error)),
            fmt_num(Some(q.max_rel_error)),
            fmt_num(q.coverage)
        );
    }
    if first {
        let _ = writeln!(
            s,
            "{:<13} {:>6}  {:<18} (nothing scored)",
            r.regime.name(),
            r.scenes,
            verdicts
        );
    }
    let _ = writeln!(
        s,
        "{:<13} {:>6}  coverage {} ({} truths), median fit {} s, stops: {}",
        "",
        "",
        fmt_num(r.coverage),
        r.n_with_stderr,
        fmt_num(Some(r.median_seconds)),
        counts(&r.terminations)
    );
}
