//! `goniofit fit`: a measurement file in, a fit report out.

use super::args::{parse_patch, LossArg, ModeArg, QuantityArg};
use anyhow::Context;
use clap::{Args, ValueEnum};
use goniofit::fit::dataset::{batch, fit_dataset_near, DatasetFit, Outcome};
use goniofit::fit::driver::{FitConfig, FitInput};
use goniofit::fit::problem::loss::{Loss, LossKind};
use goniofit::fit::problem::ResidualKind;
use goniofit::geometry::Quantity;
use goniofit::io::{self, Dataset, FileSet, ReadOptions};
use goniofit::lm::{LmConfig, Stop};
use goniofit::model::parse_assignments;
use goniofit::report::outcome::SettingSource;
use goniofit::report::{self, RunInfo};
use goniofit::settings::{self, Front};
use goniofit::Error;
use std::path::{Path, PathBuf};

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
const CLI: Front = Front::Cli;

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
pub struct FitArgs {
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
    pub fn files(&self) -> FileSet {
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
            Some(dir) => set.pictures("--plot", dir, &goniofit::plot::fit::PICTURES),
            None => set,
        }
    }

    /// Whether progress is drawn: on a terminal unless `--quiet` (indicatif draws nothing
    /// when standard error is not a terminal, so `--progress` cannot force it there).
    pub fn show_progress(&self) -> bool {
        !self.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr())
    }

    /// How the input files are read (`--radians`, `--signed-theta-r`, `--columns`,
    /// `--channel`); values are required.
    pub fn read_options(&self) -> anyhow::Result<ReadOptions> {
        // --by-group needs every channel (ASTM) or every wavelength (CSV) read.
        let channel = match (&self.channel, self.by_group) {
            (None, true) => Some("all".to_string()),
            (c, _) => c.clone(),
        };
        Ok(ReadOptions {
            radians: self.radians,
            signed_theta_r: self.signed_theta_r,
            columns: io::csv::parse_columns(self.columns.as_deref().unwrap_or(""))?,
            require_value: true,
            channel,
            subsample: self.subsample,
        })
    }

    /// The measured quantity for a dataset and where it came from: `--quantity`, what the
    /// file states, or radiance by default.
    pub fn quantity_for(&self, ds: &Dataset) -> (Quantity, &'static str) {
        match (self.quantity, ds.quantity) {
            (Some(q), _) => (q.into(), "--quantity"),
            (None, Some(q)) => (q, "stated by the file"),
            (None, None) => (Quantity::Radiance, "default"),
        }
    }

    /// The wavelength given on the command line, as a number.
    pub fn wavelength_value(&self) -> Option<f64> {
        self.wavelength.map(|w| w.0)
    }
}

/// The whole setting of one dataset's fit, for the report (`report::Setting`).
pub fn setting_of(
    args: &FitArgs,
    ds: &Dataset,
    input: &FitInput,
    file: &report::setting::InputInfo,
) -> report::Setting {
    let (quantity, quantity_source) = args.quantity_for(ds);
    let unit = wavelength_unit(args, ds);
    let source = match (args.wavelength, &ds.wavelength) {
        (Some(_), _) => "--wavelength",
        (None, Some(_)) => ds.wavelength_origin.unwrap_or("wavelength column"),
        (None, None) => "none",
    };
    let source = SettingSource {
        file: file.clone(),
        channel: args.channel.clone(),
        quantity,
        quantity_source: quantity_source.into(),
        residual: args.residual.into(),
        floor: args.floor,
        wavelength_unit: unit,
        wavelength_source: source.into(),
        loss: LossKind::from(args.loss).name().into(),
        f_scale: (args.loss != LossArg::Linear).then_some(args.f_scale),
        absolute_sigma: args.absolute_sigma,
    };
    report::outcome::setting(ds, input, &source)
}

/// The input file's absolute path, size and SHA-256.
pub fn input_info(path: &Path) -> anyhow::Result<report::setting::InputInfo> {
    let io_error = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io_error)?;
    let (sha256, bytes) = report::checksum::sha256_hex_of(file).map_err(io_error)?;
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    Ok(report::setting::InputInfo {
        path: abs.display().to_string(),
        sha256,
        bytes,
    })
}

