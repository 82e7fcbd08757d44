//! The fit report as one self-contained HTML page (`fit --html report.html`): no network,
//! no external files. Tables for the setting, statistics, parameters with their intervals,
//! derived quantities and identifiability; the pictures inline as SVG (their bitmaps are
//! already embedded as base64 PNG); the command that reproduces the fit; the text report.

use super::text::interval_text;
use super::RunInfo;
use crate::fit::driver::{FitResult, Verdict};
use crate::fit::stats::profile::LEVELS;
use std::fmt::Write;

/// Text with `&`, `<`, `>`, `"` escaped for HTML.
pub(crate) fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// An SVG document as an inline element: the XML declaration and doctype dropped.
pub(crate) fn inline_svg(svg: &str) -> &str {
    svg.find("<svg").map_or(svg, |i| &svg[i..])
}

/// The pages' style sheet (tables, numbers, preformatted text, figures, yes/no colours),
/// inlined so that a page is self-contained.
pub(crate) const STYLE: &str = "body{font-family:sans-serif;max-width:1100px;margin:1em auto;padding:0 1em;color:#222}\
table{border-collapse:collapse;margin:0.5em 0 1em}td,th{border:1px solid #ccc;padding:2px 8px;text-align:left}\
th{background:#eee}td.num{font-family:monospace;text-align:right;white-space:nowrap}pre{background:#f6f6f6;padding:0.5em;overflow-x:auto}\
figure{margin:1em 0}figure svg{width:100%;max-width:1100px;height:auto}\
.no{color:#a00}.yes{color:#060}";

/// A two-column table of (key, value) rows.
fn kv_table(s: &mut String, rows: &[(&str, String)]) {
    s.push_str("<table>\n");
    for (k, v) in rows {
        let _ = writeln!(s, "<tr><th>{}</th><td>{}</td></tr>", escape(k), escape(v));
    }
    s.push_str("</table>\n");
}

/// The intervals of a quantity, `68%: … / 95%: …`, or empty.
fn intervals_of(info: &RunInfo, name: &str) -> (String, String) {
    let Some(iv) = info.intervals.iter().find(|i| i.name == name) else {
        return (String::new(), String::new());
    };
    let at = |p: f64| iv.at(p).map(interval_text).unwrap_or_default();
    (at(LEVELS[0]), at(LEVELS[1]))
}

/// The parameter and derived-quantity tables.
fn quantity_tables(s: &mut String, r: &FitResult, info: &RunInfo) {
    let units = &info.setting.units;
    s.push_str("<h2>Parameters</h2>\n<table>\n<tr><th>name</th><th>value</th><th>standard error</th><th>unit</th><th>determined</th><th>68.27 % interval</th><th>95 % interval</th></tr>\n");
    for p in &r.params {
        let (i68, i95) = intervals_of(info, &p.name);
        let det = if p.fixed {
            "fixed".to_string()
        } else if p.determined {
            "yes".into()
        } else if i68.is_empty() && i95.is_empty() {
            "no (no interval computed)".into()
        } else {
            "no: see the interval".into()
        };
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td class=num>{:.7e}</td><td class=num>{}</td><td>{}</td><td class={}>{}</td><td class=num>{}</td><td class=num>{}</td></tr>",
            escape(&p.name),
            p.value,
            p.stderr.map_or(String::new(), |e| format!("{e:.3e}")),
            escape(&units.of_param(&p.name)),
            if p.determined || p.fixed { "yes" } else { "no" },
            escape(&det),
            escape(&i68),
            escape(&i95)
        );
    }
    s.push_str("</table>\n");
    if r.derived.is_empty() {
        return;
    }
    s.push_str("<h2>Derived quantities</h2>\n<table>\n<tr><th>name</th><th>value</th><th>standard error</th><th>unit</th><th>68.27 % interval</th><th>95 % interval</th><th>meaning</th></tr>\n");
    for d in &r.derived {
        let (i68, i95) = intervals_of(info, &d.name);
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td class=num>{:.7e}</td><td class=num>{}</td><td>{}</td><td class=num>{}</td><td class=num>{}</td><td>{}</td></tr>",
            escape(&d.name),
            d.value,
            d.stderr.map_or(String::new(), |e| format!("{e:.3e}")),
            escape(&units.of_derived(&d.name, r.verdict == Verdict::Smooth)),
            escape(&i68),
            escape(&i95),
            escape(&d.doc)
        );
    }
    s.push_str("</table>\n");
}

