//! `goniofit fit`: a measurement file in, a fit report out.

use super::args::{parse_patch, LossArg, ModeArg, QuantityArg};
use anyhow::Context;
use clap::{Args, ValueEnum};
use goniofit::fit::driver::{self, FitConfig, FitInput, FitResult};
use goniofit::fit::lm::{LmConfig, Stop};
use goniofit::fit::loss::{Loss, LossKind};
use goniofit::fit::problem::ResidualKind;
use goniofit::fit::weights::{floor_raised, residual_weights};
use goniofit::geometry::{Geometry, Quantity};
use goniofit::io::{self, Dataset, ReadOptions};
use goniofit::model::{parse_assignments, ModelOptions};
use goniofit::report::{self, RunInfo};
use goniofit::Error;
use std::path::{Path, PathBuf};

/// Candidate models for `--model auto`, compared by BIC.
pub const AUTO_CANDIDATES: [&str; 4] = ["lambert", "lambert-specular", "kbs", "kbs+lambert"];

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
    /// (fits lambert, lambert-specular, kbs, kbs+lambert and keeps the lowest BIC).
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
    #[arg(long, value_parser = parse_wavelength_arg)]
    pub wavelength: Option<(f64, Option<&'static str>)>,
    /// One channel: an ASTM channel (e.g. 550nm); for CSV a `group` label, or a wavelength
    /// (0.532 in the file's unit, or 532nm) selecting the rows of that wavelength. `all`: a
    /// joint fit over every channel (CSV without a group column: every wavelength) with
    /// shared σ, T and per-channel scales.
    #[arg(long)]
    pub channel: Option<String>,
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
    /// Do not reduce the fit when the data determines only parameter combinations.
    #[arg(long)]
    pub no_reduce: bool,
    /// Maximum solver iterations.
    #[arg(long, default_value_t = 500)]
    pub max_iter: u64,
    /// Stop the solver after this many seconds.
    #[arg(long)]
    pub timeout: Option<f64>,
    /// Show progress on standard error (reading, datasets done of total, solver
    /// iterations). This is the default on a terminal; piped, nothing is drawn.
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
    /// the command that reproduces it); one dataset only.
    #[arg(long)]
    pub html: Option<PathBuf>,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write the input rows with L_fit, residual, std_residual, mode.
    #[arg(long)]
    pub residuals: Option<PathBuf>,
    /// Write the fit's pictures (PNG and SVG) into this folder.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Also write the one-line-per-fit summary (group, n, converged, cost, R², σ, T, T/σ,
    /// verdict) to this CSV file.
    #[arg(long)]
    pub summary: Option<PathBuf>,
    /// Fit each group on its own: each ASTM channel, each label of a `group` column, or
    /// (CSV without one) each wavelength.
    #[arg(long)]
    pub by_group: bool,
    /// Threads (default: all cores): datasets are fitted in parallel, and one dataset's
    /// evaluations are split over the threads.
    #[arg(long)]
    pub threads: Option<usize>,
    /// The measurement files (CSV or ASTM E1392); several files are fitted in parallel.
    #[arg(required = true, num_args = 1..)]
    pub file: Vec<PathBuf>,
}

