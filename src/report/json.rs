//! The fit report as one JSON object.

use super::RunInfo;
use crate::fit::driver::FitResult;
use crate::fit::profile::LEVELS;
use serde_json::{json, Map, Value};

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

/// The report as a JSON value.
pub fn to_json(r: &FitResult, info: &RunInfo) -> Value {
    let units = &info.setting.units;
    let smooth = r.verdict == crate::fit::driver::Verdict::Smooth;
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
    let mut derived = Map::new();
    for d in &r.derived {
        derived.insert(
            d.name.clone(),
            json!({"value": num(d.value), "stderr": d.stderr.map(num), "determined": d.determined, "doc": d.doc, "unit": units.of_derived(&d.name, smooth)}),
        );
    }
    let k = r.corr_names.len();
    let correlation: Vec<Vec<Value>> = (0..k)
        .map(|i| (0..k).map(|j| num(r.correlation[(i, j)])).collect())
        .collect();
    let start: Map<String, Value> = r
        .layout
        .params
        .iter()
        .zip(&r.start)
        .map(|(p, v)| (p.name.clone(), num(*v)))
        .collect();
    // Profile intervals: params.<name>.interval68/interval95 = [lo, hi], null for an open
    // side.
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
    json!({
        "model": r.model,
        "factors": r.factors.trim(),
        "start": start,
        "params": params,
        "derived": derived,
        "verdict": r.verdict,
        "notes": r.notes,
        "correlation": {
            "names": r.corr_names,
            "matrix": correlation,
            "largest": super::text::top_pairs(r, super::text::TOP_PAIRS)
                .into_iter()
                .map(|(a, b, rho)| json!({"a": a, "b": b, "rho": num(rho)}))
                .collect::<Vec<_>>(),
        },
        "singular_values": r.singular_values.iter().map(|v| num(*v)).collect::<Vec<_>>(),
        "condition": num(r.condition),
        "validity": r.validity.as_ref().map(|v| {
            v.checks
                .iter()
                .map(|c| {
                    (
                        c.name.to_string(),
                        json!({"satisfied": c.satisfied, "value": num(c.value), "limit": c.limit, "text": c.text}),
                    )
                })
                .collect::<Map<String, Value>>()
        }),
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
        "termination": format!("{:?}", r.termination).to_lowercase(),
        "converged": r.converged(),
        "iterations": r.iterations,
        "evaluations": r.evaluations,
        "jacobian_evaluations": r.jacobian_evaluations,
        "seconds": r.seconds,
        "interval_seconds": info.interval_seconds,
        "init_seconds": r.init_seconds,
        "start_seconds": r.start_seconds,
        "modes": r.modes,
        "fitted_computed": r.fitted_computed,
        "g_range": r.g_range.map(|(a, b)| vec![num(a), num(b)]),
        "input": info.input,
        "setting": info.setting,
        "command": info.command,
        "version": info.version,
    })
}
