//! The HTML page of a batch of fits (`fit --html` with `--by-group`, several files, or
//! `--channel all --by-group`): one self-contained page with the summary table (sortable
//! by clicking a column's header), the small-multiples overview, and one collapsible
//! section per fit holding that fit's report and pictures as the single-fit page shows
//! them ([`super::html::body`]).

use super::html::{escape, inline_svg, STYLE};
use super::outcome::Candidate;
use super::summary::{adequacy_cell, cell, verdict_word, Row};
use super::RunInfo;
use crate::fit::driver::FitResult;
use std::fmt::Write;

/// One fit's section: its result, run information, text report, model comparison (empty
/// for one model) and pictures as (name, SVG document).
pub(crate) struct FitSection<'a> {
    /// The fit of the section's dataset.
    pub result: &'a FitResult,
    /// How it was run: input, command, setting and profile intervals.
    pub info: &'a RunInfo,
    /// The fit's text report, as the single-fit page shows it.
    pub text: String,
    /// The candidates of a model comparison (empty when one model was fitted).
    pub comparison: Vec<Candidate<'a>>,
    /// The fit's pictures as (name, SVG document), inlined in order.
    pub pictures: Vec<(String, String)>,
}

/// What the batch page shows.
pub(crate) struct Batch<'a> {
    /// The command line that ran the batch.
    pub command: &'a str,
    /// One summary row per fit, in the order of `sections`.
    pub rows: &'a [Row],
    /// One section per fit, in the order of `rows`.
    pub sections: Vec<FitSection<'a>>,
    /// The overview's small charts as (title, SVG document), and what their x axis is.
    pub overview: Vec<(String, String)>,
    /// What the overview's x axis is, in words (the sentence "each quantity against …" names
    /// it).
    pub overview_x: String,
    /// The datasets a stop request kept from being fitted (with why).
    pub not_fitted: &'a [String],
}

/// Extra style of the batch page: a grid of small charts, the table's sortable headers.
const BATCH_STYLE: &str = "body{max-width:1500px}#summary{font-size:90%}.grid{display:grid;grid-template-columns:repeat(auto-fill,minmax(420px,1fr));gap:0.5em}\
.grid figure{margin:0}.grid svg{width:100%;height:auto}\
th.sort{cursor:pointer;user-select:none}th.sort:after{content:' \\2195';color:#999}\
details.fit{border:1px solid #ccc;border-radius:4px;padding:0.3em 0.8em;margin:0.4em 0}\
details.fit>summary{cursor:pointer;font-weight:bold}";

/// Sorts the summary table by the clicked header: numbers (each cell's `data-v`) by value,
/// else by text; a second click reverses.
const SORT_JS: &str = "document.querySelectorAll('table.sortable').forEach(function(t){\
var hs=t.querySelectorAll('th');hs.forEach(function(h,i){h.classList.add('sort');h.addEventListener('click',function(){\
var b=t.tBodies[0],rs=Array.from(b.rows),d=h.dataset.dir==='a'?-1:1;h.dataset.dir=d===1?'a':'d';\
rs.sort(function(x,y){var p=x.cells[i],q=y.cells[i],u=parseFloat(p.dataset.v),v=parseFloat(q.dataset.v);\
if(!isNaN(u)&&!isNaN(v))return d*(u-v);return d*p.textContent.localeCompare(q.textContent);});\
rs.forEach(function(r){b.appendChild(r);});});});});";

/// The batch page.
pub(crate) fn batch_page(b: &Batch) -> String {
    let mut s = String::new();
    let n = b.sections.len();
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>goniofit: {n} fits</title><style>{STYLE}{BATCH_STYLE}</style></head><body>"
    );
    let _ = writeln!(s, "<h1>goniofit: {n} fits</h1>");
    let converged = b.rows.iter().filter(|r| r.converged).count();
    let adequate = b.rows.iter().filter(|r| !r.adequacy.flagged()).count();
    let _ = writeln!(
        s,
        "<p id=\"counts\">{converged} of {n} converged; {adequate} of {n} adequate (no test finds the model at odds with the data).</p>"
    );
    if !b.not_fitted.is_empty() {
        s.push_str("<p class=no>Not fitted:</p><ul>\n");
        for f in b.not_fitted {
            let _ = writeln!(s, "<li>{}</li>", escape(f));
        }
        s.push_str("</ul>\n");
    }
    s.push_str("<h2>Reproduce</h2>\n");
    let _ = writeln!(s, "<pre id=\"command\">{}</pre>", escape(b.command));
    summary_table(&mut s, b.rows);
    overview(&mut s, b);
    s.push_str("<h2>Fits</h2>\n<p>Each fit's report and pictures; click to open.</p>\n");
    for (k, (sec, row)) in b.sections.iter().zip(b.rows).enumerate() {
        section(&mut s, k + 1, sec, row);
    }
    let _ = writeln!(s, "<script>{SORT_JS}</script>\n</body></html>");
    s
}

