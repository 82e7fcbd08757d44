//! The `fit` command's options (`goniofit fit --help`) and the fit [`Settings`] they ask for.

use super::args::{parse_patch, LossArg, ModeArg, QuantityArg};
use crate::fit::problem::ResidualKind;
use crate::geometry::Quantity;
use crate::io::FileSet;
use crate::model::parse_assignments;
use crate::settings::{Front, Settings};
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum ResidualArg {
    Absolute,
    Relative,
    Log,
}

impl From<ResidualArg> for ResidualKind {
    fn from(r: ResidualArg) -> Self {
        match r {
            ResidualArg::Absolute => ResidualKind::Absolute,
            ResidualArg::Relative => ResidualKind::Relative,
            ResidualArg::Log => ResidualKind::Log,
        }
    }
}

/// Options are named as the command line spells them.
pub(super) const CLI: Front = Front::Cli;

/// Examples shown by `goniofit fit --help`.
const FIT_EXAMPLES: &str = "\
Examples:
  goniofit fit --model kbs+lambert --channel 550nm --residual log data/cornell/garnet_red.astm
      one channel of a Cornell paint BRDF (λ = 550 nm from the channel name; σ, T in nm)
  goniofit fit --model kbs+lambert --channel all --residual log data/cornell/garnet_red.astm
      every channel jointly: shared σ, T, one scale per channel
  goniofit fit --model kbs+lambert --by-group --summary fits.csv data/cornell/garnet_red.astm
      every channel on its own, with a one-line-per-fit table
  goniofit fit --model lambert --channel 0.633 data/nist-ptfe/PTFE.data.csv
      the 633 nm rows of a CSV with a wavelength column (its unit, µm here)
  goniofit fit --model kbs --wavelength 633nm --json data/synthetic/kbs_hemisphere.csv > fit.json
      a CSV without a wavelength column; the report as JSON (goniofit plot fit.json redraws it)
  goniofit fit --model auto --wavelength 1 data/synthetic/kbs_hemisphere.csv
      compare lambert, lambert-specular, kbs and kbs+lambert by BIC";