/// The fit configuration from the arguments, for a given model name; every numeric option
/// checked ([`goniofit::settings`], as the Python package checks its keywords).
pub fn fit_config(
    args: &FitArgs,
    model: &str,
    weights_are_uncertainties: bool,
) -> anyhow::Result<FitConfig> {
    let lm = LmConfig {
        max_iters: args.max_iter,
        timeout: settings::timeout(CLI, args.timeout)?,
        progress: args.show_progress(),
        ..FitConfig::default().lm
    };
    let patch = args.patch.as_deref().map(parse_patch).transpose()?;
    Ok(FitConfig {
        model: model.to_string(),
        model_opts: args.factors.apply(settings::model_options(
            CLI,
            args.mode.into(),
            args.tol,
            patch,
        )?),
        residual: args.residual.into(),
        loss: Loss::new(args.loss.into(), settings::f_scale(CLI, args.f_scale)?)?,
        floor: settings::floor(CLI, args.floor)?,
        init: parse_assignments(args.init.as_deref().unwrap_or(""))?,
        fix: parse_assignments(args.fix.as_deref().unwrap_or(""))?,
        lm,
        weights_are_uncertainties,
        reduce: !args.no_reduce,
    })
}

/// The command line as typed, for the report (control and bidi characters escaped).
fn command_line() -> String {
    std::env::args_os()
        .map(|a| io::shown_text(&a.to_string_lossy()).into_owned())
        .collect::<Vec<_>>()
        .join(" ")
}

/// The library's settings of a dataset's fit from the arguments, for dataset `ds` (its
/// quantity may come from the file). `single`: the only dataset of the command (progress
/// shown on a terminal, profile intervals unless `--no-intervals`).
fn dataset_fit(args: &FitArgs, ds: &Dataset, single: bool) -> anyhow::Result<DatasetFit> {
    let mut config = fit_config(args, &args.model, false)?;
    config.lm.progress = single && args.show_progress();
    Ok(DatasetFit {
        model: args.model.clone(),
        quantity: args.quantity_for(ds).0,
        wavelength: args.wavelength_value(),
        config,
        absolute_sigma: args.absolute_sigma,
        intervals: single && !args.no_intervals,
    })
}

/// The fit input of a dataset with the quantity, wavelength, residual and floor of `args`.
pub fn input_of(args: &FitArgs, ds: &Dataset, needs_wavelength: bool) -> anyhow::Result<FitInput> {
    Ok(dataset_fit(args, ds, false)?.input(ds, needs_wavelength)?)
}

/// Fit one dataset with every candidate model; keep the lowest BIC among the usable fits.
/// Every fit shares `stop` (the command's `--timeout` and signals); `near`: the fit of its
/// neighbour in the input (`--warm-start`), whose optima each candidate is first started at.
fn fit_one(
    args: &FitArgs,
    (label, ds): (String, Dataset),
    single: bool,
    stop: &Stop,
    near: Option<&Outcome>,
) -> anyhow::Result<Outcome> {
    let mut spec = dataset_fit(args, &ds, single)?;
    spec.config.lm.stop = Some(stop.clone());
    let context = format!("{label}: fitting model {}", args.model);
    fit_dataset_near(&spec, label, ds, near).context(context)
}

pub fn run(args: FitArgs) -> anyhow::Result<u8> {
    // Refused before any file is read.
    if args.json && summary_on_stdout(&args) {
        return Err(Error::Usage(
            "--json and --summary - both write standard output; give --summary a file".into(),
        )
        .into());
    }
    // From the start Ctrl-C, SIGTERM and SIGHUP stop the command instead of ending the
    // process, and `--timeout` counts from here: reading stops within a MiB (nothing
    // fitted, exit 3), a fit reports its best point (exit 3).
    let config = fit_config(&args, &args.model, false)?;
    let stop = Stop::new(config.lm.timeout, None);
    let (threads, note) = settings::threads(CLI, args.threads)?;
    if let Some(note) = note {
        eprintln!("goniofit: {note}");
    }
    let opts = args.read_options()?;
    let heartbeat = super::heartbeat::Heartbeat::start(!args.quiet);
    heartbeat.stage(format!("reading {}", io::shown(&args.file[0])));
    // Every input is read (and checked) before any fit starts.
    let t_read = std::time::Instant::now();
    let (jobs, files) = read_jobs(&args, &opts, &stop)?;
    let read = t_read.elapsed().as_secs_f64();
    let single = jobs.len() == 1;
    heartbeat.stage(match single {
        true => format!("fitting {} (model {})", jobs[0].0, args.model),
        false => format!("fitting {} datasets (model {})", jobs.len(), args.model),
    });
    if !single && args.residuals.is_some() {
        return Err(Error::Usage(
            "--residuals takes one dataset; fit several files or groups one at a time for it"
                .into(),
        )
        .into());
    }
    let t0 = std::time::Instant::now();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| anyhow::anyhow!("thread pool: {e}"))?;
    let (outcomes, skipped) = fit_jobs(&args, jobs, &stop, (&pool, &heartbeat))?;
    let wall = t0.elapsed().as_secs_f64();
    heartbeat.stage("writing the reports and outputs");
    // The reports' parts of a big batch are built on the fit's threads.
    use rayon::prelude::*;
    let infos: Vec<RunInfo> = pool.install(|| {
        outcomes
            .par_iter()
            .map(|o| run_info(&args, o, &files))
            .collect()
    });
    let threads = pool.current_num_threads();
    pool.install(|| print_reports(&args, &outcomes, &infos, &skipped, wall, threads))?;
    if single {
        super::fit_outputs::write_single_outputs(&args, &outcomes[0], &infos[0])?;
    } else {
        super::fit_outputs::write_batch_outputs(&args, &outcomes, &infos, &skipped)?;
    }
    if super::stages::wanted() {
        let report = t0.elapsed().as_secs_f64() - wall;
        super::stages::print(
            &super::stages::Phases {
                read,
                fit: wall,
                report,
            },
            &outcomes,
        );
    }
    let code = exit_code(&outcomes, &skipped, &stop);
    // The process ends with this command: its memory goes back to the system at once,
    // while freeing a big batch's results vector by vector is serial work at the end.
    std::mem::forget((outcomes, infos));
    Ok(code)
}