/// The model comparison of `--model auto` (nothing for a single model): each candidate's
/// BIC, ΔBIC to the chosen fit, what became of its fit (converged, degenerate, not
/// converged: the last two not usable) and its part in the choice (chosen, tie).
fn comparison_table(s: &mut String, rows: &[super::outcome::Candidate]) {
    if rows.is_empty() {
        return;
    }
    s.push_str("<h2>Model comparison</h2>\n<p>The lowest BIC among the usable fits wins; ΔBIC &lt; 2 is a tie.</p>\n<table>\n<tr><th>model</th><th>BIC</th><th>ΔBIC</th><th>AIC</th><th>cost</th><th>fit</th><th>choice</th></tr>\n");
    for c in rows {
        let r = c.result;
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td class=num>{:.4}</td><td class=num>{:.2}</td><td class=num>{:.4}</td><td class=num>{:.6e}</td><td class={}>{}</td><td>{}</td></tr>",
            escape(&r.full_model()),
            r.bic,
            c.delta_bic,
            r.aic,
            r.cost,
            if r.converged() { "yes" } else { "no" },
            escape(&c.state()),
            c.role()
        );
    }
    s.push_str("</table>\n");
}

/// The page. `text` is the plain-text report; `comparison` the model comparison of
/// `--model auto` (empty for one model); `pictures` are (title, SVG document) pairs.
pub(crate) fn page(
    r: &FitResult,
    info: &RunInfo,
    text: &str,
    comparison: &[super::outcome::Candidate],
    pictures: &[(String, String)],
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>goniofit: {} on {}</title><style>{STYLE}</style></head><body>",
        escape(&r.full_model()),
        escape(&info.input)
    );
    let _ = writeln!(
        s,
        "<h1>goniofit fit report: {} on {}</h1>",
        escape(&r.full_model()),
        escape(&info.input)
    );
    s += &body(r, info, text, comparison, pictures);
    s.push_str("</body></html>\n");
    s
}

/// One fit's report under its title (headings `<h2>`): status, the command that
/// reproduces it, setting, model comparison, results, pictures (inline SVG with their
/// names as captions) and the text report folded away.
pub(crate) fn body(
    r: &FitResult,
    info: &RunInfo,
    text: &str,
    comparison: &[super::outcome::Candidate],
    pictures: &[(String, String)],
) -> String {
    let mut s = String::new();
    status(&mut s, r);
    s.push_str("<h2>Reproduce</h2>\n");
    let _ = writeln!(s, "<pre id=\"command\">{}</pre>", escape(&info.command));
    s.push_str("<h2>Setting</h2>\n");
    setting_table(&mut s, info);
    comparison_table(&mut s, comparison);
    results(&mut s, r, info);
    s.push_str("<h2>Pictures</h2>\n");
    for (title, svg) in pictures {
        let _ = writeln!(
            s,
            "<figure>{}<figcaption>{}</figcaption></figure>",
            inline_svg(svg),
            escape(title)
        );
    }
    s.push_str("<h2>Text report</h2>\n<details><summary>the report as printed</summary>\n");
    let _ = writeln!(s, "<pre>{}</pre></details>", escape(text));
    s
}

/// The report as an HTML fragment for a notebook's rich display (the Python package's
/// `FitResult._repr_html_`): the page's status line, the model comparison of `auto`
/// (`comparison`, nothing for one model), statistics, parameter and derived tables with
/// their intervals, verdict and notes, the key picture (`picture`: an SVG document, e.g.
/// the fit on a log scale) and the setting folded away; no page styles leak out (its
/// rules are scoped to the fragment).
pub fn fragment(
    r: &FitResult,
    info: &RunInfo,
    comparison: &[super::outcome::Candidate],
    picture: Option<&str>,
) -> String {
    let scoped = STYLE
        .split('}')
        .filter(|rule| !rule.is_empty() && !rule.starts_with("body"))
        .map(|rule| format!(".goniofit-report {rule}}}"))
        .collect::<String>();
    let mut s = format!("<div class=\"goniofit-report\"><style>{scoped}</style>\n");
    let _ = writeln!(
        s,
        "<h3>goniofit fit: {} on {}</h3>",
        escape(&r.full_model()),
        escape(&info.input)
    );
    status(&mut s, r);
    comparison_table(&mut s, comparison);
    results(&mut s, r, info);
    if let Some(svg) = picture {
        let _ = writeln!(s, "<figure>{}</figure>", inline_svg(svg));
    }
    s.push_str("<details><summary>Setting</summary>\n");
    setting_table(&mut s, info);
    s.push_str("</details></div>\n");
    s
}

/// Whether the fit converged, and its termination in words (said once: "Converged:
/// relative reduction of the cost below ftol").
fn status(s: &mut String, r: &FitResult) {
    let words = r.termination.describe();
    let words = words.strip_prefix("converged: ").unwrap_or(words);
    let _ = writeln!(
        s,
        "<p class={}>{}: {}</p>",
        if r.converged() { "yes" } else { "no" },
        if r.converged() {
            "Converged"
        } else {
            "Did not converge"
        },
        escape(words)
    );
    adequacy(s, r);
}