#[derive(Debug, Args)]
#[command(after_help = FIT_EXAMPLES)]
pub(crate) struct FitArgs {
    /// Model: kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert, lambert-specular, or auto
    /// (fits lambert, lambert-specular, kbs, kbs+lambert and kbs+lambert with --fresnel
    /// dielectric --shadowing smith, and keeps the lowest BIC).
    #[arg(long, default_value = "kbs")]
    pub model: String,
    /// Whether the measured value is a radiance L (eq. 28) or a BRDF (L / cos θi). Default:
    /// what the file states (ASTM `MEAS_NAME BRDF`, NIST PTFE `f_r11`), else radiance. A
    /// reflectance factor is a BRDF × π.
    #[arg(long, value_enum)]
    pub quantity: Option<QuantityArg>,
    /// Wavelength, with its unit (633nm, 0.633um) or as a bare number (then σ and T are in
    /// that number's unknown unit); σ and T are reported in this unit. Required for KBS
    /// models unless a `wavelength` column or an ASTM channel name gives it.
    #[arg(long, allow_hyphen_values = true, value_parser = super::args::parse_wavelength)]
    pub wavelength: Option<super::args::Wavelength>,
    /// One channel: an ASTM channel (e.g. 550nm); for CSV a `group` label, or a wavelength
    /// (0.532 in the file's unit, or 532nm) selecting the rows of that wavelength. `all`: a
    /// joint fit over every channel (CSV without a group column: every wavelength) with
    /// shared σ, T and per-channel scales.
    #[arg(long)]
    pub channel: Option<String>,
    /// MERL tables: fit every K-th θd and φd cell (K² fewer samples; default all).
    #[arg(long, value_name = "K", default_value_t = 1, value_parser = clap::builder::RangedU64ValueParser::<usize>::new().range(1..=90))]
    pub subsample: usize,
    /// CSV angles are in radians (default degrees).
    #[arg(long)]
    pub radians: bool,
    /// In-plane CSV with signed θr: θr < 0 means the back side (φr = 180°).
    #[arg(long)]
    pub signed_theta_r: bool,
    /// Map column roles to other header names: theta_i=ti,L=brdf,...
    #[arg(long)]
    pub columns: Option<String>,
    /// Residual: absolute f − y, relative (f − y)/|y|, or log ln f − ln y (values below
    /// the floor are raised to it).
    #[arg(long, value_enum, default_value = "absolute")]
    pub residual: ResidualArg,
    /// Robust loss on the weighted residuals f = √w r (scipy's `least_squares` losses):
    /// the fit minimises ½ Σ C² ρ(f²/C²), C = --f-scale. Use it when a few samples are
    /// gross outliers (a saturated pixel, a stray reflection); see docs/conventions.md.
    #[arg(long, value_enum, default_value = "linear")]
    pub loss: LossArg,
    /// The loss scale C: residuals |f| well below C count as in least squares, beyond it
    /// as outliers (with --residual relative and no weights, 0.03 = 3 %). Finite, > 0.
    #[arg(long, default_value_t = 1.0)]
    pub f_scale: f64,
    /// Floor for relative/log residuals (default 1e-6 × max |L|).
    #[arg(long)]
    pub floor: Option<f64>,
    /// Starting values, name=value,... (overrides the automatic ones).
    #[arg(long)]
    pub init: Option<String>,
    /// Parameters held fixed, name=value,...
    #[arg(long)]
    pub fix: Option<String>,
    /// KBS evaluation: auto picks per sample the cheapest evaluation meeting --tol.
    #[arg(long, value_enum, default_value = "auto")]
    pub mode: ModeArg,
    /// Relative accuracy target of the KBS evaluation.
    #[arg(long, default_value = "1e-10")]
    pub tol: f64,
    /// Patch half-sizes X,Y (unit of λ): include the coherent term.
    #[arg(long)]
    pub patch: Option<String>,
    /// Fresnel and shadowing factors on the KBS lobe.
    #[command(flatten)]
    pub factors: super::args::FactorArgs,
    /// Do not reduce the fit when the data determines only parameter combinations.
    #[arg(long)]
    pub no_reduce: bool,
    /// Maximum solver iterations.
    #[arg(long, default_value_t = 500)]
    pub max_iter: u64,
    /// Stop the whole command after this many seconds of wall time (counted from its start:
    /// reading, fitting, writing); exit 3 with what exists (see docs/guide.md, "Stopping a fit").
    #[arg(long)]
    pub timeout: Option<f64>,
    /// Show progress on standard error (reading, datasets done of total with the time
    /// left, solver iterations). This is the default on a terminal; when standard error is
    /// not a terminal, a run longer than 2 s prints one line every 5 s instead.
    #[arg(long)]
    pub progress: bool,
    /// No progress display and no summary line on standard error.
    #[arg(long, conflicts_with = "progress")]
    pub quiet: bool,
    /// Standard errors and intervals from `sigma_L` as stated (a true standard
    /// uncertainty), not rescaled by the residual scatter (scipy's `absolute_sigma=True`).
    #[arg(long)]
    pub absolute_sigma: bool,
    /// Skip the profile-likelihood intervals (they refit the data a few dozen times per
    /// quantity).
    #[arg(long)]
    pub no_intervals: bool,
    /// Also write the report as one self-contained HTML page (tables, the pictures inline,
    /// the command that reproduces it). Several fits (`--by-group`, several files): one
    /// page with the sortable summary table, an overview, and a section per fit.
    #[arg(long)]
    pub html: Option<PathBuf>,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write the input rows with L_fit, residual, std_residual, mode.
    #[arg(long)]
    pub residuals: Option<PathBuf>,
    /// Write the fit's pictures (PNG and SVG) into this folder; several fits: one folder
    /// per fit inside it (numbered in the summary's order).
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Also write the one-line-per-fit summary (group, n, converged, cost, R², σ, T, T/σ,
    /// verdict) to this CSV file; `-` writes it to standard output in place of the text
    /// reports (a big batch's natural output).
    #[arg(long)]
    pub summary: Option<PathBuf>,
    /// Fit each group on its own: each ASTM channel, each label of a `group` column, or
    /// (CSV without one) each wavelength.
    #[arg(long)]
    pub by_group: bool,
    /// With several datasets (groups, files): start each fit at the optimum of the one
    /// before it in the input's order (a neighbouring texel of a spatially varying
    /// measurement), keeping it when it converges, leaves at most 4 times the fraction of
    /// the data its neighbour left unexplained and shows no runs of one sign the
    /// neighbour's did not; searching for the start as usual otherwise (always for a lobe
    /// with Fresnel or shadowing factors). Much faster on many similar small fits.
    #[arg(long)]
    pub warm_start: bool,
    /// Threads (default: all cores): datasets are fitted in parallel, and one dataset's
    /// evaluations are split over the threads.
    #[arg(long)]
    pub threads: Option<usize>,
    /// The measurement files (CSV or ASTM E1392); several files are fitted in parallel.
    #[arg(required = true, num_args = 1..)]
    pub file: Vec<PathBuf>,
}

impl FitArgs {
    /// The measurement files; the report on standard output, `--residuals`, `--html`,
    /// `--summary` and the pictures in the `--plot` folder.
    pub(crate) fn files(&self) -> FileSet {
        let mut set = FileSet::new();
        for f in &self.file {
            set = set.input("input", f);
        }
        set = set
            .stdout()
            .output_opt("--residuals", self.residuals.as_deref())
            .output_opt("--html", self.html.as_deref())
            .output_opt("--summary", self.summary.as_deref());
        match &self.plot {
            Some(dir) => set.pictures("--plot", dir, &crate::plot::fit::PICTURES),
            None => set,
        }
    }