/// 0 when every fit converged with its uncertainties and intervals computed, nothing was
/// skipped and no signal came; else 3. A signal that came after the fits (while the
/// outputs were written) still says the run was interrupted: every output is complete, and
/// the exit code is 3.
fn exit_code(outcomes: &[Outcome], skipped: &[String], stop: &Stop) -> u8 {
    let interrupted = stop.requested() == Some(goniofit::lm::Termination::Interrupted);
    let all_usable = outcomes
        .iter()
        .all(|o| o.result.converged() && !o.intervals_stopped && o.result.fitted_computed);
    if all_usable && !interrupted && skipped.is_empty() {
        0
    } else {
        3
    }
}

/// Read every input file into the datasets to fit (one per file, or one per group with
/// `--by-group`), with each file's checksum and size.
#[allow(clippy::type_complexity)]
fn read_jobs(
    args: &FitArgs,
    opts: &ReadOptions,
    stop: &Stop,
) -> anyhow::Result<(
    Vec<(String, Dataset)>,
    Vec<(PathBuf, report::setting::InputInfo)>,
)> {
    let mut jobs: Vec<(String, Dataset)> = Vec::new();
    let mut files = Vec::new();
    for file in &args.file {
        // The raw rows are kept only for the residuals file (which passes them through).
        let bar = reading_bar(file, args.show_progress());
        // The file's checksum is taken on another thread while it is parsed.
        let (ds, info) = rayon::join(
            || {
                io::read_dataset_with(file, opts, args.residuals.is_some(), &|done| {
                    bar.set_position(done);
                    stop.requested().map_or(Ok(()), |why| Err(why.describe()))
                })
            },
            || input_info(file),
        );
        let ds = ds?;
        bar.finish_and_clear();
        goniofit::fit::dataset::check_magnitudes(&ds)?;
        files.push((file.clone(), info?));
        if !args.by_group {
            jobs.push((io::shown(file), ds));
            continue;
        }
        let groups = ds.channel_groups();
        if groups.is_empty() {
            return Err(Error::Usage(format!(
                "{}: --by-group needs groups: ASTM channels, a group column, or a wavelength column",
                io::shown(file)
            ))
            .into());
        }
        // Each group's dataset without the labels (the groups hold them).
        let mut ds = ds;
        ds.channel = None;
        let shown = io::shown(file);
        for (name, idx) in groups {
            let label = format!("{shown} [{}]", io::shown_text(&name));
            jobs.push((label, ds.subset(&idx)));
        }
    }
    Ok((jobs, files))
}

