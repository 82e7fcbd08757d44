//! The reports of a design ([`crate::design`]): text, JSON and the CSV of the proposed
//! geometries.

use crate::design::simulate::Simulation;
use crate::design::{percent, target_label, Design, Estimate, Scene};
use crate::plot::fmt_num;
use std::collections::BTreeMap;

/// A finished design with what it was planned for.
pub struct Run<'a> {
    /// The design: the chosen geometries and the estimates before and after.
    pub design: &'a Design,
    /// The model, parameters, wavelength and noise it was planned for.
    pub scene: &'a Scene<'a>,
    /// Where the measured geometries came from (a path, or `none`).
    pub source: &'a str,
    /// Fits of simulated measurements at the measured and proposed geometries.
    pub simulation: Option<&'a Simulation>,
    /// The same at the measured geometries alone (None without any).
    pub simulation_before: Option<&'a Simulation>,
}

/// The proposed geometries as CSV: a `theta_i,theta_r,phi_r` header and one row per
/// geometry, degrees, in the order chosen.
pub(crate) fn csv(d: &Design) -> String {
    let mut s = String::from("theta_i,theta_r,phi_r\n");
    for c in &d.chosen {
        s += &format!("{},{},{}\n", c[0], c[1], c[2]);
    }
    s
}

fn se_text(e: Option<&Estimate>) -> String {
    match e.and_then(|e| e.relative) {
        Some(r) if r <= 1.0 => percent(r),
        Some(_) => "> ±100 %".into(),
        None => "not determined".into(),
    }
}

fn noise_text(scene: &Scene) -> String {
    let kind = match scene.noise.kind {
        crate::fit::problem::ResidualKind::Absolute => "absolute (in the unit of L)",
        crate::fit::problem::ResidualKind::Relative => "relative (a fraction of L)",
        crate::fit::problem::ResidualKind::Log => "log (in ln L)",
    };
    format!("ε = {} per sample, {kind}", fmt_num(scene.noise.level))
}

fn model_text(scene: &Scene) -> String {
    let parts: Vec<String> = scene
        .model
        .params()
        .iter()
        .zip(&scene.params)
        .map(|(s, v)| format!("{}={}", s.name, fmt_num(*v)))
        .collect();
    format!("{} ({})", scene.model.name(), parts.join(", "))
}

fn unit(scene: &Scene) -> String {
    scene
        .unit
        .as_deref()
        .map_or_else(String::new, |u| format!(" {u}"))
}

/// The text report.
pub(crate) fn text(run: &Run) -> String {
    let (d, scene) = (run.design, run.scene);
    let reachable = d.candidates.iter().filter(|c| c.reachable).count();
    let mut s = format!("[[goniofit {}: design]]\n", env!("CARGO_PKG_VERSION"));
    let line = |s: &mut String, k: &str, v: String| *s += &format!("    {k:<12}= {v}\n");
    line(&mut s, "model", model_text(scene));
    line(
        &mut s,
        "wavelength",
        format!("{}{}", fmt_num(scene.wavelength), unit(scene)),
    );
    line(&mut s, "noise", noise_text(scene));
    line(
        &mut s,
        "measured",
        format!("{} geometries ({})", d.n_existing, run.source),
    );
    line(
        &mut s,
        "candidates",
        format!(
            "{} ({reachable} within the dynamic range)",
            d.candidates.len()
        ),
    );
    line(&mut s, "target", format!("{} ({})", d.target, d.criterion));
    s += &format!(
        "[[Proposed]] {} geometries (θi, θr, φr in degrees)\n",
        d.chosen.len()
    );
    for c in &d.chosen {
        s += &format!("    {:>6} {:>6} {:>6}\n", c[0], c[1], c[2]);
    }
    s += &estimates_table(run);
    for a in &d.alternatives {
        s += &format!(
            "    at {}{}: {} after {} geometries{}\n",
            fmt_num(a.wavelength),
            unit(scene),
            match a.target_after {
                Some(r) => percent(r),
                None => "not determined".into(),
            },
            a.chosen.len(),
            crate::design::where_(&a.chosen)
        );
    }
    s += "[[Next]]\n";
    s += &format!("    {}\n", d.sentence);
    s
}

