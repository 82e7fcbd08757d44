//! A fit report as an HTML fragment (tables of statistics, parameters, derived quantities
//! and the identifiability verdict), for notebooks: the Python package's `FitResult` shows
//! it as its rich display. Numbers are formatted as in the text report; every string from
//! the data is escaped.

use super::RunInfo;
use crate::fit::driver::FitResult;
use std::fmt::Write;

/// `s` with `& < > "` escaped for HTML text and attributes.
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            _ => out.push(c),
        }
    }
    out
}

/// `v ± se (rel %)` as the text report prints it, or `v` alone without a standard error.
fn value_se(v: f64, se: Option<f64>) -> String {
    match se {
        Some(se) if v != 0.0 => format!("{v:.7e} ± {se:.3e} ({:.2}%)", 100.0 * se / v.abs()),
        Some(se) => format!("{v:.7e} ± {se:.3e}"),
        None => format!("{v:.7e}"),
    }
}

/// The tag of a parameter the data does not determine.
const UNDETERMINED: &str = "not determined by the data";

/// A table with a header row and rows of cells (already escaped).
fn table(s: &mut String, header: [&str; 4], rows: impl Iterator<Item = [String; 4]>) {
    s.push_str("<table>\n<tr>");
    for h in header {
        let _ = write!(s, "<th>{h}</th>");
    }
    s.push_str("</tr>\n");
    for cells in rows {
        s.push_str("<tr>");
        for c in cells {
            let _ = write!(s, "<td style=\"text-align:left\">{c}</td>");
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</table>\n");
}

/// The report of `r` as an HTML fragment: a heading with the model and input, the fit
/// statistics, the parameters (value ± standard error, unit, whether the data determines
/// it), the derived quantities, the verdict and the notes.
pub fn fit_summary(r: &FitResult, info: &RunInfo) -> String {
    let mut s = String::from("<div class=\"goniofit-report\">\n");
    let _ = writeln!(
        s,
        "<p><b>goniofit fit</b>: model <code>{}</code>, {} samples, input {}</p>",
        escape(&r.model),
        r.n,
        escape(&info.input)
    );
    let termination = format!("{:?}", r.termination).to_lowercase();
    let _ = writeln!(
        s,
        "<p>{} — {} ({}); cost ½Σwr² = {:.7e}, reduced χ² = {:.7e}, R² = {:.7}</p>",
        if r.converged() {
            "converged"
        } else {
            "<b>not converged</b>"
        },
        escape(&termination),
        escape(r.termination.describe()),
        r.cost,
        r.reduced_chi2,
        r.r2
    );
    let params = r.params.iter().map(|p| {
        let tag = if p.fixed {
            "fixed"
        } else if p.determined {
            ""
        } else {
            UNDETERMINED
        };
        [
            p.name.as_str(),
            value_se(p.value, p.stderr).as_str(),
            p.unit.as_str(),
            tag,
        ]
        .map(escape)
    });
    table(&mut s, ["parameter", "value", "unit", ""], params);
    if !r.derived.is_empty() {
        let derived = r.derived.iter().map(|d| {
            let tag = if d.determined { "" } else { UNDETERMINED };
            [
                d.name.as_str(),
                value_se(d.value, d.stderr).as_str(),
                d.doc.as_str(),
                tag,
            ]
            .map(escape)
        });
        table(&mut s, ["derived", "value", "meaning", ""], derived);
    }
    let _ = writeln!(
        s,
        "<p>verdict: <b>{}</b></p>",
        escape(&format!("{:?}", r.verdict).to_lowercase())
    );
    if !r.notes.is_empty() {
        s.push_str("<ul>\n");
        for n in &r.notes {
            let _ = writeln!(s, "<li>{}</li>", escape(n));
        }
        s.push_str("</ul>\n");
    }
    s.push_str("</div>\n");
    s
}

#[cfg(test)]
mod tests {
    use super::escape;

    #[test]
    fn escapes_markup() {
        assert_eq!(escape("a<b & \"c\">"), "a&lt;b &amp; &quot;c&quot;&gt;");
    }
}
