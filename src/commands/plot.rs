//! `goniofit plot`: redraw a fit's pictures from its saved JSON report (`goniofit fit
//! --json > fit.json`), without fitting again: the report carries the fit's arguments and
//! the fitted values.

use super::fit::{fit_config, input_of};
use crate::cli::{Cli, Command};
use anyhow::Context;
use clap::{Args, Parser};
use goniofit::fit::driver::{self, FitConfig, FitInput, Verdict};
use goniofit::fit::problem::ParamLayout;
use goniofit::io::{self, FileSet};
use goniofit::Error;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub struct PlotArgs {
    /// A fit report written by `goniofit fit --json`.
    pub report: PathBuf,
    /// Folder for the pictures (PNG and SVG).
    #[arg(long, default_value = "fit-plots")]
    pub out: PathBuf,
}

impl PlotArgs {
    /// The report and the measurement file it names; the pictures in the `--out` folder.
    pub fn files(&self) -> FileSet {
        let mut set = FileSet::new().input("report", &self.report);
        let data = std::fs::read_to_string(&self.report)
            .ok()
            .and_then(|text| serde_json::from_str::<serde_json::Value>(&text).ok())
            .and_then(|json| saved_input(&json));
        if let Some(data) = data {
            set = set.input("the report's input", &data);
        }
        set.pictures("--out", &self.out, &goniofit::plot::fit::PICTURES)
    }
}

/// The absolute path of the fitted file a report names (reports before it had one: None).
fn saved_input(json: &serde_json::Value) -> Option<PathBuf> {
    json["setting"]["input"]["path"]
        .as_str()
        .filter(|p| !p.is_empty())
        .map(PathBuf::from)
}

/// A fit report read back with the data it fitted: the fit's arguments, model, fitted
/// values (layout order), settings and input, and the unit of λ.
pub struct SavedFit {
    pub json: serde_json::Value,
    pub model: String,
    pub values: Vec<f64>,
    pub config: FitConfig,
    pub input: FitInput,
    pub layout: ParamLayout,
    pub unit: Option<String>,
}

/// Read a report written by `goniofit fit --json` and re-read the file it fitted (warning
/// when the file changed since). Errors: not such a report (a bad input, exit 2), or the
/// data no longer readable.
pub fn read_saved_fit(report: &Path) -> anyhow::Result<SavedFit> {
    let text = std::fs::read_to_string(report).map_err(|source| Error::Io {
        path: report.to_path_buf(),
        source,
    })?;
    let bad = |what: &str| Error::File {
        path: report.to_path_buf(),
        message: format!(
            "not a goniofit fit report ({what}); write one with `goniofit fit --json`"
        ),
    };
    let json: serde_json::Value = serde_json::from_str(&text).map_err(|_| bad("not JSON"))?;
    let replay = json.get("replay").ok_or_else(|| bad("no 'replay' block"))?;
    let fit_args: Vec<String> =
        serde_json::from_value(replay["args"].clone()).map_err(|_| bad("replay.args"))?;
    let model: String =
        serde_json::from_value(replay["model"].clone()).map_err(|_| bad("replay.model"))?;
    let values: Vec<f64> =
        serde_json::from_value(replay["values"].clone()).map_err(|_| bad("replay.values"))?;
    let cli = Cli::try_parse_from(std::iter::once("goniofit".to_string()).chain(fit_args))
        .map_err(|e| bad(&format!("its fit arguments do not parse: {e}")))?;
    let Command::Fit(fa) = cli.command else {
        return Err(bad("not a fit").into());
    };
    let opts = fa.read_options()?;
    // The report's absolute input path (reports before it had one: the path as typed).
    let saved = &json["setting"]["input"];
    let file = match saved_input(&json) {
        Some(p) => p,
        None => fa.file.first().ok_or_else(|| bad("no input file"))?.clone(),
    };
    let ds = io::read_dataset(&file, &opts)
        .with_context(|| format!("re-reading the data of {}", goniofit::io::shown(report)))?;
    if let Some(want) = saved["sha256"].as_str() {
        let now = super::fit::input_info(&file)?.sha256;
        if now != want {
            eprintln!(
                "goniofit: warning: {} changed since the fit (sha256 {now}, the report has {want}); what follows uses the file as it is now",
                goniofit::io::shown(&file)
            );
        }
    }
    let input = input_of(&fa, &ds, model.starts_with("kbs"))?;
    // The factors of the fitted model (an `auto` choice's are not among the arguments).
    let factors = replay["factors"].as_str().unwrap_or_default();
    let mut config = fit_config(&fa, &model, ds.sigma_l.is_some())?;
    config.model_opts = config
        .model_opts
        .with_factors_of(&format!("{model} {factors}"))
        .1;
    let m = goniofit::model::by_name(&model, &config.model_opts)?;
    let layout = ParamLayout::new(m.as_ref(), &input.channel_names);
    if layout.len() != values.len() {
        return Err(bad("parameter count does not match the model").into());
    }
    let unit = super::fit::wavelength_unit(&fa, &ds);
    Ok(SavedFit {
        json,
        model,
        values,
        config,
        input,
        layout,
        unit,
    })
}

