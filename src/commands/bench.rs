//! `goniofit bench`: benchmarks that print a table (criterion benches live in `benches/`).

use crate::harness::workprec::{self, WorkPrecisionConfig};
use crate::io::FileSet;
use anyhow::Context as _;
use clap::{Args, Subcommand};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct BenchArgs {
    #[command(subcommand)]
    pub command: BenchCommand,
}

#[derive(Debug, Subcommand)]
pub(crate) enum BenchCommand {
    /// Error against run time for the KBS evaluation modes (series at tol 1e-4 … 1e-14,
    /// smooth, rough, auto) and the solver settings (analytic vs finite-difference Jacobian,
    /// loose/default/tight tolerances).
    WorkPrecision(WorkPrecisionArgs),
}

#[derive(Debug, Args)]
#[command(after_help = "\
Eval rows: seconds = median time to evaluate the model on a 5x18x36 hemisphere in three \
regimes (smooth σ=0.02 T=1, intermediate σ=0.3 T=2, rough σ=3 T=20; λ=1); model_error = \
largest relative error against the series at tol 1e-15; param_error = largest relative error \
of σ, T, scale from a fit, in that mode, of noise-free reference data (4x12x24 hemisphere, \
σ=0.3, T=2, scale=1.5). Fit rows: the same fit in auto mode with each solver setting; \
seconds = median solver time.")]
pub(crate) struct WorkPrecisionArgs {
    /// Print `{"rows": [...]}` as JSON instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Timing repeats (the median is reported).
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Directory for the plot (work-precision.png and .svg).
    #[arg(long, default_value = "work-precision")]
    pub out: PathBuf,
}

impl BenchArgs {
    /// The plot in the `--out` folder, and the table on standard output.
    pub(crate) fn files(&self) -> FileSet {
        match &self.command {
            BenchCommand::WorkPrecision(a) => FileSet::new()
                .pictures("--out", &a.out, &[workprec::PLOT_STEM])
                .stdout(),
        }
    }
}

/// Run `goniofit bench ...`.
pub(crate) fn run(args: BenchArgs) -> anyhow::Result<u8> {
    match args.command {
        BenchCommand::WorkPrecision(a) => work_precision(a),
    }
}

fn work_precision(args: WorkPrecisionArgs) -> anyhow::Result<u8> {
    if args.repeats == 0 {
        return Err(crate::error::Error::Usage("--repeats must be at least 1".into()).into());
    }
    let bar = super::recover::progress_bar(workprec::steps() as u64, "work-precision");
    let wp = workprec::run(
        &WorkPrecisionConfig {
            repeats: args.repeats,
        },
        &|label| {
            bar.set_message(label.to_string());
            bar.inc(1);
        },
    )
    .context("work-precision benchmark")?;
    bar.finish_and_clear();
    let paths = workprec::write_plot(&wp, &args.out)
        .with_context(|| format!("writing the plot to {}", crate::io::shown(&args.out)))?;
    if args.json {
        crate::io::print_stdout(&format!("{}\n", serde_json::to_string_pretty(&wp)?))?;
    } else {
        crate::io::print_stdout(&wp.table())?;
    }
    for p in &paths {
        eprintln!("goniofit bench: wrote {}", crate::io::shown(p));
    }
    Ok(0)
}
