//! The plain-text fit report (lmfit-style).

use super::RunInfo;
use crate::fit::driver::{FitResult, Verdict};
use std::fmt::Write;

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

/// The report as text.
pub fn render(r: &FitResult, info: &RunInfo) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "[[goniofit {}: fit report]]", info.version);
    let _ = writeln!(s, "    input           = {}", info.input);
    let _ = writeln!(s, "    command         = {}", info.command);
    let _ = writeln!(s, "    model           = {}", r.model);
    let _ = writeln!(s, "[[Fit statistics]]");
    let _ = writeln!(
        s,
        "    termination     = {} ({})",
        format!("{:?}", r.termination).to_lowercase(),
        r.termination.describe()
    );
    let _ = writeln!(s, "    converged       = {}", r.converged());
    let _ = writeln!(s, "    samples         = {}", r.n);
    let _ = writeln!(s, "    free parameters = {}", r.n_free);
    let _ = writeln!(s, "    iterations      = {}", r.iterations);
    let _ = writeln!(
        s,
        "    evaluations     = {} (+{} Jacobians)",
        r.evaluations, r.jacobian_evaluations
    );
    let _ = writeln!(
        s,
        "    run time        = {:.4} s (grid search for starting values {:.4} s, their refinement {:.4} s)",
        r.seconds,
        r.start_seconds,
        r.init_seconds - r.start_seconds
    );
    let _ = writeln!(s, "    cost ½Σwr²      = {:.7e}", r.cost);
    let _ = writeln!(s, "    chi-square      = {:.7e}", r.chi2);
    let _ = writeln!(s, "    reduced chi-sq  = {:.7e}", r.reduced_chi2);
    let _ = writeln!(s, "    rms residual    = {:.7e}", r.rms);
    let _ = writeln!(s, "    max |residual|  = {:.7e}", r.max_abs_residual);
    let _ = writeln!(s, "    R-squared       = {}", r_squared_text(r.r2));
    let _ = writeln!(s, "    AIC             = {:.4}", r.aic);
    let _ = writeln!(s, "    BIC             = {:.4}", r.bic);
    if let Some((lo, hi)) = r.g_range {
        let _ = writeln!(s, "    g range         = {lo:.3e} .. {hi:.3e}");
    }
    let modes: Vec<String> = r.modes.iter().map(|(k, v)| format!("{k}: {v}")).collect();
    let _ = writeln!(s, "    evaluation modes= {}", modes.join(", "));
    let _ = writeln!(s, "[[Variables]]");
    let width = r
        .params
        .iter()
        .map(|p| p.name.len())
        .max()
        .unwrap_or(5)
        .max(5);
    for p in &r.params {
        let tag = if p.fixed {
            "(fixed)".to_string()
        } else if p.determined {
            String::new()
        } else {
            "(not determined by the data)".to_string()
        };
        let _ = writeln!(
            s,
            "    {:<width$} = {} {}",
            p.name,
            value_se(p.value, p.stderr),
            tag
        );
    }
    if !r.derived.is_empty() {
        let _ = writeln!(s, "[[Derived]]");
        let width = r.derived.iter().map(|d| d.name.len()).max().unwrap_or(5);
        for d in &r.derived {
            let tag = if d.determined {
                ""
            } else {
                "(not determined by the data)"
            };
            let _ = writeln!(
                s,
                "    {:<width$} = {} {} # {}",
                d.name,
                value_se(d.value, d.stderr),
                tag,
                d.doc
            );
        }
    }
    let _ = writeln!(s, "[[Identifiability]]");
    let _ = writeln!(
        s,
        "    verdict         = {}",
        match r.verdict {
            Verdict::Full => "every free parameter is determined",
            Verdict::Rough => "rough regime: only T/sigma and the amplitude are determined",
            Verdict::Smooth => "smooth regime: only T and the amplitude s*sigma^2 are determined",
            Verdict::Partial => "some parameter combinations are not determined",
        }
    );
    let sv: Vec<String> = r
        .singular_values
        .iter()
        .map(|v| format!("{v:.3e}"))
        .collect();
    let _ = writeln!(s, "    singular values = {}", sv.join(", "));
    let _ = writeln!(s, "    condition       = {:.3e}", r.condition);
    for note in &r.notes {
        let _ = writeln!(s, "    note: {note}");
    }
    let k = r.corr_names.len();
    if k > 1 {
        let _ = writeln!(
            s,
            "[[Correlations]] (free parameters; sigma, T, w as their logarithms)"
        );
        let w = r
            .corr_names
            .iter()
            .map(|n| n.len())
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
                // NaN where a standard error is 0 (an exact fit): undefined, not a number.
                let c = r.correlation[(i, j)];
                let c = if c.is_finite() {
                    format!("{c:.4}")
                } else {
                    "undef".into()
                };
                let _ = write!(s, " {c:>w$}");
            }
            let _ = writeln!(s);
        }
    }
    s
}

/// R² for the report: seven decimals where that is short (never `-0.0000000`: a value that
/// rounds to zero prints as `0.0000000`), scientific for |R²| ≥ 1e4 (a fit far worse than the
/// mean), and "undefined" when the data has no spread (NaN).
pub fn r_squared_text(r2: f64) -> String {
    if !r2.is_finite() {
        return "undefined (the data has no spread, or the fit is not finite)".into();
    }
    if r2.abs() >= 1e4 {
        return format!("{r2:.7e}");
    }
    let t = format!("{r2:.7}");
    if t.trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.')
    {
        "0.0000000".into()
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::r_squared_text;

    #[test]
    fn r_squared_is_short_and_never_minus_zero() {
        assert_eq!(r_squared_text(0.67525804), "0.6752580");
        assert_eq!(r_squared_text(-2e-9), "0.0000000");
        assert_eq!(r_squared_text(-0.5), "-0.5000000");
        assert_eq!(r_squared_text(-1.5e280), "-1.5000000e280");
        assert!(r_squared_text(f64::NAN).starts_with("undefined"));
    }
}