impl FitArgs {
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

/// The largest |L|·√w, |L| and w (and the smallest w) a fit accepts: the cost ½Σw r² and
/// the Jacobian products square these, so beyond them double precision overflows (cost
/// = inf, R² = NaN). The fit is the same in any unit of L (amplitudes scale with it) and
/// under any common factor of the weights, so rescaling the file loses nothing.
pub const MAGNITUDE_LIMIT: f64 = 1e100;

/// Refuse values and weights the fit cannot square in double precision (see
/// [`MAGNITUDE_LIMIT`]), naming the file, line and column of the first one.
pub fn check_magnitudes(ds: &Dataset) -> anyhow::Result<()> {
    let Some(y) = &ds.value else { return Ok(()) };
    let column = |i: usize, what: &str| match &ds.channel {
        Some(ch) if ds.headers.iter().any(|h| h == "channel") => ch[i].clone(),
        _ => what.to_string(),
    };
    let lim = MAGNITUDE_LIMIT;
    for (i, &v) in y.iter().enumerate() {
        let w = ds.weight.as_ref().map_or(1.0, |w| w[i]);
        let (col, msg) = if v.abs() > lim {
            (
                column(i, "L"),
                format!(
                    "value {} is beyond ±{lim:e}: the fit squares values (cost ½Σw r²) and would overflow double precision; express L in another unit (the fit is the same in any unit of L)",
                    goniofit::model::domain::short_number(v)
                ),
            )
        } else if !(1.0 / lim..=lim).contains(&w) || v.abs() * w.sqrt() > lim {
            let col = if ds.sigma_l.is_some() {
                "sigma_L"
            } else {
                "weight"
            };
            (
                col.to_string(),
                format!(
                    "weight {} (with L = {}) is outside what the fit can square (weights in [{:e}, {lim:e}], |L|·√w ≤ {lim:e}); scale every weight or uncertainty by one factor (the fitted parameters do not change)",
                    goniofit::model::domain::short_number(w),
                    goniofit::model::domain::short_number(v),
                    1.0 / lim
                ),
            )
        } else {
            continue;
        };
        return Err(Error::input(&ds.path, ds.lines[i], &col, msg).into());
    }
    Ok(())
}

/// `--wavelength`: a positive number with an optional unit (nm, um, µm).
fn parse_wavelength_arg(text: &str) -> Result<(f64, Option<&'static str>), String> {
    io::parse_length(text).map_err(|e| e.to_string())
}

/// The fit's data from a dataset: geometry, values, channels, and the weights transformed
/// for the residual kind (`goniofit::fit::weights`).
pub fn fit_input(
    ds: &Dataset,
    quantity: Quantity,
    wavelength: Option<f64>,
    needs_wavelength: bool,
    residual: ResidualKind,
    floor: Option<f64>,
) -> anyhow::Result<FitInput> {
    check_magnitudes(ds)?;
    let n = ds.samples.len();
    let lambda: Vec<f64> = match (&ds.wavelength, wavelength) {
        (_, Some(l)) => vec![l],
        (Some(w), None) => w.clone(),
        (None, None) if needs_wavelength => {
            return Err(Error::Usage(format!(
                "{}: KBS models need a wavelength: give --wavelength, a wavelength column, or an ASTM channel such as 550nm",
                goniofit::io::shown(&ds.path)
            ))
            .into())
        }
        (None, None) => vec![1.0],
    };
    let geo = Geometry::new(&ds.samples, &lambda, quantity)?;
    let y = ds.value.clone().ok_or_else(|| Error::File {
        path: ds.path.clone(),
        message: "no measured value column (L)".into(),
    })?;
    let floor = floor_for(floor, &y);
    let (weight, _) = residual_weights(
        ds.weight.as_deref().filter(|_| ds.sigma_l.is_none()),
        ds.sigma_l.as_deref(),
        &y,
        residual,
        floor,
    );
    let (channel, channel_names) = match &ds.channel {
        Some(labels) => {
            let mut names: Vec<String> = Vec::new();
            let idx = labels
                .iter()
                .map(|l| match names.iter().position(|x| x == l) {
                    Some(i) => i,
                    None => {
                        names.push(l.clone());
                        names.len() - 1
                    }
                })
                .collect();
            // Names as printed (reports, parameter names): control and bidi characters escaped.
            let names = names
                .iter()
                .map(|n| io::shown_text(n).into_owned())
                .collect();
            (idx, names)
        }
        None => (vec![0; n], vec![String::new()]),
    };
    Ok(FitInput {
        geo,
        y,
        weight,
        channel,
        channel_names,
    })
}

/// The residual floor: `--floor`, or 1e-6 × max |y| (as the fit computes it).
fn floor_for(floor: Option<f64>, y: &[f64]) -> f64 {
    driver::residual_floor(
        &FitConfig {
            floor,
            ..FitConfig::default()
        },
        y,
    )
}

/// The whole setting of one dataset's fit, for the report (`report::Setting`).
pub fn setting_of(
    args: &FitArgs,
    ds: &Dataset,
    input: &FitInput,
    file: &report::setting::InputInfo,
) -> report::Setting {
    let (quantity, quantity_source) = args.quantity_for(ds);
    let residual: ResidualKind = args.residual.into();
    let floor = floor_for(args.floor, &input.y);
    let (_, weights) = residual_weights(
        ds.weight.as_deref().filter(|_| ds.sigma_l.is_none()),
        ds.sigma_l.as_deref(),
        &input.y,
        residual,
        floor,
    );
    let (unit, source) = match (args.wavelength, &ds.wavelength) {
        (Some((_, u)), _) => (u.map(String::from), "--wavelength"),
        (None, Some(_)) if io::is_astm(&ds.path, "") => {
            (ds.wavelength_unit.clone(), "channel name")
        }
        (None, Some(_)) => (ds.wavelength_unit.clone(), "wavelength column"),
        (None, None) => (None, "none"),
    };
    let mut values: Vec<f64> = Vec::new();
    if source != "none" {
        for &l in &input.geo.wavelength {
            if !values.contains(&l) {
                values.push(l);
            }
        }
    }
    report::Setting {
        input: file.clone(),
        wavelength: report::setting::WavelengthInfo {
            values,
            unit: unit.clone(),
            source: source.into(),
        },
        channel: args.channel.clone(),
        quantity,
        quantity_source: quantity_source.into(),
        residual,
        floor: report::setting::FloorInfo {
            value: floor,
            raised: floor_raised(&input.y, residual, floor),
            used: residual != ResidualKind::Absolute,
        },
        weights,
        loss: LossKind::from(args.loss).name().into(),
        f_scale: (args.loss != LossArg::Linear).then_some(args.f_scale),
        absolute_sigma: args.absolute_sigma,
        units: report::Units {
            length: unit,
            quantity,
            radiance: None,
        },
    }
}

/// The input file's absolute path, size and SHA-256.
pub fn input_info(path: &Path) -> anyhow::Result<report::setting::InputInfo> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let abs = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    Ok(report::setting::InputInfo {
        path: abs.display().to_string(),
        sha256: report::checksum::sha256_hex(&bytes),
        bytes: bytes.len() as u64,
    })
}

