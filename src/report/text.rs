//! The plain-text fit report (lmfit-style), with the setting and units written out.

use super::setting::{Setting, Units};
use super::RunInfo;
use crate::fit::driver::{FitResult, Verdict};
use crate::plot::wrap;
use std::fmt::Write;

/// Correlation matrices with more rows than this are summarised by their largest pairs.
pub(crate) const FULL_MATRIX_MAX: usize = 8;

/// How many of the largest |ρ| pairs a summarised correlation matrix lists.
pub(crate) const TOP_PAIRS: usize = 10;

/// Format a value with its standard error and relative error.
fn value_se(v: f64, se: Option<f64>) -> String {
    match se {
        Some(se) if v != 0.0 => format!(
            "{:<14} +/- {:<11} ({:.2}%)",
            format!("{v:.7e}"),
            format!("{se:.3e}"),
            100.0 * se / v.abs()
        ),
        Some(se) => format!("{:<14} +/- {:<11}", format!("{v:.7e}"), format!("{se:.3e}")),
        None => format!("{:<14}", format!("{v:.7e}")),
    }
}

/// A number in scientific notation with 3 decimals; `n/a` for NaN (not computed).
fn sci(v: f64) -> String {
    if v.is_nan() {
        "n/a".into()
    } else {
        format!("{v:.3e}")
    }
}

/// The condition number of the Jacobian: `sci`, or in words for a singular
/// (rank-deficient) one, whose condition number is infinite.
pub(crate) fn condition_text(v: f64) -> String {
    if v.is_infinite() {
        "singular (rank-deficient Jacobian: the data does not determine every parameter)".into()
    } else {
        sci(v)
    }
}

/// `v` with 8 significant digits; "not computed" when it is not a finite number and the
/// fitted values it comes from were not `computed` (a stop request came first).
pub(crate) fn sci7(v: f64, computed: bool) -> String {
    if_computed(computed || v.is_finite(), || format!("{v:.7e}"))
}

/// `text()` when a figure was `computed`, else `NOT_COMPUTED`.
pub(crate) fn if_computed(computed: bool, text: impl FnOnce() -> String) -> String {
    if computed {
        text()
    } else {
        NOT_COMPUTED.to_string()
    }
}

/// A figure of the report that a stop request kept from being computed.
const NOT_COMPUTED: &str = "not computed (the fit was stopped first)";

