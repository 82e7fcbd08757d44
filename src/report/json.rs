//! The fit report as one JSON object.

use super::RunInfo;
use crate::fit::driver::FitResult;
use crate::fit::stats::profile::LEVELS;
use serde_json::{json, Map, Value};

/// The solver's termination as the report spells it (`ftol`, `degenerate`, …).
pub fn termination_name(t: crate::lm::Termination) -> String {
    format!("{t:?}").to_lowercase()
}

/// Finite numbers as numbers, the rest as null (JSON has no NaN).
fn num(v: f64) -> Value {
    if v.is_finite() {
        json!(v)
    } else {
        Value::Null
    }
}

/// The adequacy verdict, its headline, reasons and statistics (non-finite numbers as null).
fn adequacy_json(r: &FitResult) -> Value {
    let mut v = serde_json::to_value(&r.adequacy).unwrap_or(Value::Null);
    if let Value::Object(m) = &mut v {
        m.insert("headline".into(), json!(r.adequacy.headline()));
    }
    v
}

/// The report as a JSON value: the parameter and derived-quantity tables (with their
/// profile intervals), the correlation, the validity checks, the statistics and the run's
/// provenance, as one object.
pub fn to_json(r: &FitResult, info: &RunInfo) -> Value {
    let mut params = params_json(r, info);
    let mut derived = derived_json(r, info);
    attach_intervals(info, &mut params, &mut derived);
    json!({
        "model": r.model,
        "factors": r.factors.trim(),
        "start": start_json(r),
        "params": params,
        "derived": derived,
        "verdict": r.verdict,
        "notes": r.notes,
        "correlation": correlation_json(r),
        "singular_values": r.singular_values.iter().map(|v| num(*v)).collect::<Vec<_>>(),
        "condition": num(r.condition),
        "validity": validity_json(r),
        "adequacy": adequacy_json(r),
        "cost": num(r.cost),
        "loss": {"kind": r.loss.kind, "f_scale": num(r.loss.f_scale), "beyond_f_scale": r.beyond_f_scale},
        "chi2": num(r.chi2),
        "reduced_chi2": num(r.reduced_chi2),
        "rms": num(r.rms),
        "max_abs_residual": num(r.max_abs_residual),
        "r2": num(r.r2),
        "aic": num(r.aic),
        "bic": num(r.bic),
        "n": r.n,
        "n_free": r.n_free,
        "termination": termination_name(r.termination),
        "converged": r.converged(),
        "iterations": r.iterations,
        "evaluations": r.evaluations,
        "jacobian_evaluations": r.jacobian_evaluations,
        "seconds": r.seconds,
        "interval_seconds": info.interval_seconds,
        "init_seconds": r.init_seconds,
        "start_seconds": r.start_seconds,
        "start_from": if r.started_near { "neighbour" } else { "search" },
        "modes": r.modes,
        "fitted_computed": r.fitted_computed,
        "g_range": r.g_range.map(|(a, b)| vec![num(a), num(b)]),
        "input": info.input,
        "setting": info.setting,
        "command": info.command,
        "version": info.version,
    })
}

/// One entry per fitted parameter, keyed by its name: value, standard error (null when
/// unknown or non-finite), whether the data determine it, whether it was held fixed, and
/// its unit in the run's unit setting.
fn params_json(r: &FitResult, info: &RunInfo) -> Map<String, Value> {
    let units = &info.setting.units;
    let mut params = Map::new();
    for p in &r.params {
        params.insert(
            p.name.clone(),
            json!({
                "value": num(p.value),
                "stderr": p.stderr.map(num),
                "determined": p.determined,
                "fixed": p.fixed,
                "unit": units.of_param(&p.name),
            }),
        );
    }
    params
}

/// One entry per derived quantity, keyed by its name: value, standard error, whether it is
/// determined, its one-line description and its unit (which depends on whether the verdict
/// is a smooth surface).
fn derived_json(r: &FitResult, info: &RunInfo) -> Map<String, Value> {
    let units = &info.setting.units;
    let smooth = r.verdict == crate::fit::driver::Verdict::Smooth;
    let mut derived = Map::new();
    for d in &r.derived {
        derived.insert(
            d.name.clone(),
            json!({"value": num(d.value), "stderr": d.stderr.map(num), "determined": d.determined, "doc": d.doc, "unit": units.of_derived(&d.name, smooth)}),
        );
    }
    derived
}

/// Adds the profile intervals to the entries they belong to (a parameter's name first, else
/// a derived quantity's): `interval68` / `interval95` = `[lo, hi]`, null for an open side.
/// An interval whose name matches neither table, or whose level was not computed, adds
/// nothing.
fn attach_intervals(
    info: &RunInfo,
    params: &mut Map<String, Value>,
    derived: &mut Map<String, Value>,
) {
    for iv in &info.intervals {
        let target = if params.contains_key(&iv.name) {
            params.get_mut(&iv.name)
        } else {
            derived.get_mut(&iv.name)
        };
        if let Some(Value::Object(m)) = target {
            for (key, prob) in [("interval68", LEVELS[0]), ("interval95", LEVELS[1])] {
                if let Some(l) = iv.at(prob) {
                    m.insert(
                        key.into(),
                        json!([l.lo.value().map(num), l.hi.value().map(num)]),
                    );
                }
            }
        }
    }
}

/// The start point of the fit, parameter name → starting value.
fn start_json(r: &FitResult) -> Map<String, Value> {
    r.layout
        .params
        .iter()
        .zip(&r.start)
        .map(|(p, v)| (p.name.clone(), num(*v)))
        .collect()
}

/// The correlation matrix with its row/column names and the most correlated pairs
/// (the same pairs the text report lists), non-finite entries as null.
fn correlation_json(r: &FitResult) -> Value {
    let k = r.corr_names.len();
    let matrix: Vec<Vec<Value>> = (0..k)
        .map(|i| (0..k).map(|j| num(r.correlation[(i, j)])).collect())
        .collect();
    json!({
        "names": r.corr_names,
        "matrix": matrix,
        "largest": super::text::top_pairs(r, super::text::TOP_PAIRS)
            .into_iter()
            .map(|(a, b, rho)| json!({"a": a, "b": b, "rho": num(rho)}))
            .collect::<Vec<_>>(),
    })
}

/// The validity checks keyed by name (satisfied, value, limit, text), or null when the
/// fit ran none.
fn validity_json(r: &FitResult) -> Option<Map<String, Value>> {
    r.validity.as_ref().map(|v| {
        v.checks
            .iter()
            .map(|c| {
                (
                    c.name.to_string(),
                    json!({"satisfied": c.satisfied, "value": num(c.value), "limit": c.limit, "text": c.text}),
                )
            })
            .collect::<Map<String, Value>>()
    })
}