/// A table cell holding text `t` and, for sorting, the number `v` when finite.
fn td(t: &str, v: Option<f64>, class: &str) -> String {
    let data = v
        .filter(|v| v.is_finite())
        .map_or(String::new(), |v| format!(" data-v=\"{v:e}\""));
    let class = if class.is_empty() {
        String::new()
    } else {
        format!(" class=\"{class}\"")
    };
    format!("<td{class}{data}>{}</td>", escape(t))
}

/// The summary table: one row per fit, its first cell linking to the fit's section; the
/// σ, T and T/σ columns when some fit has them (a KBS model).
fn summary_table(s: &mut String, rows: &[Row]) {
    let unit = rows
        .first()
        .map_or(String::new(), |r| r.length_unit.clone());
    let kbs = rows
        .iter()
        .any(|r| r.sigma.is_some() || r.t.is_some() || r.ratio.is_some());
    s.push_str("<h2>Summary</h2>\n<p>Click a column's header to sort by it. Values in parentheses are not determined by the data.</p>\n<table id=\"summary\" class=\"sortable\">\n<thead><tr>");
    let mut headers: Vec<String> = ["#", "fit", "n", "converged", "termination", "adequacy"]
        .into_iter()
        .chain(["cost", "R²"])
        .map(String::from)
        .collect();
    if kbs {
        headers.extend([format!("σ ({unit})"), format!("T ({unit})"), "T/σ".into()]);
    }
    headers.push("verdict".into());
    for h in &headers {
        let _ = write!(s, "<th>{}</th>", escape(h));
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for (k, r) in rows.iter().enumerate() {
        let yes = |b: bool| if b { "yes" } else { "no" };
        let mut cells = vec![
            td(&(k + 1).to_string(), Some((k + 1) as f64), "num"),
            format!(
                "<td><a href=\"#fit-{}\">{}</a></td>",
                k + 1,
                escape(&r.group)
            ),
            td(&r.n.to_string(), Some(r.n as f64), "num"),
            td(yes(r.converged), None, yes(r.converged)),
            td(&r.termination, None, ""),
            td(&adequacy_cell(r), None, yes(!r.adequacy.flagged())),
            td(&format!("{:.5e}", r.cost), Some(r.cost), "num"),
            td(&super::text::fixed(r.r2, 6), Some(r.r2), "num"),
        ];
        if kbs {
            cells.extend([
                td(&cell(r.sigma), r.sigma.map(|v| v.0), "num"),
                td(&cell(r.t), r.t.map(|v| v.0), "num"),
                td(&cell(r.ratio), r.ratio.map(|v| v.0), "num"),
            ]);
        }
        cells.push(td(verdict_word(r.verdict), None, ""));
        let _ = writeln!(s, "<tr>{}</tr>", cells.concat());
    }
    s.push_str("</tbody></table>\n");
}

/// The small-multiples overview.
fn overview(s: &mut String, b: &Batch) {
    if b.overview.is_empty() {
        return;
    }
    let _ = writeln!(
        s,
        "<h2>Overview</h2>\n<p>Each quantity against {}; open circles: not determined by the data; fits that did not converge are not drawn.</p>\n<div class=\"grid\" id=\"overview\">",
        escape(&b.overview_x)
    );
    // The chart's own title names the quantity: no caption.
    for (title, svg) in &b.overview {
        let _ = writeln!(
            s,
            "<figure data-quantity=\"{}\">{}</figure>",
            escape(title),
            inline_svg(svg)
        );
    }
    s.push_str("</div>\n");
}

/// One fit's collapsible section: its summary line (row number, label, convergence,
/// adequacy, verdict) and the single-fit report one heading level down.
fn section(s: &mut String, k: usize, sec: &FitSection, row: &Row) {
    let _ = writeln!(
        s,
        "<details class=\"fit\" id=\"fit-{k}\"><summary>#{k} {} — {}, {}, {}</summary>",
        escape(&row.group),
        if row.converged {
            "converged"
        } else {
            "not converged"
        },
        escape(&adequacy_cell(row)),
        verdict_word(row.verdict)
    );
    let body = super::html::body(
        sec.result,
        sec.info,
        &sec.text,
        &sec.comparison,
        &sec.pictures,
    )
    .replace("<h2>", "<h3>")
    .replace("</h2>", "</h3>")
    // Ids are the page's own (the summary's links); a section's parts are classes.
    .replace(" id=\"", " data-part=\"");
    s.push_str(&body);
    s.push_str("</details>\n");
}
