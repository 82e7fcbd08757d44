//! The command line: its definition (clap derive), dispatch, and exit codes ([`main`]). Each
//! subcommand's arguments live beside its implementation in `commands/`.

use crate::commands::{
    self, bench, convert, design, eval, figures, fit, plot, recover, render, synth,
};
use crate::io::FileSet;
use clap::{Parser, Subcommand};
use std::process::ExitCode;

/// Fit physical light-scattering models (Kirchhoff–Beckmann–Spizzichino, Lambertian,
/// specular) to gonioreflectometer measurements.
#[derive(Debug, Parser)]
#[command(name = "goniofit", version, about, long_about = None)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub(crate) enum Command {
    /// Evaluate a model at the angles of a CSV file; prints the rows with `L_model` appended.
    Eval(commands::eval::EvalArgs),
    /// Fit a model to a measurement file (CSV, ASTM E1392, RGL `.bsdf`, MERL `.binary`, ALTA
    /// data) and report parameters with uncertainties, what the data determines, and residual statistics.
    Fit(Box<commands::fit_args::FitArgs>),
    /// Write the samples `fit` would fit, from any format goniofit reads (CSV, ASTM E1392,
    /// RGL `.bsdf`, MERL `.binary`, ALTA data), as a CSV table: theta_i, theta_r, phi_r (degrees), L, the channel.
    Convert(commands::convert::ConvertArgs),
    /// Redraw a fit's pictures from its saved JSON report (`goniofit fit --json > fit.json`).
    Plot(commands::plot::PlotArgs),
    /// Generate synthetic measurements from known parameters, with seeded noise; writes the
    /// CSV and the truth beside it as JSON.
    Synth(Box<commands::synth::SynthArgs>),
    /// Propose the next geometries to measure: those that most reduce the predicted
    /// uncertainty of a target (σ, T, T/σ, … or every parameter), from a fit's report or a
    /// model with parameter values, with the standard errors before and after.
    Design(Box<commands::design::DesignArgs>),
    /// Synthetic recovery: draw scenes across regimes, fit each, and report the recovery
    /// error of what the data determines and the coverage of the reported uncertainties.
    Recover(Box<commands::recover::RecoverArgs>),
    /// Benchmarks with a table: `bench work-precision` (error against run time).
    Bench(Box<commands::bench::BenchArgs>),
    /// Render a picture from a model (a lit sphere).
    Render(commands::render::RenderArgs),
    /// Regenerate the paper's Figures 4–7 (PNG and SVG) into a folder.
    Figures(commands::figures::FiguresArgs),
}

impl Command {
    /// Every file the command reads and writes, with the option naming it.
    fn files(&self) -> anyhow::Result<FileSet> {
        Ok(match self {
            Command::Eval(a) => a.files(),
            Command::Fit(a) => a.files(),
            Command::Plot(a) => a.files(),
            Command::Synth(a) => a.files(),
            Command::Recover(_) => FileSet::new().stdout(),
            Command::Bench(a) => a.files(),
            Command::Convert(a) => a.files(),
            Command::Design(a) => a.files(),
            Command::Render(a) => a.files(),
            Command::Figures(a) => a.files(),
        })
    }
}

/// Run the parsed command line, once its files passed [`FileSet::check`] (no output is an
/// input or another output, every output path can be written): nothing is read or written
/// before.
fn run(cli: Cli) -> anyhow::Result<u8> {
    cli.command.files()?.check()?;
    match cli.command {
        Command::Eval(a) => eval::run(a),
        Command::Fit(a) => fit::run(*a),
        Command::Plot(a) => plot::run(a),
        Command::Synth(a) => synth::run(*a),
        Command::Recover(a) => recover::run(*a),
        Command::Bench(a) => bench::run(*a),
        Command::Convert(a) => convert::run(a),
        Command::Design(a) => design::run(*a),
        Command::Render(a) => render::run(a),
        Command::Figures(a) => figures::run(a),
    }
}

/// The command line: parse the process's arguments, run the subcommand, and map the outcome
/// to an exit code. Exit codes: 0 success, 1 internal failure, 2 bad usage or bad input, 3 a
/// fit that ran but did not converge or was stopped (its report is printed when it has a
/// point), 130 a signal while nothing was being computed.
pub fn main() -> ExitCode {
    commands::memory::return_big_buffers();
    // Ctrl-C, SIGTERM, SIGHUP: a running fit stops and reports (exit 3); anything else ends
    // with exit 130 and leaves no unfinished output file behind.
    commands::signals::install();
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    match run(cli) {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            // A stop with nothing to report is no error: it says what was stopped (exit 3).
            let kind = if commands::is_stopped(&e) {
                ""
            } else {
                "error: "
            };
            eprintln!("goniofit: {kind}{}", error_chain(&e));
            ExitCode::from(commands::exit_code_of(&e))
        }
    }
}

/// The error and its causes, joined by ": ", leaving out a cause whose text the message
/// already contains (errors that show their source in their own message).
fn error_chain(e: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if !out.contains(&text) {
            if !out.is_empty() {
                out.push_str(": ");
            }
            out.push_str(&text);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