/// A number printed with `digits` decimals, without a negative zero (R² of a fit no better
/// than the mean prints as 0.0000000, not −0.0000000). Non-finite values print as `n/a`.
pub(crate) fn fixed(v: f64, digits: usize) -> String {
    if !v.is_finite() {
        return "n/a".into();
    }
    if v.abs() >= 1e6 {
        // Never a 280-digit number (R² of a fit far worse than the mean).
        return format!("{v:.digits$e}");
    }
    let s = format!("{v:.digits$}");
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

/// The `[[Setting]]` lines: wavelength, quantity, residual and floor, weights, input.
fn setting_lines(s: &mut String, st: &Setting) {
    let _ = writeln!(s, "[[Setting]]");
    let wl = &st.wavelength;
    if !wl.values.is_empty() {
        let vals: Vec<String> = wl.values.iter().map(|v| format!("{v}")).collect();
        let vals = if vals.len() > 4 {
            let lo = wl.values.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = wl.values.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            format!("{lo} .. {hi} ({} values)", vals.len())
        } else {
            vals.join(", ")
        };
        let _ = writeln!(
            s,
            "    wavelength      = {} {} (from {}{}; σ, T in {})",
            vals,
            st.units.length_name(),
            if wl.source.starts_with("--") {
                ""
            } else {
                "the "
            },
            wl.source,
            st.units.length_name()
        );
    }
    if let Some(c) = &st.channel {
        let _ = writeln!(s, "    channel         = {c}");
    }
    let _ = writeln!(
        s,
        "    quantity        = {} ({}; values in {})",
        match st.quantity {
            crate::geometry::Quantity::Brdf => "brdf",
            crate::geometry::Quantity::Radiance => "radiance",
        },
        st.quantity_source,
        st.units.value_name()
    );
    let residual = format!("{:?}", st.residual).to_lowercase();
    if st.floor.used {
        let _ = writeln!(
            s,
            "    residual        = {residual} (floor {:.3e} {}: raised {} of the measured values)",
            st.floor.value,
            st.units.value_name(),
            st.floor.raised
        );
    } else {
        let _ = writeln!(s, "    residual        = {residual} (fitted − measured)");
    }
    let _ = writeln!(
        s,
        "    weights         = {}: {}",
        st.weights.source, st.weights.transform
    );
    if let (true, Some(c)) = (st.loss != "linear", st.f_scale) {
        let _ = writeln!(
            s,
            "    loss            = {} (f_scale C = {c:.4e}: minimises ½ΣC²ρ(wr²/C²), residuals |√w r| beyond C count as outliers)",
            st.loss
        );
    }
    if st.absolute_sigma {
        let _ = writeln!(
            s,
            "    uncertainties   = from sigma_L as stated (--absolute-sigma), not rescaled by the residual scatter"
        );
    }
    if !st.input.path.is_empty() {
        let _ = writeln!(
            s,
            "    input sha256    = {} ({} bytes; the absolute path is in --json)",
            st.input.sha256, st.input.bytes
        );
    }
}

/// A unit for the text report: a pure number shows no unit.
fn text_unit(unit: String) -> String {
    if unit == "1" {
        String::new()
    } else {
        unit
    }
}

/// The `[[Variables]]` and `[[Derived]]` blocks with units.
fn variable_lines(s: &mut String, r: &FitResult, units: &Units) {
    let _ = writeln!(s, "[[Variables]]");
    let width = r
        .params
        .iter()
        .map(|p| p.name.chars().count())
        .max()
        .unwrap_or(5)
        .max(5);
    for p in &r.params {
        let tag = if p.fixed {
            "(fixed)"
        } else if p.determined {
            ""
        } else if r.verdict == Verdict::NotComputed {
            "(standard error not computed: stopped)"
        } else {
            "(not determined by the data)"
        };
        let line = format!(
            "    {:<width$} = {:<40} {:<9} {}",
            p.name,
            value_se(p.value, p.stderr),
            text_unit(units.of_param(&p.name)),
            tag
        );
        let _ = writeln!(s, "{}", line.trim_end());
    }
    if !r.derived.is_empty() {
        let _ = writeln!(s, "[[Derived]]");
        let width = r
            .derived
            .iter()
            .map(|d| d.name.chars().count())
            .max()
            .unwrap_or(5);
        for d in &r.derived {
            let tag = if d.determined {
                ""
            } else if r.verdict == Verdict::NotComputed {
                "(standard error not computed: stopped) "
            } else {
                "(not determined by the data) "
            };
            let _ = writeln!(
                s,
                "    {:<width$} = {:<40} {:<9} {}# {}",
                d.name,
                value_se(d.value, d.stderr),
                text_unit(units.of_derived(&d.name, r.verdict == Verdict::Smooth)),
                tag,
                d.doc
            );
        }
    }
}

/// A number of an interval, 4 significant digits.
fn g4(v: f64) -> String {
    format!("{v:.4e}")
}

/// One interval as text: `[lo, hi]`, or a one-sided bound ("> lo") where a side is open.
pub(crate) fn interval_text(l: &crate::fit::stats::profile::Level) -> String {
    use crate::fit::stats::profile::Bound;
    match (l.lo, l.hi) {
        (Bound::Open(_), Bound::Open(_)) => "not bounded by the data".into(),
        (Bound::Edge(v), Bound::Open(_)) => {
            format!("≥ {} (its bound; no upper bound from the data)", g4(v))
        }
        (lo, Bound::Open(_)) => format!("> {}", g4(lo.value().unwrap_or(0.0))),
        (Bound::Open(_), hi) => format!("< {}", g4(hi.value().unwrap_or(0.0))),
        (lo, hi) => format!(
            "[{}, {}]",
            g4(lo.value().unwrap_or(0.0)),
            g4(hi.value().unwrap_or(0.0))
        ),
    }
}

/// The `[[Intervals]]` block: profile-likelihood intervals at 68.27 % and 95 %.
fn interval_lines(s: &mut String, r: &FitResult, info: &RunInfo) {
    if info.intervals.is_empty() {
        return;
    }
    let units = &info.setting.units;
    let _ = writeln!(
        s,
        "[[Intervals]] (profile likelihood, as lmfit's conf_interval; one-sided where χ² stays flat to a factor 1000 or up to the model's domain edge)"
    );
    if r.params.iter().any(|p| !p.determined && !p.fixed) {
        let _ = writeln!(
            s,
            "    note: for a parameter not determined by the data the interval is not an error bar: it is how far the data still bounds that parameter alone, the others refitted at each value"
        );
    }
    let width = info
        .intervals
        .iter()
        .map(|i| i.name.chars().count())
        .max()
        .unwrap_or(5);
    for iv in &info.intervals {
        let unit = if r.params.iter().any(|p| p.name == iv.name) {
            units.of_param(&iv.name)
        } else {
            units.of_derived(&iv.name, r.verdict == Verdict::Smooth)
        };
        let parts: Vec<String> = crate::fit::stats::profile::LEVELS
            .iter()
            .filter_map(|&p| iv.at(p))
            .map(|l| format!("{:.0}%: {}", l.prob * 100.0, interval_text(l)))
            .collect();
        let _ = writeln!(
            s,
            "    {:<width$}  {}  {}",
            iv.name,
            parts.join("   "),
            text_unit(unit)
        );
    }
}

/// The `[[Correlations]]` block: the matrix when small, its largest |ρ| pairs otherwise.
fn correlation_lines(s: &mut String, r: &FitResult) {
    let k = r.corr_names.len();
    if k <= 1 || r.verdict == Verdict::NotComputed {
        return;
    }
    if k > FULL_MATRIX_MAX {
        let _ = writeln!(
            s,
            "[[Correlations]] ({k} free parameters: the {TOP_PAIRS} largest |ρ|; the full matrix is in --json)"
        );
        for (a, b, rho) in top_pairs(r, TOP_PAIRS) {
            let _ = writeln!(s, "    {:>8}  {} ~ {}", fixed(rho, 4), a, b);
        }
        return;
    }
    let _ = writeln!(
        s,
        "[[Correlations]] (free parameters; sigma, T, w as their logarithms)"
    );
    let w = r
        .corr_names
        .iter()
        .map(|n| n.chars().count())
        .max()
        .unwrap_or(5)
        .max(8);
    let _ = write!(s, "    {:<w$}", "");
    for name in &r.corr_names {
        let _ = write!(s, " {:>w$}", name);
    }
    let _ = writeln!(s);
    for i in 0..k {
        let _ = write!(s, "    {:<w$}", r.corr_names[i]);
        for j in 0..k {
            let _ = write!(s, " {:>w$}", fixed(r.correlation[(i, j)], 4));
        }
        let _ = writeln!(s);
    }
}

/// The `n` off-diagonal correlations of largest magnitude (names, ρ), largest first.
pub(crate) fn top_pairs(r: &FitResult, n: usize) -> Vec<(String, String, f64)> {
    let k = r.corr_names.len();
    let mut pairs: Vec<(String, String, f64)> = Vec::new();
    for i in 0..k {
        for j in i + 1..k {
            let rho = r.correlation[(i, j)];
            if rho.is_finite() {
                pairs.push((r.corr_names[i].clone(), r.corr_names[j].clone(), rho));
            }
        }
    }
    pairs.sort_by(|a, b| b.2.abs().total_cmp(&a.2.abs()));
    pairs.truncate(n);
    pairs
}

/// The goodness-of-fit lines of [[Fit statistics]] after the cost: χ², rms, R², AIC, BIC,
/// the g range and the evaluation modes. Without the fitted values (a stop after the solve)
/// the figures they give say "not computed", never NaN.
fn goodness_lines(s: &mut String, r: &FitResult) {
    for (label, v) in [
        ("chi-square     ", r.chi2),
        ("reduced chi-sq ", r.reduced_chi2),
        ("rms residual   ", r.rms),
        ("max |residual| ", r.max_abs_residual),
    ] {
        let _ = writeln!(s, "    {label} = {}", sci7(v, r.fitted_computed));
    }
    let r2 = if_computed(r.fitted_computed, || fixed(r.r2, 7));
    let _ = writeln!(s, "    R-squared       = {r2}");
    let _ = writeln!(s, "    AIC             = {}", fixed(r.aic, 4));
    let _ = writeln!(s, "    BIC             = {}", fixed(r.bic, 4));
    if let Some((lo, hi)) = r.g_range {
        let _ = writeln!(s, "    g range         = {lo:.3e} .. {hi:.3e}");
    }
    let modes: Vec<String> = r.modes.iter().map(|(k, v)| format!("{k}: {v}")).collect();
    let modes = if_computed(r.fitted_computed, || modes.join(", "));
    let _ = writeln!(s, "    evaluation modes= {modes}");
}

/// The report as text.
pub(crate) fn render(r: &FitResult, info: &RunInfo) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "[[goniofit {}: fit report]]", info.version);
    let _ = writeln!(s, "    input           = {}", info.input);
    let _ = writeln!(s, "    command         = {}", info.command);
    let _ = writeln!(s, "    model           = {}{}", r.model, r.factors);
    setting_lines(&mut s, &info.setting);
    let _ = writeln!(s, "[[Fit statistics]]");
    let _ = writeln!(
        s,
        "    termination     = {} ({})",
        format!("{:?}", r.termination).to_lowercase(),
        r.termination.describe()
    );
    let _ = writeln!(s, "    converged       = {}", r.converged());
    adequacy_lines(&mut s, r);
    let _ = writeln!(s, "    samples         = {}", r.n);
    let _ = writeln!(s, "    free parameters = {}", r.n_free);
    let _ = writeln!(s, "    iterations      = {}", r.iterations);
    let _ = writeln!(
        s,
        "    evaluations     = {} (+{} Jacobians)",
        r.evaluations, r.jacobian_evaluations
    );
    run_time_lines(&mut s, r, info);
    if r.loss.is_linear() {
        let _ = writeln!(s, "    cost ½Σwr²      = {:.7e}", r.cost);
    } else {
        let _ = writeln!(
            s,
            "    cost ½ΣC²ρ      = {:.7e} ({} loss)",
            r.cost, r.loss.kind
        );
        if let Some(k) = r.beyond_f_scale {
            let _ = writeln!(
                s,
                "    beyond f_scale  = {k} of {} samples ({:.1} %: |√w r| > C, down-weighted as outliers)",
                r.n,
                100.0 * k as f64 / r.n.max(1) as f64
            );
        }
    }
    goodness_lines(&mut s, r);
    variable_lines(&mut s, r, &info.setting.units);
    interval_lines(&mut s, r, info);
    identifiability_lines(&mut s, r);
    validity_lines(&mut s, r);
    correlation_lines(&mut s, r);
    s
}

