//! The reports of one dataset's [`Outcome`]: the chosen fit's report, with the model
//! comparison when several candidates ran (`auto`), and in JSON the `replay` block that
//! `goniofit plot` redraws from. The CLI and the Python package both print these.

use super::{json, text, RunInfo};
use crate::fit::dataset::Outcome;
use crate::fit::driver::FitResult;
use serde_json::Value;

/// The outcome's report as one JSON object: [`json::to_json`] of the chosen fit, `replay`
/// (see [`replay_json`]) and, for several candidates, `comparison` (model, bic, aic, cost,
/// converged per candidate). `args` are the fit's command-line arguments (without the
/// program name) that `goniofit plot` parses again.
pub fn to_json(o: &Outcome, info: &RunInfo, args: &[String]) -> Value {
    let mut v = json::to_json(&o.result, info);
    v["replay"] = replay_json(&o.result, args);
    if o.candidates.len() > 1 {
        v["comparison"] = serde_json::json!(o
            .candidates
            .iter()
            .map(|r| serde_json::json!({"model": r.model, "bic": r.bic, "aic": r.aic, "cost": r.cost, "converged": r.converged()}))
            .collect::<Vec<_>>());
    }
    v
}

/// The outcome's report as text: the model comparison (lowest BIC wins) when several
/// candidates ran, then [`text::render`] of the chosen fit.
pub fn to_text(o: &Outcome, info: &RunInfo) -> String {
    let mut s = String::new();
    if o.candidates.len() > 1 {
        s += "[[Model comparison]] (lowest BIC wins)\n";
        for r in &o.candidates {
            s += &format!(
                "    {:<17} BIC = {:>14.4}  AIC = {:>14.4}  cost = {:.6e}{}\n",
                r.model,
                r.bic,
                r.aic,
                r.cost,
                if r.model == o.result.model {
                    "  <- chosen"
                } else {
                    ""
                }
            );
        }
    }
    s + &text::render(&o.result, info)
}

/// What `goniofit plot` needs to redraw a fit from its JSON report: the fit's command-line
/// arguments and the fitted values of every parameter (layout order).
pub fn replay_json(r: &FitResult, args: &[String]) -> Value {
    serde_json::json!({
        "args": args,
        "model": r.model,
        "names": r.layout.params.iter().map(|p| p.name.clone()).collect::<Vec<_>>(),
        "values": r.values,
        "n_free": r.n_free,
    })
}