/// Fit every job in `pool` (one job: on the calling thread's pool with the fit's own
/// progress; several: in parallel, with a bar of datasets fitted), all sharing `stop`.
/// Returns the fits and the labels of the datasets a stop request kept from a result.
fn fit_jobs(
    args: &FitArgs,
    mut jobs: Vec<(String, Dataset)>,
    stop: &Stop,
    (pool, heartbeat): (&rayon::ThreadPool, &super::heartbeat::Heartbeat),
) -> anyhow::Result<(Vec<Outcome>, Vec<String>)> {
    if jobs.len() == 1 {
        let job = jobs.pop().expect("one job");
        let one = pool.install(|| fit_one(args, job, true, stop, None))?;
        return Ok((vec![one], Vec::new()));
    }
    let bar = if args.show_progress() {
        super::recover::progress_bar(jobs.len() as u64, "datasets fitted")
    } else {
        indicatif::ProgressBar::hidden()
    };
    heartbeat.count(jobs.len() as u64);
    let done: Vec<anyhow::Result<Outcome>> = pool.install(|| {
        batch::in_chains(jobs, args.warm_start, |(label, ds), previous| {
            // After a stop request no further dataset is started.
            if stop.is_requested() {
                return Err(not_fitted(&label, stop));
            }
            let near = previous.and_then(|r: &anyhow::Result<Outcome>| r.as_ref().ok());
            let outcome = fit_one(args, (label, ds), false, stop, near);
            bar.inc(1);
            heartbeat.inc();
            outcome
        })
    });
    bar.finish_and_clear();
    fitted_and_stopped(done)
}

/// The error of a dataset `label` a stop request kept from being fitted.
fn not_fitted(label: &str, stop: &Stop) -> anyhow::Error {
    let why = stop.requested().map_or("stopped", |t| t.describe());
    anyhow::Error::new(Error::Stopped(format!(
        "{label}: {why} before its fit started"
    )))
}

/// The fits of a batch, and the labels of the datasets a stop request kept from a result
/// ([`Error::Stopped`]: not started, or stopped before the first evaluation on the whole
/// data finished). Any other error ends the command.
fn fitted_and_stopped(
    outcomes: Vec<anyhow::Result<Outcome>>,
) -> anyhow::Result<(Vec<Outcome>, Vec<String>)> {
    let mut fitted = Vec::new();
    let mut skipped = Vec::new();
    for o in outcomes {
        match o {
            Ok(o) => fitted.push(o),
            Err(e) if super::is_stopped(&e) => skipped.push(format!("{e:#}")),
            Err(e) => return Err(e),
        }
    }
    Ok((fitted, skipped))
}