/// The fit's run time: from the start search (or the warm start) to the result, then the
/// profile intervals'.
fn run_time_lines(s: &mut String, r: &FitResult, info: &RunInfo) {
    if r.started_near {
        let _ = writeln!(
            s,
            "    run time        = {:.4} s (started at the previous dataset's optimum: --warm-start)",
            r.seconds
        );
    } else {
        let _ = writeln!(
            s,
            "    run time        = {:.4} s (grid search for starting values {:.4} s, their refinement {:.4} s)",
            r.seconds,
            r.start_seconds,
            r.init_seconds - r.start_seconds
        );
    }
    if !info.intervals.is_empty() {
        let _ = writeln!(
            s,
            "    run time        + {:.4} s for the profile intervals",
            info.interval_seconds
        );
    }
}

/// The `[[Identifiability]]` block: the verdict, the Jacobian's singular values and
/// condition, and the fit's notes.
fn identifiability_lines(s: &mut String, r: &FitResult) {
    let _ = writeln!(s, "[[Identifiability]]");
    let _ = writeln!(s, "    verdict         = {}", r.verdict.describe());
    let sv: Vec<String> = r.singular_values.iter().map(|v| sci(*v)).collect();
    let sv = if sv.len() > FULL_MATRIX_MAX {
        format!(
            "{} … {} ({} values; all in --json)",
            sv[..3].join(", "),
            sv[sv.len() - 3..].join(", "),
            sv.len()
        )
    } else {
        sv.join(", ")
    };
    let _ = writeln!(s, "    singular values = {sv}");
    let _ = writeln!(s, "    condition       = {}", condition_text(r.condition));
    for note in &r.notes {
        let _ = writeln!(s, "    note: {note}");
    }
}