pub fn run(args: PlotArgs) -> anyhow::Result<u8> {
    let SavedFit {
        json,
        values,
        config,
        input,
        layout,
        unit,
        ..
    } = read_saved_fit(&args.report)?;
    let status = plot_status(&json);
    let written = plot_fit(
        &args.out,
        &config,
        &input,
        (&layout, &values, None),
        (&status, &undetermined_params(&json)),
        unit.as_deref(),
    )?;
    eprintln!(
        "goniofit: wrote {} pictures to {}",
        written.len(),
        goniofit::io::shown(&args.out)
    );
    Ok(0)
}

/// The free parameters the fit's JSON report marks as not determined by the data.
pub fn undetermined_params(json: &serde_json::Value) -> Vec<String> {
    json["params"]
        .as_object()
        .map(|m| {
            m.iter()
                .filter(|(_, p)| p["determined"] == false && p["fixed"] != true)
                .map(|(k, _)| k.clone())
                .collect()
        })
        .unwrap_or_default()
}

/// The pictures' second title line, from the fit's JSON report (so that `goniofit plot`
/// says the same as `fit --plot`): T/σ with its standard error, the parameters the data
/// does not determine, and whether the fit converged (or why not).
pub fn plot_status(json: &serde_json::Value) -> String {
    use goniofit::plot::fmt_num;
    let mut parts = Vec::new();
    if let Some(d) = json["derived"].get("T/sigma") {
        if let Some(v) = d["value"].as_f64() {
            parts.push(match d["stderr"].as_f64().filter(|e| e.is_finite()) {
                Some(e) => format!("T/σ = {} ± {}", fmt_num(v), fmt_num(e)),
                None => format!("T/σ = {}", fmt_num(v)),
            });
        }
    }
    let mut undetermined: Vec<String> = undetermined_params(json)
        .iter()
        .map(|k| k.replace("sigma", "σ"))
        .collect();
    // σ and T first, as in the report.
    undetermined.sort_by_key(|k| (k != "σ", k != "T", k.clone()));
    // The text report's words for a verdict that leaves something undetermined (σ drawn
    // as the glyph the pictures can show).
    let verdict = json["verdict"].as_str().and_then(Verdict::from_name);
    if let Some(v) = verdict.filter(|v| *v != Verdict::Full) {
        parts.push(goniofit::report::text::verdict_text(v).replace("sigma", "σ"));
    }
    if !undetermined.is_empty() {
        parts.push(format!("not determined: {}", undetermined.join(", ")));
    }
    let termination = json["termination"].as_str().unwrap_or("?");
    parts.push(if json["converged"] == true {
        format!("converged ({termination})")
    } else if termination == "degenerate" {
        "degenerate: not a usable optimum (see the report's notes)".to_string()
    } else {
        format!("not converged ({termination}): the best point so far")
    });
    parts.join("; ")
}

/// A fit to draw: its layout, parameter values, and fitted values when the fit has them
/// (else they are evaluated here).
pub type FitToDraw<'a> = (
    &'a goniofit::fit::problem::ParamLayout,
    &'a [f64],
    Option<&'a [f64]>,
);

/// Draw the pictures of a fit (see [`FitToDraw`]) into `dir` as PNG and SVG (see
/// [`with_plot_input`] for what `status` and `unit` are); returns the files written.
pub fn plot_fit(
    dir: &Path,
    config: &FitConfig,
    input: &FitInput,
    fit: FitToDraw,
    status: (&str, &[String]),
    unit: Option<&str>,
) -> anyhow::Result<Vec<PathBuf>> {
    with_plot_input(config, input, fit, status, unit, |p| {
        goniofit::plot::fit::write_fit_plots(dir, p)
    })
}

