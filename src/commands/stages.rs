//! The per-stage timing of `goniofit fit` for benchmarks: with the environment variable
//! `GONIOFIT_STAGES` set (to anything), the command writes one JSON line on standard error
//! after its outputs: the process's phases (reading, fitting, reports and outputs, in wall
//! seconds) and the median of each stage of one fit over the batch, in microseconds of
//! wall time on the thread that ran it (benches/stages.sh reads it). Without the variable
//! nothing is measured beyond the fit's own clocks and nothing is written.

use crate::fit::dataset::Outcome;
use crate::fit::driver::StageSeconds;

/// The environment variable that asks for the stage timing.
pub(crate) const VAR: &str = "GONIOFIT_STAGES";

/// Whether the stage timing was asked for.
pub(crate) fn wanted() -> bool {
    std::env::var_os(VAR).is_some()
}

/// One fit's stage times: its [`StageSeconds`], its intervals' and its whole dataset's
/// wall seconds.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Times {
    stages: StageSeconds,
    intervals: f64,
    dataset: f64,
}

impl Times {
    /// The stage times of `o`.
    pub(crate) fn of(o: &Outcome) -> Times {
        Times {
            stages: o.result.stage_seconds,
            intervals: o.interval_seconds,
            dataset: o.seconds,
        }
    }
}

/// Write the stage timing line (see the module doc): the process's phases `(read, fit,
/// report)` in wall seconds, and the median of each stage over the fits' `times`.
pub(crate) fn print((read, fit, report): (f64, f64, f64), times: &[Times]) {
    let us = |f: &dyn Fn(&Times) -> f64| {
        let mut v: Vec<f64> = times.iter().map(|t| 1e6 * f(t)).collect();
        (median(&mut v) * 10.0).round() / 10.0
    };
    let line = serde_json::json!({
        "fits": times.len(),
        "read_s": read,
        "fit_s": fit,
        "report_s": report,
        "median_us": {
            "grid": us(&|t| t.stages.grid),
            "refine": us(&|t| t.stages.refine),
            "solve": us(&|t| t.stages.solve),
            "uncertainty": us(&|t| t.stages.uncertainty),
            "assemble": us(&|t| t.stages.assemble),
            "intervals": us(&|t| t.intervals),
            "dataset": us(&|t| t.dataset),
        },
        "report_us_per_fit": (1e7 * report / times.len().max(1) as f64).round() / 10.0,
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
