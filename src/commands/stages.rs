//! The per-stage timing of `goniofit fit` for benchmarks: with the environment variable
//! `GONIOFIT_STAGES` set (to anything), the command writes one JSON line on standard error
//! after its outputs: the process's phases (reading, fitting, reports and outputs, in wall
//! seconds) and the median of each stage of one fit over the batch, in microseconds of
//! wall time on the thread that ran it (benches/stages.sh reads it). Without the variable
//! nothing is measured beyond the fit's own clocks and nothing is written.

use goniofit::fit::dataset::Outcome;

/// The environment variable that asks for the stage timing.
pub const VAR: &str = "GONIOFIT_STAGES";

/// Whether the stage timing was asked for.
pub fn wanted() -> bool {
    std::env::var_os(VAR).is_some()
}

/// The wall seconds of the process's phases.
pub struct Phases {
    pub read: f64,
    pub fit: f64,
    pub report: f64,
}

/// Write the stage timing line (see the module doc) for `outcomes`.
pub fn print(phases: &Phases, outcomes: &[Outcome]) {
    let us = |f: &dyn Fn(&Outcome) -> f64| {
        let mut v: Vec<f64> = outcomes.iter().map(|o| 1e6 * f(o)).collect();
        (median(&mut v) * 10.0).round() / 10.0
    };
    let s = |o: &Outcome| o.result.stage_seconds;
    let line = serde_json::json!({
        "fits": outcomes.len(),
        "read_s": phases.read,
        "fit_s": phases.fit,
        "report_s": phases.report,
        "median_us": {
            "grid": us(&|o| s(o).grid),
            "refine": us(&|o| s(o).refine),
            "solve": us(&|o| s(o).solve),
            "uncertainty": us(&|o| s(o).uncertainty),
            "assemble": us(&|o| s(o).assemble),
            "intervals": us(&|o| o.interval_seconds),
            "dataset": us(&|o| o.seconds),
        },
        "report_us_per_fit": (1e7 * phases.report / outcomes.len().max(1) as f64).round() / 10.0,
    });
    eprintln!("{line}");
}

/// The median of `v` (0 for none; NaN sorts last).
fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    let m = v.len() / 2;
    if v.len() % 2 == 1 {
        v[m]
    } else {
        0.5 * (v[m - 1] + v[m])
    }
}