/// The standard errors before and after (and simulated), one row per quantity.
fn estimates_table(run: &Run) -> String {
    let d = run.design;
    let mut s = String::from("[[Standard errors]] (relative; linearised");
    if let Some(sim) = run.simulation {
        s += &format!(
            "; simulated: the scatter of fits of {} simulated measurements, {} usable",
            sim.draws, sim.used
        );
    }
    s += ")\n";
    let sims = [run.simulation_before, run.simulation];
    let mut head = format!("    {:<20}{:>12}  {:>14}", "quantity", "value", "before");
    if sims[0].is_some() {
        head += &format!("  {:>14}", "sim. before");
    }
    head += &format!("  {:>14}", "after");
    if sims[1].is_some() {
        head += &format!("  {:>14}", "sim. after");
    }
    s += &head;
    s += "\n";
    let sim_of = |sim: &Simulation, name: &str| se_text(sim.spread.iter().find(|e| e.name == name));
    for (b, a) in d.before.iter().zip(&d.after) {
        let mark = if b.name.eq_ignore_ascii_case(&d.target) {
            " *"
        } else {
            ""
        };
        let label = format!("{}{mark}", target_label(&b.name));
        s += &format!(
            "    {label:<20}{:>12}  {:>14}",
            fmt_num(b.value),
            se_text(Some(b))
        );
        if let Some(sim) = sims[0] {
            s += &format!("  {:>14}", sim_of(sim, &b.name));
        }
        s += &format!("  {:>14}", se_text(Some(a)));
        if let Some(sim) = sims[1] {
            s += &format!("  {:>14}", sim_of(sim, &b.name));
        }
        s += "\n";
    }
    s
}

/// The JSON report: the setting, the proposed geometries, every quantity before and after
/// (and simulated), the target, the alternatives and the sentence. Standard errors that
/// do not exist are null.
pub fn json(run: &Run) -> serde_json::Value {
    let (d, scene) = (run.design, run.scene);
    let by_name = |v: &[Estimate]| -> BTreeMap<String, Estimate> {
        v.iter().map(|e| (e.name.clone(), e.clone())).collect()
    };
    let target_sim = |sim: Option<&Simulation>| {
        sim.filter(|_| !d.target.eq_ignore_ascii_case("all"))
            .and_then(|s| {
                s.spread
                    .iter()
                    .find(|e| e.name.eq_ignore_ascii_case(&d.target))
            })
            .and_then(|e| e.relative)
    };
    let sim_json = |s: &Simulation| {
        serde_json::json!({
            "draws": s.draws, "used": s.used, "failed": s.failed,
            "not_converged": s.not_converged, "spread": by_name(&s.spread),
        })
    };
    serde_json::json!({
        "version": env!("CARGO_PKG_VERSION"),
        "model": scene.model.name(),
        "params": scene.model.params().iter().zip(&scene.params)
            .map(|(s, v)| (s.name.to_string(), *v)).collect::<BTreeMap<_, _>>(),
        "wavelength": {"value": scene.wavelength, "unit": scene.unit},
        "noise": {"kind": scene.noise.kind, "level": scene.noise.level},
        "measured": {"count": d.n_existing, "source": run.source},
        "candidates": {
            "count": d.candidates.len(),
            "reachable": d.candidates.iter().filter(|c| c.reachable).count(),
        },
        "chosen": d.chosen.iter()
            .map(|c| serde_json::json!({"theta_i": c[0], "theta_r": c[1], "phi_r": c[2]}))
            .collect::<Vec<_>>(),
        "before": by_name(&d.before),
        "after": by_name(&d.after),
        "simulated": run.simulation.map(sim_json),
        "simulated_before": run.simulation_before.map(sim_json),
        "target": {
            "name": d.target,
            "criterion": d.criterion,
            "before": d.target_before,
            "after": d.target_after,
            "simulated": target_sim(run.simulation),
            "simulated_before": target_sim(run.simulation_before),
        },
        "alternatives": d.alternatives,
        "sentence": d.sentence,
    })
}