/// The fit configuration from the arguments, for a given model name.
pub fn fit_config(
    args: &FitArgs,
    model: &str,
    weights_are_uncertainties: bool,
) -> anyhow::Result<FitConfig> {
    let lm = LmConfig {
        max_iters: args.max_iter,
        timeout: args.timeout.map(std::time::Duration::from_secs_f64),
        progress: args.show_progress(),
        ..FitConfig::default().lm
    };
    Ok(FitConfig {
        model: model.to_string(),
        model_opts: ModelOptions {
            mode: args.mode.into(),
            tol: args.tol,
            patch: args.patch.as_deref().map(parse_patch).transpose()?,
        },
        residual: args.residual.into(),
        loss: Loss::new(args.loss.into(), args.f_scale)
            .map_err(|_| {
                Error::Usage(format!(
                    "--f-scale {}: the loss scale must be a finite number > 0, the size of a weighted residual beyond which a sample counts as an outlier (e.g. 0.03 for 3 % with --residual relative)",
                    args.f_scale
                ))
            })?,
        floor: args.floor,
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

/// One dataset's fit: every candidate model, and the chosen one (lowest BIC).
pub struct Outcome {
    pub label: String,
    pub dataset: Dataset,
    pub input: FitInput,
    pub candidates: Vec<FitResult>,
    pub result: FitResult,
    /// Profile-likelihood intervals (empty when not computed).
    pub intervals: Vec<goniofit::fit::profile::Interval>,
}

/// Fit one dataset with every candidate model; keep the lowest BIC.
/// Every fit shares `stop` (the command's `--timeout` and signals): once it fires, the
/// running fit ends at its best point, and candidates not yet started are skipped.
fn fit_dataset(
    args: &FitArgs,
    label: String,
    mut ds: Dataset,
    progress: bool,
    stop: &Stop,
) -> anyhow::Result<Outcome> {
    let candidates: Vec<String> = if args.model.eq_ignore_ascii_case("auto") {
        AUTO_CANDIDATES.iter().map(|s| s.to_string()).collect()
    } else {
        goniofit::model::by_name(&args.model, &ModelOptions::default()).map_err(|e| match e {
            Error::UnknownModel(name) => Error::Usage(format!(
                "unknown model '{name}' (known: kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert, lambert-specular, or auto to fit the last four and keep the lowest BIC)"
            )),
            e => e,
        })?;
        vec![args.model.to_ascii_lowercase()]
    };
    let needs_wavelength = candidates.iter().any(|m| m.starts_with("kbs"));
    let input = input_of(args, &ds, needs_wavelength)?;
    if input.channel_names.len() <= 1 {
        // The input now holds the angles (as geometry) and values; what is left of the
        // dataset serves the residuals file (rows) and the report's setting (weights,
        // wavelength). A joint fit keeps the samples for its one-channel comparison fit.
        ds.samples = Vec::new();
        ds.lines = Vec::new();
        ds.value = None;
    }
    let uncertainties = ds.sigma_l.is_some();
    let mut results: Vec<FitResult> = Vec::new();
    let mut not_fitted = Vec::new();
    for m in &candidates {
        if stop.is_requested() && !results.is_empty() {
            not_fitted.push(m.as_str());
            continue;
        }
        let mut config = fit_config(args, m, uncertainties)?;
        config.lm.progress = progress && args.show_progress();
        config.lm.stop = Some(stop.clone());
        results.push(
            driver::fit(&input, &config).with_context(|| format!("{label}: fitting model {m}"))?,
        );
    }
    let (best, skipped) = lowest_bic_usable(&results);
    let mut result = results[best].clone();
    result.notes.extend(skipped);
    if !not_fitted.is_empty() {
        result.notes.push(format!(
            "the fit was stopped before the candidates {} were fitted",
            not_fitted.join(", ")
        ));
    }
    if args.absolute_sigma {
        report::use_absolute_sigma(&mut result);
    }
    report::add_reflectance_factors(
        &mut result,
        &report::Units {
            quantity: args.quantity_for(&ds).0,
            ..Default::default()
        },
    );
    if input.channel_names.len() > 1 && !stop.is_requested() {
        if let Some(note) = joint_narrowing(args, &ds, &result, stop)? {
            result.notes.push(note);
        }
    }
    // Intervals for a single dataset (`progress` is true only then): many fits at once
    // get the summary table instead.
    let wanted = !args.no_intervals && progress && result.n_free <= MAX_PROFILED;
    let mut intervals = if wanted {
        profile_intervals(args, &input, &result, uncertainties, stop)?
    } else {
        Vec::new()
    };
    // A profile walk cut short by a stop request ends at a wrong likelihood: none is shown.
    if wanted && stop.is_requested() {
        intervals.clear();
        result.notes.push(
            "profile-likelihood intervals not computed: the fit was stopped (only the \
             standard errors are shown)"
                .into(),
        );
    }
    Ok(Outcome {
        label,
        dataset: ds,
        input,
        candidates: results,
        result,
        intervals,
    })
}

/// The candidate with the lowest BIC among the converged fits (among all when none
/// converged), and a note for each candidate with a lower BIC that was skipped because its
/// fit is not a usable optimum (degenerate, or stopped without converging).
fn lowest_bic_usable(results: &[FitResult]) -> (usize, Vec<String>) {
    let any_converged = results.iter().any(|r| r.converged());
    let best = results
        .iter()
        .enumerate()
        .filter(|(_, r)| r.converged() || !any_converged)
        .min_by(|a, b| a.1.bic.total_cmp(&b.1.bic))
        .map(|(i, _)| i)
        .expect("at least one candidate");
    let skipped = results
        .iter()
        .filter(|r| !r.converged() && any_converged && r.bic < results[best].bic)
        .map(|r| {
            format!(
                "auto: skipped {} (lower BIC {:.4}) because its fit is not usable: {}",
                r.model,
                r.bic,
                r.notes
                    .last()
                    .map(String::as_str)
                    .unwrap_or(r.termination.describe())
            )
        })
        .collect();
    (best, skipped)
}

/// Fits with more free parameters than this get no profile intervals (each needs two
/// walks of refits per quantity).
pub const MAX_PROFILED: usize = 8;

/// Profile-likelihood intervals (`goniofit::fit::profile`) of every free parameter, of
/// the parameters the reduced fit held, and of T/σ, the rms slope, the amplitudes and
/// the reflectance factors, on the full problem at the reported optimum. Every refit shares
/// the command's `stop`; once it fires the walks end (the caller discards their result).
pub fn profile_intervals(
    args: &FitArgs,
    input: &FitInput,
    r: &FitResult,
    uncertainties: bool,
    stop: &Stop,
) -> anyhow::Result<Vec<goniofit::fit::profile::Interval>> {
    use goniofit::fit::problem::FitProblem;
    use goniofit::fit::profile::{Profiler, Target};
    if stop.is_requested() {
        return Ok(Vec::new());
    }
    let mut config = fit_config(args, &r.model, uncertainties)?;
    config.lm.stop = Some(stop.clone());
    let model = goniofit::model::by_name(&r.model, &config.model_opts)?;
    let mut layout = r.layout.clone();
    // Parameters held by the reduction (reported as not fixed) are profiled too.
    for (fp, p) in layout.params.iter_mut().zip(&r.params) {
        if !p.fixed {
            fp.fixed = None;
        }
    }
    let floor = driver::residual_floor(&config, &input.y);
    let problem = FitProblem::new(model.as_ref(), layout, input, config.residual, floor)?
        .with_loss(config.loss);
    let prof = Profiler::new(&problem, &r.values, args.absolute_sigma, &config.lm);
    let layout = &problem.layout;
    let mut out = Vec::new();
    for k in layout.free() {
        if stop.is_requested() {
            break;
        }
        if let Some(iv) = prof.interval(&layout.params[k].name, &Target::Param(k)) {
            out.push(iv);
        }
    }
    let first = |n: &str| layout.find(n).first().copied();
    if let (Some(ks), Some(kt)) = (first("sigma"), first("T")) {
        let ratio = Target::Product {
            coef: vec![(kt, 1.0), (ks, -1.0)],
            eliminate: ks,
        };
        if let Some(iv) = prof.interval("T/sigma", &ratio) {
            out.push(iv.mapped("rms_slope", 2.0, true));
            out.push(iv);
        }
        for d in &r.derived {
            if !d.name.starts_with("amplitude") {
                continue;
            }
            let scale = d.name.replacen("amplitude", "scale", 1);
            let Some(ka) = layout.params.iter().position(|p| p.name == scale) else {
                continue;
            };
            let coef = match r.verdict {
                driver::Verdict::Smooth => vec![(ka, 1.0), (ks, 2.0)],
                _ => vec![(ka, 1.0), (kt, 2.0), (ks, -2.0)],
            };
            let target = Target::Product {
                coef,
                eliminate: ks,
            };
            if let Some(iv) = prof.interval(&d.name, &target) {
                out.push(iv);
            }
        }
    }
    for d in &r.derived {
        if let Some(term) = d.doc.strip_prefix("π·").and_then(|t| t.split(',').next()) {
            let src = d.name.replacen("reflectance_factor", term, 1);
            if let Some(iv) = out.iter().find(|i| i.name == src) {
                let m = iv.mapped(&d.name, std::f64::consts::PI, false);
                out.push(m);
            }
        }
    }
    Ok(out)
}

/// The fit input of a dataset with the quantity, wavelength, residual and floor of `args`.
pub fn input_of(args: &FitArgs, ds: &Dataset, needs_wavelength: bool) -> anyhow::Result<FitInput> {
    fit_input(
        ds,
        args.quantity_for(ds).0,
        args.wavelength_value(),
        needs_wavelength,
        args.residual.into(),
        args.floor,
    )
}

/// The report of one outcome as JSON.
fn outcome_json(o: &Outcome, info: &RunInfo) -> serde_json::Value {
    let mut v = report::json::to_json(&o.result, info);
    v["replay"] = replay_json(&o.result);
    if o.candidates.len() > 1 {
        v["comparison"] = serde_json::json!(o
            .candidates
            .iter()
            .map(|r| serde_json::json!({"model": r.model, "bic": r.bic, "aic": r.aic, "cost": r.cost, "converged": r.converged()}))
            .collect::<Vec<_>>());
    }
    v
}

/// The report of one outcome as text.
fn outcome_text(o: &Outcome, info: &RunInfo) -> String {
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
    s + &report::text::render(&o.result, info)
}

pub fn run(args: FitArgs) -> anyhow::Result<u8> {
    let opts = args.read_options()?;
    if let Some(r) = &args.residuals {
        let inputs: Vec<(&str, &Path)> = args.file.iter().map(|f| ("input", f.as_path())).collect();
        io::check_distinct(&inputs, &[("--residuals", r)])?;
    }
    // Every input is read (and checked) before any fit starts.
    let mut jobs: Vec<(String, Dataset)> = Vec::new();
    let mut files: Vec<(PathBuf, report::setting::InputInfo)> = Vec::new();
    for file in &args.file {
        // The raw rows are kept only for the residuals file (which passes them through).
        let bar = reading_bar(file, args.show_progress());
        let ds = io::read_dataset_with(file, &opts, args.residuals.is_some(), &|done| {
            bar.set_position(done)
        })?;
        bar.finish_and_clear();
        check_magnitudes(&ds)?;
        files.push((file.clone(), input_info(file)?));
        if args.by_group {
            let groups = ds.channel_groups();
            if groups.is_empty() {
                return Err(Error::Usage(format!(
                    "{}: --by-group needs groups: ASTM channels, a group column, or a wavelength column",
                    io::shown(file)
                ))
                .into());
            }
            for (name, idx) in groups {
                let mut sub = ds.subset(&idx);
                sub.channel = None;
                jobs.push((
                    format!("{} [{}]", io::shown(file), io::shown_text(&name)),
                    sub,
                ));
            }
        } else {
            jobs.push((io::shown(file), ds));
        }
    }
    let single = jobs.len() == 1;
    if !single && (args.residuals.is_some() || args.plot.is_some() || args.html.is_some()) {
        return Err(Error::Usage(
            "--residuals and --plot take one dataset; fit several files one at a time for those"
                .into(),
        )
        .into());
    }
    // From here on Ctrl-C, SIGTERM and SIGHUP stop the fits (which report their best point
    // and exit 3) instead of ending the process; `--timeout` bounds the whole command.
    let stop = Stop::new(args.timeout.map(std::time::Duration::from_secs_f64), None);
    let t0 = std::time::Instant::now();
    let threads = args.threads.unwrap_or(0);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| anyhow::anyhow!("thread pool: {e}"))?;
    let outcomes: Vec<anyhow::Result<Outcome>> = if single {
        let (label, ds) = jobs.pop().expect("one job");
        vec![pool.install(|| fit_dataset(&args, label, ds, true, &stop))]
    } else {
        use rayon::prelude::*;
        let bar = if args.show_progress() {
            super::recover::progress_bar(jobs.len() as u64, "datasets fitted")
        } else {
            indicatif::ProgressBar::hidden()
        };
        let done = pool.install(|| {
            jobs.into_par_iter()
                .map(|(label, ds)| {
                    let outcome = fit_dataset(&args, label, ds, false, &stop);
                    bar.inc(1);
                    outcome
                })
                .collect()
        });
        bar.finish_and_clear();
        done
    };
    let wall = t0.elapsed().as_secs_f64();
    let outcomes: Vec<Outcome> = outcomes.into_iter().collect::<anyhow::Result<_>>()?;
    let info_for = |o: &Outcome| {
        let file = files
            .iter()
            .find(|(p, _)| *p == o.dataset.path)
            .map(|(_, i)| i.clone())
            .unwrap_or_default();
        RunInfo {
            input: o.label.clone(),
            command: command_line(),
            version: env!("CARGO_PKG_VERSION").to_string(),
            setting: setting_of(&args, &o.dataset, &o.input, &file),
            intervals: o.intervals.clone(),
        }
    };
    let infos: Vec<RunInfo> = outcomes.iter().map(info_for).collect();
    let rows: Vec<report::summary::Row> = outcomes
        .iter()
        .zip(&infos)
        .map(|(o, i)| report::summary::row(&o.label, &o.result, &i.setting.units))
        .collect();
    if args.json {
        let values: Vec<serde_json::Value> = outcomes
            .iter()
            .zip(&infos)
            .map(|(o, i)| outcome_json(o, i))
            .collect();
        let v = if single {
            values.into_iter().next().expect("one outcome")
        } else {
            serde_json::json!({
                "fits": values,
                "datasets": outcomes.len(),
                "seconds": wall,
                "threads": pool.current_num_threads(),
                "summary": summary_json(&rows),
            })
        };
        io::print_stdout(&format!("{}\n", serde_json::to_string_pretty(&v)?))?;
    } else {
        let mut text: String = outcomes
            .iter()
            .zip(&infos)
            .map(|(o, i)| outcome_text(o, i))
            .collect();
        let joint = outcomes.iter().any(|o| o.input.channel_names.len() > 1);
        if !single || joint {
            text += &report::summary::table(&rows);
        }
        io::print_stdout(&text)?;
    }
    if let Some(path) = &args.summary {
        let headers: Vec<String> = report::summary::CSV_HEADER.map(String::from).to_vec();
        io::write_csv(path, &headers, &report::summary::csv_rows(&rows))?;
    }
    if !single && !args.quiet {
        eprintln!(
            "goniofit: fitted {} datasets in {:.3} s ({:.1} datasets/s) on {} threads",
            outcomes.len(),
            wall,
            outcomes.len() as f64 / wall,
            pool.current_num_threads()
        );
    }
    if single {
        let o = &outcomes[0];
        if let Some(path) = &args.residuals {
            write_residuals(path, &o.dataset, &o.result)?;
        }
        if let Some(path) = &args.html {
            write_html(&args, path, o, &infos[0])?;
        }
        if let Some(dir) = &args.plot {
            let config = fit_config(&args, &o.result.model, o.dataset.sigma_l.is_some())?;
            let written = plot_fit(dir, &config, &o.input, &o.result.layout, &o.result.values)?;
            eprintln!(
                "goniofit: wrote {} pictures to {}",
                written.len(),
                goniofit::io::shown(dir)
            );
        }
    }
    // A signal that came after the fits (while the outputs were written) still says the
    // run was interrupted: every output is complete, and the exit code is 3.
    let interrupted = stop.requested() == Some(goniofit::fit::lm::Termination::Interrupted);
    Ok(
        if outcomes.iter().all(|o| o.result.converged()) && !interrupted {
            0
        } else {
            3
        },
    )
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
    bar.set_message(file.display().to_string());
    bar
}

/// Files smaller than this are read without a bar (they take milliseconds).
const READING_BAR_BYTES: u64 = 4 << 20;

/// Write the HTML page of one outcome: its pictures drawn into a temporary folder and
/// inlined as SVG.
fn write_html(args: &FitArgs, path: &Path, o: &Outcome, info: &RunInfo) -> anyhow::Result<()> {
    let config = fit_config(args, &o.result.model, o.dataset.sigma_l.is_some())?;
    let dir = tempfile::tempdir().context("a temporary folder for the pictures")?;
    let written = plot_fit(
        dir.path(),
        &config,
        &o.input,
        &o.result.layout,
        &o.result.values,
    )?;
    let mut pictures = Vec::new();
    for p in written
        .iter()
        .filter(|p| p.extension().is_some_and(|e| e == "svg"))
    {
        let svg = std::fs::read_to_string(p).map_err(|source| Error::Io {
            path: p.clone(),
            source,
        })?;
        let title = p
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        pictures.push((title, svg));
    }
    let text = outcome_text(o, info);
    let page = report::html::page(&o.result, info, &text, &pictures);
    io::write_bytes(path, page.as_bytes())?;
    eprintln!(
        "goniofit: wrote {} (one page, {} pictures inline)",
        path.display(),
        pictures.len()
    );
    Ok(())
}

/// The summary rows as JSON objects (the CSV's columns).
fn summary_json(rows: &[report::summary::Row]) -> serde_json::Value {
    let csv = report::summary::csv_rows(rows);
    serde_json::Value::Array(
        csv.into_iter()
            .map(|r| {
                let m: serde_json::Map<String, serde_json::Value> = report::summary::CSV_HEADER
                    .iter()
                    .zip(r)
                    .map(|(k, v)| (k.to_string(), serde_json::Value::String(v)))
                    .collect();
                serde_json::Value::Object(m)
            })
            .collect(),
    )
}

/// For a joint fit: how much narrower σ, T and T/σ are than from the middle channel alone,
/// or that the data determines them neither way.
fn joint_narrowing(
    args: &FitArgs,
    ds: &Dataset,
    joint: &FitResult,
    stop: &Stop,
) -> anyhow::Result<Option<String>> {
    let Some(labels) = &ds.channel else {
        return Ok(None);
    };
    let names = &joint.layout.channel_names;
    let mid = &names[names.len() / 2];
    let idx: Vec<usize> = (0..labels.len())
        .filter(|&i| io::shown_text(&labels[i]) == mid.as_str())
        .collect();
    let mut single = ds.subset(&idx);
    single.channel = None;
    let input = input_of(args, &single, true)?;
    let mut config = fit_config(args, &joint.model, ds.sigma_l.is_some())?;
    config.lm.progress = false;
    config.lm.stop = Some(stop.clone());
    let alone = driver::fit(&input, &config)?;
    if stop.is_requested() {
        // The single-channel fit was cut short: its errors say nothing.
        return Ok(None);
    }
    let mut parts = Vec::new();
    for name in ["sigma", "T", "T/sigma"] {
        let se = |r: &FitResult| -> Option<Option<f64>> {
            let p = r.params.iter().find(|p| p.name == name);
            let d = r.derived.iter().find(|d| d.name == name);
            match (p, d) {
                (Some(p), _) => Some(p.stderr),
                (None, Some(d)) => Some(d.stderr),
                _ => None,
            }
        };
        match (se(joint), se(&alone)) {
            (Some(Some(j)), Some(Some(a))) => parts.push(format!(
                "{name}: ±{j:.3e} joint vs ±{a:.3e} from {mid} alone ({:.1}× narrower)",
                a / j
            )),
            (Some(Some(j)), Some(None)) => parts.push(format!(
                "{name}: ±{j:.3e} joint, not determined from {mid} alone"
            )),
            (Some(None), Some(Some(a))) => parts.push(format!(
                "{name}: not determined jointly, ±{a:.3e} from {mid} alone"
            )),
            (Some(None), Some(None)) => parts.push(format!(
                "{name}: not determined by the data, jointly or from {mid} alone"
            )),
            _ => {}
        }
    }
    Ok((!parts.is_empty()).then(|| {
        format!(
            "joint fit over {} channels: {}",
            names.len(),
            parts.join("; ")
        )
    }))
}

/// Write the input rows with L_fit, residual, std_residual and mode (atomically).
fn write_residuals(path: &Path, ds: &Dataset, r: &FitResult) -> anyhow::Result<()> {
    let mut headers = ds.headers.clone();
    headers.extend(["L_fit", "residual", "std_residual", "mode"].map(String::from));
    let rows: Vec<Vec<String>> = ds
        .rows
        .iter()
        .enumerate()
        .map(|(i, row)| {
            let mut row = row.clone();
            row.push(format!("{:e}", r.fitted[i]));
            row.push(format!("{:e}", r.residuals[i]));
            row.push(format!("{:e}", r.std_residuals[i]));
            row.push(r.sample_modes[i].name().to_string());
            row
        })
        .collect();
    io::write_csv(path, &headers, &rows)?;
    Ok(())
}

/// What `goniofit plot` needs to redraw a fit from its JSON report: the fit's command-line
/// arguments and the fitted values of every parameter (layout order).
fn replay_json(r: &FitResult) -> serde_json::Value {
    let args: Vec<String> = std::env::args_os()
        .skip(1)
        .map(|a| a.to_string_lossy().into_owned())
        .collect();
    serde_json::json!({
        "args": args,
        "model": r.model,
        "names": r.layout.params.iter().map(|p| p.name.clone()).collect::<Vec<_>>(),
        "values": r.values,
        "n_free": r.n_free,
    })
}

/// Draw the pictures of a fit at parameter values `values` (layout order). For a joint fit
/// the middle channel is drawn.
pub fn plot_fit(
    dir: &Path,
    config: &FitConfig,
    input: &FitInput,
    layout: &goniofit::fit::problem::ParamLayout,
    values: &[f64],
) -> anyhow::Result<Vec<PathBuf>> {
    use goniofit::fit::problem::FitProblem;
    let model = goniofit::model::by_name(&config.model, &config.model_opts)?;
    let c = layout.index.len() / 2;
    let idx: Vec<usize> = (0..input.y.len())
        .filter(|&i| input.channel[i] == c)
        .collect();
    let sub = input.subset(&idx);
    let floor = driver::residual_floor(config, &input.y);
    let problem = FitProblem::new(model.as_ref(), layout.clone(), &sub, config.residual, floor)?;
    let (fitted, _) = problem.model_values(values, false);
    let residuals = problem.raw_residuals(&fitted);
    let std_residuals = driver::standardized_residuals(
        &residuals,
        problem.sqrt_weight(),
        layout.free().len(),
        config.weights_are_uncertainties,
    );
    let params = layout.model_params(values, c);
    let specs = model.params();
    let mut title = format!("{}:", model.name());
    for (spec, v) in specs.iter().zip(&params) {
        title += &format!(" {}={}", spec.name, goniofit::plot::fmt_num(*v));
    }
    let named = |n: &str| specs.iter().position(|s| s.name == n).map(|j| params[j]);
    if let (Some(sigma), Some(t)) = (named("sigma"), named("T")) {
        title += &format!(" T/σ={}", goniofit::plot::fmt_num(t / sigma));
    }
    if layout.channel_names.len() > 1 {
        title += &format!(" [{}]", layout.channel_names[c]);
    }
    let plot_input = goniofit::plot::fit::FitPlotInput {
        title,
        model: model.as_ref(),
        params: &params,
        geo: &sub.geo,
        measured: &sub.y,
        fitted: &fitted,
        std_residuals: &std_residuals,
    };
    Ok(goniofit::plot::fit::write_fit_plots(dir, &plot_input)?)
}