/// The adequacy verdict beside the convergence status, its reasons as a list.
fn adequacy(s: &mut String, r: &FitResult) {
    let a = &r.adequacy;
    let class = if a.verdict.flagged() { "no" } else { "yes" };
    let _ = writeln!(
        s,
        "<p id=\"adequacy\" class={class}>Adequacy: {}</p>",
        escape(&a.headline())
    );
    if !a.reasons.is_empty() {
        s.push_str("<ul id=\"adequacy-reasons\">\n");
        for reason in &a.reasons {
            let _ = writeln!(s, "<li>{}</li>", escape(&reason.text));
        }
        s.push_str("</ul>\n");
    }
}

/// The setting: input file and checksum, wavelength, quantity, residual, floor, weights,
/// loss, absolute sigma.
fn setting_table(s: &mut String, info: &RunInfo) {
    let st = &info.setting;
    let wl: Vec<String> = st.wavelength.values.iter().map(|v| v.to_string()).collect();
    kv_table(
        s,
        &[
            ("input file", st.input.path.clone()),
            ("sha256", st.input.sha256.clone()),
            (
                "wavelength",
                format!(
                    "{} {} (from {})",
                    wl.join(", "),
                    st.units.length_name(),
                    st.wavelength.source
                ),
            ),
            (
                "quantity",
                format!(
                    "{:?} ({}; values in {})",
                    st.quantity,
                    st.quantity_source,
                    st.units.value_name()
                )
                .to_lowercase(),
            ),
            (
                "residual",
                format!("{:?}, fitted − measured", st.residual).to_lowercase(),
            ),
            (
                "floor",
                if st.floor.used {
                    format!("{:.3e} (raised {} values)", st.floor.value, st.floor.raised)
                } else {
                    "not used".into()
                },
            ),
            (
                "weights",
                format!("{}: {}", st.weights.source, st.weights.transform),
            ),
            (
                "loss",
                match st.f_scale {
                    Some(c) => format!("{} (f_scale {c:.4e})", st.loss),
                    None => st.loss.clone(),
                },
            ),
            ("absolute sigma", st.absolute_sigma.to_string()),
        ],
    );
}

/// The fit statistics, the parameter and derived-quantity tables, and the identifiability
/// verdict with the notes and the condition number.
fn results(s: &mut String, r: &FitResult, info: &RunInfo) {
    s.push_str("<h2>Fit statistics</h2>\n");
    kv_table(
        s,
        &[
            ("samples", r.n.to_string()),
            ("free parameters", r.n_free.to_string()),
            ("cost ½Σwr²", format!("{:.7e}", r.cost)),
            (
                "reduced χ²",
                super::text::sci7(r.reduced_chi2, r.fitted_computed),
            ),
            (
                "R²",
                super::text::if_computed(r.fitted_computed, || super::text::fixed(r.r2, 7)),
            ),
            ("iterations", r.iterations.to_string()),
        ],
    );
    quantity_tables(s, r, info);
    s.push_str("<h2>Identifiability and validity</h2>\n");
    let _ = writeln!(
        s,
        "<p id=\"verdict\">{}</p>\n<ul>",
        escape(r.verdict.describe())
    );
    for n in &r.notes {
        let _ = writeln!(s, "<li>{}</li>", escape(n));
    }
    if !r.condition.is_nan() {
        let _ = writeln!(
            s,
            "</ul>\n<p>condition number {}</p>",
            super::text::condition_text(r.condition)
        );
    } else {
        let _ = writeln!(s, "</ul>");
    }
    validity(s, r);
}

/// The validity checks of a KBS fit (the paper's assumptions at the fitted surface) as a
/// table: check, satisfied / violated / not determined, and what was found.
fn validity(s: &mut String, r: &FitResult) {
    let Some(v) = &r.validity else {
        return;
    };
    s.push_str(
        "<p>The paper's assumptions at the fitted surface (a warning, not a failure):</p>\n\
         <table id=\"validity\">\n<tr><th>check</th><th>result</th><th>what was found</th></tr>\n",
    );
    for c in &v.checks {
        let (word, class) = match c.satisfied {
            Some(true) => ("satisfied", "yes"),
            Some(false) => ("violated", "no"),
            None => ("not determined", "no"),
        };
        let _ = writeln!(
            s,
            "<tr><td>{}</td><td class=\"{class}\">{word}</td><td>{}</td></tr>",
            escape(c.name),
            // The text opens with the result word, which the previous cell shows.
            escape(
                c.text
                    .split_once(": ")
                    .map_or(c.text.as_str(), |(_, found)| found)
            )
        );
    }
    s.push_str("</table>\n");
}