/// What a report says about the run besides the fit: input, command, setting, intervals.
fn run_info(
    args: &FitArgs,
    o: &Outcome,
    files: &[(PathBuf, report::setting::InputInfo)],
) -> RunInfo {
    let file = files
        .iter()
        .find(|(p, _)| *p == o.dataset.path)
        .map(|(_, i)| i.clone())
        .unwrap_or_default();
    RunInfo {
        input: o.label.clone(),
        command: command_line(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        setting: setting_of(args, &o.dataset, &o.input, &file),
        intervals: o.intervals.clone(),
        interval_seconds: o.interval_seconds,
    }
}

/// Print the reports (JSON or text, with the summary table after several fits or a joint
/// one), write `--summary`, and say on standard error how long several fits took.
fn print_reports(
    args: &FitArgs,
    outcomes: &[Outcome],
    infos: &[RunInfo],
    skipped: &[String],
    wall: f64,
    threads: usize,
) -> anyhow::Result<()> {
    // One dataset to fit (a batch with all but one not fitted is still a batch).
    let single = outcomes.len() == 1 && skipped.is_empty();
    use rayon::prelude::*;
    let rows: Vec<report::summary::Row> = outcomes
        .par_iter()
        .zip(infos)
        .map(|(o, i)| report::summary::row(&o.label, &o.result, &i.setting.units))
        .collect();
    if args.json && single {
        let v = report::outcome::to_json(&outcomes[0], &infos[0], &replay_args());
        io::print_stdout(&format!("{}\n", serde_json::to_string_pretty(&v)?))?;
    } else if args.json {
        let head = serde_json::json!({
            "fits": FITS_MARK,
            "datasets": outcomes.len(),
            "not_converged": rows.iter().filter(|r| !r.converged).count(),
            "not_fitted": skipped,
            "seconds": wall,
            "threads": threads,
            "summary": summary_json(&rows),
        });
        print_batch_json(&head, outcomes, infos)?;
    } else if summary_on_stdout(args) {
        // The summary rows are the standard output (written below).
    } else {
        // Each report written as it is rendered (a big batch never holds all its text).
        let joint = outcomes.iter().any(|o| o.input.channel_names.len() > 1);
        io::write_atomic(Path::new("-"), |w| {
            for (o, i) in outcomes.iter().zip(infos) {
                w.write_all(report::outcome::to_text(o, i).as_bytes())?;
            }
            if !single || joint {
                w.write_all(report::summary::table(&rows).as_bytes())?;
            }
            Ok(())
        })?;
    }
    if let Some(path) = &args.summary {
        io::write_csv(
            path,
            &report::summary::csv_header(),
            &report::summary::csv_rows(&rows),
        )?;
    }
    if !skipped.is_empty() {
        eprintln!(
            "goniofit: {} of {} datasets not fitted:\n  {}",
            skipped.len(),
            skipped.len() + outcomes.len(),
            skipped.join("\n  ")
        );
    }
    if !single && !args.quiet {
        let failed =
            report::summary::not_converged(&rows).map_or(String::new(), |t| format!("; {t}"));
        eprintln!(
            "goniofit: fitted {} datasets in {:.3} s ({:.1} datasets/s) on {} threads{failed}",
            outcomes.len(),
            wall,
            outcomes.len() as f64 / wall,
            threads
        );
    }
    Ok(())
}

/// Whether `--summary -` makes the summary CSV the standard output (in place of the text
/// reports: a big batch's natural output).
fn summary_on_stdout(args: &FitArgs) -> bool {
    args.summary.as_deref() == Some(Path::new("-"))
}

/// Stands for the batch report's `fits` array in [`print_batch_json`]'s head.
const FITS_MARK: &str = "\u{1}fits\u{1}";

/// The batch's JSON report on standard output, the bytes `serde_json::to_string_pretty`
/// gives of the whole object, written as it is produced: `head` (every key, with `fits`
/// standing for the array) around each fit's object serialised and written in turn, so
/// that a batch of many fits never holds its whole report in memory.
fn print_batch_json(
    head: &serde_json::Value,
    outcomes: &[Outcome],
    infos: &[RunInfo],
) -> anyhow::Result<()> {
    let text = serde_json::to_string_pretty(head)?;
    let mark = serde_json::to_string(FITS_MARK)?;
    let (before, after) = text
        .split_once(&mark)
        .ok_or_else(|| anyhow::anyhow!("the batch report's head has no fits"))?;
    let replay = replay_args();
    io::write_atomic(Path::new("-"), |w| {
        w.write_all(before.as_bytes())?;
        if outcomes.is_empty() {
            w.write_all(b"[]")?;
        }
        for (k, (o, i)) in outcomes.iter().zip(infos).enumerate() {
            let fit = report::outcome::to_json(o, i, &replay);
            let fit = serde_json::to_string_pretty(&fit).map_err(std::io::Error::other)?;
            // Two levels deeper than alone: JSON strings hold no raw line breaks.
            w.write_all(if k == 0 { b"[\n    " } else { b",\n    " })?;
            w.write_all(fit.replace('\n', "\n    ").as_bytes())?;
        }
        if !outcomes.is_empty() {
            w.write_all(b"\n  ]")?;
        }
        w.write_all(after.as_bytes())?;
        w.write_all(b"\n")
    })?;
    Ok(())
}

/// A bar of bytes read from `file` on standard error (hidden unless `show`).
fn reading_bar(file: &Path, show: bool) -> indicatif::ProgressBar {
    let len = std::fs::metadata(file).map(|m| m.len()).unwrap_or(0);
    if !show || len < READING_BAR_BYTES {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(super::recover::bar_style(
        "reading {msg} [{bar:30}] {bytes}/{total_bytes} {elapsed} (eta {eta})",
    ));
    bar.set_message(io::shown(file));
    bar
}

/// Files smaller than this are read without a bar (they take milliseconds).
const READING_BAR_BYTES: u64 = 4 << 20;

/// The summary rows as JSON objects (the CSV's columns).
fn summary_json(rows: &[report::summary::Row]) -> serde_json::Value {
    let csv = report::summary::csv_rows(rows);
    serde_json::Value::Array(
        csv.into_iter()
            .map(|r| {
                let m: serde_json::Map<String, serde_json::Value> = report::summary::csv_header()
                    .into_iter()
                    .zip(r)
                    .map(|(k, v)| (k, serde_json::Value::String(v)))
                    .collect();
                serde_json::Value::Object(m)
            })
            .collect(),
    )
}

/// The fit's command-line arguments (without the program name), for the JSON report's
/// `replay` block that `goniofit plot` parses again.
fn replay_args() -> Vec<String> {
    std::env::args_os()
        .skip(1)
        .map(|a| a.to_string_lossy().into_owned())
        .collect()
}

/// The unit of λ the fit's σ and T are in: `--wavelength`'s, else the file's.
pub fn wavelength_unit(args: &FitArgs, ds: &Dataset) -> Option<String> {
    match (args.wavelength, &ds.wavelength) {
        (Some((_, u)), _) => u.map(String::from),
        (None, Some(_)) => ds.wavelength_unit.clone(),
        (None, None) => None,
    }
}
