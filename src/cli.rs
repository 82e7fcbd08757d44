//! Command-line definition (clap derive) and dispatch. Each subcommand's arguments live
//! beside its implementation in `commands/`.

use crate::commands::{
    self, bench, convert, design, eval, figures, fit, plot, recover, render, synth,
};
use clap::{Parser, Subcommand};
use goniofit::io::FileSet;

/// Fit physical light-scattering models (Kirchhoff–Beckmann–Spizzichino, Lambertian,
/// specular) to gonioreflectometer measurements.
#[derive(Debug, Parser)]
#[command(name = "goniofit", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
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
pub fn run(cli: Cli) -> anyhow::Result<u8> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use clap::CommandFactory;

    #[test]
    fn cli_definition_is_consistent() {
        Cli::command().debug_assert();
    }
}
