//! `goniofit plot`: redraw a fit's pictures from its saved JSON report (`goniofit fit
//! --json > fit.json`), without fitting again: the report carries the fit's arguments and
//! the fitted values.

use super::fit::{fit_config, input_of, plot_fit};
use crate::cli::{Cli, Command};
use anyhow::Context;
use clap::{Args, Parser};
use goniofit::fit::problem::ParamLayout;
use goniofit::io;
use goniofit::Error;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct PlotArgs {
    /// A fit report written by `goniofit fit --json`.
    pub report: PathBuf,
    /// Folder for the pictures (PNG and SVG).
    #[arg(long, default_value = "fit-plots")]
    pub out: PathBuf,
}

pub fn run(args: PlotArgs) -> anyhow::Result<u8> {
    let text = std::fs::read_to_string(&args.report).map_err(|source| Error::Io {
        path: args.report.clone(),
        source,
    })?;
    let bad = |what: &str| Error::File {
        path: args.report.clone(),
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
    let file = match saved["path"].as_str().filter(|p| !p.is_empty()) {
        Some(p) => PathBuf::from(p),
        None => fa.file.first().ok_or_else(|| bad("no input file"))?.clone(),
    };
    let ds = io::read_dataset(&file, &opts).with_context(|| {
        format!(
            "re-reading the data of {}",
            goniofit::io::shown(&args.report)
        )
    })?;
    if let Some(want) = saved["sha256"].as_str() {
        let now = super::fit::input_info(&file)?.sha256;
        if now != want {
            eprintln!(
                "goniofit: warning: {} changed since the fit (sha256 {now}, the report has {want}); the pictures show the file as it is now",
                goniofit::io::shown(&file)
            );
        }
    }
    let input = input_of(&fa, &ds, model.starts_with("kbs"))?;
    let config = fit_config(&fa, &model, ds.sigma_l.is_some())?;
    let m = goniofit::model::by_name(&model, &config.model_opts)?;
    let layout = ParamLayout::new(m.as_ref(), &input.channel_names);
    if layout.len() != values.len() {
        return Err(bad("parameter count does not match the model").into());
    }
    let status = super::fit::plot_status(&json);
    let unit = super::fit::wavelength_unit(&fa, &ds);
    let written = plot_fit(
        &args.out,
        &config,
        &input,
        (&layout, &values),
        &status,
        unit.as_deref(),
    )?;
    eprintln!(
        "goniofit: wrote {} pictures to {}",
        written.len(),
        goniofit::io::shown(&args.out)
    );
    Ok(0)
}