/// The pictures of a fit rendered in memory: (name, SVG document), named as
/// [`goniofit::plot::fit::PICTURES`].
pub fn svg_of_fit(
    config: &FitConfig,
    input: &FitInput,
    fit: FitToDraw,
    status: (&str, &[String]),
    unit: Option<&str>,
) -> anyhow::Result<Vec<(String, String)>> {
    with_plot_input(
        config,
        input,
        fit,
        status,
        unit,
        goniofit::plot::fit::svg_pictures,
    )
}

/// Call `draw` with the picture input of a fit at parameter values `fit.1` (layout
/// `fit.0`; `fit.2` its fitted values when the fit has them, else they are evaluated
/// here), with `status.0` (see [`plot_status`]) under the titles, the parameters of
/// `status.1` (not determined by the data) named in the title without a value, and λ in
/// `unit`. A joint fit draws every channel with its own parameters (the polar and contour
/// maps: the busiest θi's channel, named in their titles).
pub fn with_plot_input<T>(
    config: &FitConfig,
    input: &FitInput,
    (layout, values, fitted): FitToDraw,
    status: (&str, &[String]),
    unit: Option<&str>,
    draw: impl FnOnce(&goniofit::plot::fit::FitPlotInput) -> goniofit::error::Result<T>,
) -> anyhow::Result<T> {
    use goniofit::fit::problem::FitProblem;
    let model = goniofit::model::by_name(&config.model, &config.model_opts)?;
    let floor = driver::residual_floor(config, &input.y);
    let problem = FitProblem::new(
        model.as_ref(),
        layout.clone(),
        input,
        config.residual,
        floor,
    )?;
    let fitted = match fitted.filter(|f| f.len() == input.y.len()) {
        Some(f) => f.to_vec(),
        None => problem.model_values(values, false).0,
    };
    let residuals = problem.raw_residuals(&fitted);
    let std_residuals = driver::standardized_residuals(
        &residuals,
        problem.sqrt_weight(),
        layout.free().len(),
        config.weights_are_uncertainties,
    );
    let n_channels = layout.index.len().max(1);
    let params: Vec<Vec<f64>> = (0..n_channels)
        .map(|c| layout.model_params(values, c))
        .collect();
    let joint = n_channels > 1;
    let plot_input = goniofit::plot::fit::FitPlotInput {
        title: plot_title(model.as_ref(), layout, &params[0], status.1),
        subtitle: status.0.to_string(),
        model: model.as_ref(),
        params: &params[0],
        geo: &input.geo,
        measured: &input.y,
        fitted: &fitted,
        std_residuals: &std_residuals,
        wavelength_unit: unit,
        channels: goniofit::plot::fit::Channels {
            of_sample: match input.channel.as_slice() {
                Some(c) if joint => c,
                _ => &[],
            },
            params: if joint { &params } else { &[] },
            names: &layout.channel_names,
        },
    };
    Ok(draw(&plot_input)?)
}

/// "kbs: sigma=… T=… scale=…"; for a joint fit only the shared parameters, and which are
/// per channel. A parameter in `undetermined` gets no value: "(σ, T not determined)".
fn plot_title(
    model: &dyn goniofit::model::Model,
    layout: &goniofit::fit::problem::ParamLayout,
    params: &[f64],
    undetermined: &[String],
) -> String {
    let n_channels = layout.index.len();
    let per_channel = |j: usize| {
        n_channels > 1
            && layout
                .params
                .iter()
                .any(|p| p.spec == j && p.channel.is_some())
    };
    let mut title = format!("{}:", model.name());
    let mut own = Vec::new();
    let mut loose = Vec::new();
    for (j, (spec, v)) in model.params().iter().zip(params).enumerate() {
        if per_channel(j) {
            own.push(spec.name.to_string());
        } else if undetermined.iter().any(|u| u == spec.name) {
            loose.push(spec.name.replace("sigma", "σ"));
        } else {
            title += &format!(" {}={}", spec.name, goniofit::plot::fmt_num(*v));
        }
    }
    if !loose.is_empty() {
        title += &format!(" ({} not determined)", loose.join(", "));
    }
    if !own.is_empty() {
        title += &format!(
            " (joint fit of {n_channels} channels; {} per channel)",
            own.join(", ")
        );
    }
    title
}
