//! `goniofit fit`: a measurement file in, a fit report out.

use super::args::{parse_patch, ModeArg, QuantityArg};
use anyhow::Context;
use clap::{Args, ValueEnum};
use goniofit::fit::driver::{self, FitConfig, FitInput, FitResult};
use goniofit::fit::lm::{LmConfig, Stop};
use goniofit::fit::problem::ResidualKind;
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

#[derive(Debug, Args)]
pub struct FitArgs {
    /// Model: kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert, lambert-specular, or auto
    /// (fits lambert, lambert-specular, kbs, kbs+lambert and keeps the lowest BIC).
    #[arg(long, default_value = "kbs")]
    pub model: String,
    /// Whether the measured value is a radiance L (eq. 28) or a BRDF (L / cos θi). A
    /// reflectance factor is a BRDF × π.
    #[arg(long, value_enum, default_value = "radiance")]
    pub quantity: QuantityArg,
    /// Wavelength (the unit of σ and T in the report); required for KBS models unless a
    /// `wavelength` column or an ASTM channel name gives it.
    #[arg(long)]
    pub wavelength: Option<f64>,
    /// ASTM E1392 channel to fit (e.g. 550nm), or `all` for a joint fit over every channel
    /// with shared σ, T and per-channel scales.
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
    #[arg(long, default_value_t = 1e-10)]
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
    /// Show a progress line while fitting.
    #[arg(long)]
    pub progress: bool,
    /// Print the report as one JSON object.
    #[arg(long)]
    pub json: bool,
    /// Write the input rows with L_fit, residual, std_residual, mode.
    #[arg(long)]
    pub residuals: Option<PathBuf>,
    /// Write the fit's pictures (PNG and SVG) into this folder.
    #[arg(long)]
    pub plot: Option<PathBuf>,
    /// Fit each group (a `group` column, or each ASTM channel) on its own.
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
    /// How the input files are read (`--radians`, `--signed-theta-r`, `--columns`,
    /// `--channel`); values are required.
    pub fn read_options(&self) -> anyhow::Result<ReadOptions> {
        Ok(ReadOptions {
            radians: self.radians,
            signed_theta_r: self.signed_theta_r,
            columns: io::csv::parse_columns(self.columns.as_deref().unwrap_or(""))?,
            require_value: true,
            channel: self.channel.clone(),
        })
    }
}