    /// Whether progress is drawn: on a terminal unless `--quiet` (indicatif draws nothing
    /// when standard error is not a terminal, so `--progress` cannot force it there).
    pub(crate) fn show_progress(&self) -> bool {
        !self.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr())
    }

    /// What the fit is asked to do ([`Settings`]): every option but the outputs and the
    /// files, `--patch`, `--init` and `--fix` parsed; the values are checked by
    /// [`Settings::check`].
    pub(crate) fn settings(&self) -> anyhow::Result<Settings> {
        Ok(Settings {
            model: self.model.clone(),
            wavelength: self.wavelength.map(|w| w.0),
            wavelength_unit: self.wavelength.and_then(|w| w.1).map(String::from),
            quantity: self.quantity.map(Quantity::from),
            channel: self.channel.clone(),
            by_group: self.by_group,
            radians: self.radians,
            signed_theta_r: self.signed_theta_r,
            columns: self.columns.clone(),
            subsample: self.subsample,
            residual: self.residual.into(),
            loss: self.loss.into(),
            f_scale: self.f_scale,
            floor: self.floor,
            init: parse_assignments(self.init.as_deref().unwrap_or(""))?,
            fix: parse_assignments(self.fix.as_deref().unwrap_or(""))?,
            mode: self.mode.into(),
            tol: self.tol,
            patch: self.patch.as_deref().map(parse_patch).transpose()?,
            fresnel: self.factors.fresnel.into(),
            shadowing: self.factors.shadowing.into(),
            max_iter: self.max_iter,
            timeout: self.timeout,
            reduce: !self.no_reduce,
            absolute_sigma: self.absolute_sigma,
            intervals: self.no_intervals.then_some(false),
            warm_start: self.warm_start,
            threads: self.threads,
        })
    }
}

/// A `fit` command: its arguments (the files and outputs) and the fit's settings from them.
pub(crate) struct Command {
    /// The command's arguments: the files, the outputs and how progress is shown.
    pub args: FitArgs,
    /// What each fit is asked to do ([`FitArgs::settings`], checked).
    pub settings: Settings,
}