/// The adequacy verdict beside `converged`, its reasons below it, wrapped.
fn adequacy_lines(s: &mut String, r: &FitResult) {
    let a = &r.adequacy;
    for (k, line) in wrap(&a.headline(), 80).iter().enumerate() {
        let lead = if k == 0 {
            "    adequacy        = "
        } else {
            "                      "
        };
        let _ = writeln!(s, "{lead}{line}");
    }
    for reason in &a.reasons {
        for (k, line) in wrap(&reason.text, 76).iter().enumerate() {
            let lead = if k == 0 { "- " } else { "  " };
            let _ = writeln!(s, "                      {lead}{line}");
        }
    }
}

/// The `[[Validity]]` lines of a KBS fit: each of the paper's assumptions at the fitted
/// surface, satisfied, violated or not determined (warnings, not failures).
fn validity_lines(s: &mut String, r: &FitResult) {
    let Some(v) = &r.validity else {
        return;
    };
    let _ = writeln!(
        s,
        "[[Validity]] (the paper's assumptions at the fitted surface; a warning, not a failure)"
    );
    for c in &v.checks {
        // One clause per line (the texts separate clauses by "; "), so that no line runs
        // past the width of a terminal.
        let mut clauses = c.text.split("; ");
        let first = clauses.next().unwrap_or_default();
        let _ = writeln!(s, "    {:<15} = {first}", c.name);
        for clause in clauses {
            let _ = writeln!(s, "{:22}{clause}", "");
        }
    }
}

#[cfg(test)]
mod tests {
    use super::{condition_text, fixed};

    #[test]
    fn a_singular_jacobian_s_condition_is_said_in_words() {
        let text = condition_text(f64::INFINITY);
        assert!(text.starts_with("singular (rank-deficient"), "{text}");
        assert!(!text
            .split(|c: char| !c.is_alphanumeric())
            .any(|w| w == "inf"));
        assert_eq!(condition_text(1234.5), "1.234e3");
        assert_eq!(condition_text(f64::NAN), "n/a");
    }

    #[test]
    fn no_negative_zero() {
        assert_eq!(fixed(-1e-12, 7), "0.0000000");
        assert_eq!(fixed(-0.5, 2), "-0.50");
        assert_eq!(fixed(f64::NAN, 2), "n/a");
        assert_eq!(fixed(-1.5e280, 7), "-1.5000000e280");
        assert_eq!(fixed(0.67525804, 7), "0.6752580");
    }
}