/// The fit's data from a dataset: geometry, values, weights, channels.
pub fn fit_input(
    ds: &Dataset,
    quantity: Quantity,
    wavelength: Option<f64>,
    needs_wavelength: bool,
) -> anyhow::Result<FitInput> {
    let n = ds.samples.len();
    let lambda: Vec<f64> = match (&ds.wavelength, wavelength) {
        (_, Some(l)) => vec![l],
        (Some(w), None) => w.clone(),
        (None, None) if needs_wavelength => {
            return Err(Error::Usage(format!(
                "{}: KBS models need a wavelength: give --wavelength, a wavelength column, or an ASTM channel such as 550nm",
                ds.path.display()
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
    let weight = ds.weight.clone().unwrap_or_else(|| vec![1.0; n]);
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

/// The fit configuration from the arguments, for a given model name.
pub fn fit_config(
    args: &FitArgs,
    model: &str,
    weights_are_uncertainties: bool,
) -> anyhow::Result<FitConfig> {
    let lm = LmConfig {
        max_iters: args.max_iter,
        timeout: args.timeout.map(std::time::Duration::from_secs_f64),
        progress: args.progress,
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
        floor: args.floor,
        init: parse_assignments(args.init.as_deref().unwrap_or(""))?,
        fix: parse_assignments(args.fix.as_deref().unwrap_or(""))?,
        lm,
        weights_are_uncertainties,
        reduce: !args.no_reduce,
    })
}

/// The command line as typed, for the report.
fn command_line() -> String {
    std::env::args().collect::<Vec<_>>().join(" ")
}

/// One dataset's fit: every candidate model, and the chosen one (lowest BIC).
pub struct Outcome {
    pub label: String,
    pub dataset: Dataset,
    pub input: FitInput,
    pub candidates: Vec<FitResult>,
    pub result: FitResult,
}

/// Fit one dataset with every candidate model; keep the lowest BIC.
/// Every fit shares `stop` (the command's `--timeout` and signals): once it fires, the
/// running fit ends at its best point, and candidates not yet started are skipped.
fn fit_dataset(
    args: &FitArgs,
    label: String,
    ds: Dataset,
    progress: bool,
    stop: &Stop,
) -> anyhow::Result<Outcome> {
    let candidates: Vec<String> = if args.model.eq_ignore_ascii_case("auto") {
        AUTO_CANDIDATES.iter().map(|s| s.to_string()).collect()
    } else {
        goniofit::model::by_name(&args.model, &ModelOptions::default())?;
        vec![args.model.to_ascii_lowercase()]
    };
    let needs_wavelength = candidates.iter().any(|m| m.starts_with("kbs"));
    let input = fit_input(&ds, args.quantity.into(), args.wavelength, needs_wavelength)?;
    let uncertainties = ds.sigma_l.is_some();
    let mut results: Vec<FitResult> = Vec::new();
    let mut skipped = Vec::new();
    for m in &candidates {
        if stop.is_requested() && !results.is_empty() {
            skipped.push(m.as_str());
            continue;
        }
        let mut config = fit_config(args, m, uncertainties)?;
        config.lm.progress = progress && args.progress;
        config.lm.stop = Some(stop.clone());
        results.push(
            driver::fit(&input, &config).with_context(|| format!("{label}: fitting model {m}"))?,
        );
    }
    let best = results
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.bic.total_cmp(&b.1.bic))
        .map(|(i, _)| i)
        .expect("at least one candidate");
    let mut result = results[best].clone();
    if !skipped.is_empty() {
        result.notes.push(format!(
            "the fit was stopped before the candidates {} were fitted",
            skipped.join(", ")
        ));
    }
    if input.channel_names.len() > 1 && !stop.is_requested() {
        if let Some(note) = joint_narrowing(args, &ds, &result)? {
            result.notes.push(note);
        }
    }
    Ok(Outcome {
        label,
        dataset: ds,
        input,
        candidates: results,
        result,
    })
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
    for file in &args.file {
        let ds = io::read_dataset(file, &opts)?;
        if args.by_group {
            let names = ds.channel_names();
            if names.is_empty() {
                return Err(Error::Usage(format!(
                    "{}: --by-group needs a group column (or ASTM channels)",
                    file.display()
                ))
                .into());
            }
            for name in names {
                let mut sub = ds.subset(&ds.channel_indices(&name));
                sub.channel = None;
                jobs.push((format!("{} [{name}]", file.display()), sub));
            }
        } else {
            jobs.push((file.display().to_string(), ds));
        }
    }
    let single = jobs.len() == 1;
    if !single && (args.residuals.is_some() || args.plot.is_some()) {
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
        pool.install(|| {
            jobs.into_par_iter()
                .map(|(label, ds)| fit_dataset(&args, label, ds, false, &stop))
                .collect()
        })
    };
    let wall = t0.elapsed().as_secs_f64();
    let outcomes: Vec<Outcome> = outcomes.into_iter().collect::<anyhow::Result<_>>()?;
    let info_for = |o: &Outcome| RunInfo {
        input: o.label.clone(),
        command: command_line(),
        version: env!("CARGO_PKG_VERSION").to_string(),
    };
    if args.json {
        let values: Vec<serde_json::Value> = outcomes
            .iter()
            .map(|o| outcome_json(o, &info_for(o)))
            .collect();
        let v = if single {
            values.into_iter().next().expect("one outcome")
        } else {
            serde_json::json!({
                "fits": values,
                "datasets": outcomes.len(),
                "seconds": wall,
                "threads": pool.current_num_threads(),
            })
        };
        io::print_stdout(&format!("{}\n", serde_json::to_string_pretty(&v)?))?;
    } else {
        let text: String = outcomes
            .iter()
            .map(|o| outcome_text(o, &info_for(o)))
            .collect();
        io::print_stdout(&text)?;
    }
    if !single {
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
        if let Some(dir) = &args.plot {
            let config = fit_config(&args, &o.result.model, o.dataset.sigma_l.is_some())?;
            let written = plot_fit(dir, &config, &o.input, &o.result.layout, &o.result.values)?;
            eprintln!(
                "goniofit: wrote {} pictures to {}",
                written.len(),
                dir.display()
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

/// For a joint fit: how much narrower σ and T are than from the middle channel alone.
fn joint_narrowing(
    args: &FitArgs,
    ds: &Dataset,
    joint: &FitResult,
) -> anyhow::Result<Option<String>> {
    let Some(labels) = &ds.channel else {
        return Ok(None);
    };
    let names = &joint.layout.channel_names;
    let mid = &names[names.len() / 2];
    let idx: Vec<usize> = (0..labels.len()).filter(|&i| &labels[i] == mid).collect();
    let mut single = ds.subset(&idx);
    single.channel = None;
    let input = fit_input(&single, args.quantity.into(), args.wavelength, true)?;
    let mut config = fit_config(args, &joint.model, ds.sigma_l.is_some())?;
    config.lm.progress = false;
    let alone = driver::fit(&input, &config)?;
    let mut parts = Vec::new();
    for name in ["sigma", "T"] {
        let se = |r: &FitResult| {
            r.params
                .iter()
                .find(|p| p.name == name)
                .and_then(|p| p.stderr)
        };
        match (se(joint), se(&alone)) {
            (Some(j), Some(a)) => parts.push(format!(
                "{name}: ±{j:.3e} joint vs ±{a:.3e} from {mid} alone ({:.1}× narrower)",
                a / j
            )),
            (Some(j), None) => parts.push(format!(
                "{name}: ±{j:.3e} joint, not determined from {mid} alone"
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
    let args: Vec<String> = std::env::args().skip(1).collect();
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
