//! `goniofit plot`: redraw a fit's pictures from its saved JSON report (`goniofit fit
//! --json > fit.json`), without fitting again: the report carries the fit's settings and
//! the fitted values.

use crate::error::Error;
use crate::fit::driver::{FitConfig, FitInput};
use crate::fit::problem::ParamLayout;
use crate::io::{self, FileSet};
use crate::plot::fit::plot_fit;
use crate::report::json::FitReport;
use anyhow::Context;
use clap::Args;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub(crate) struct PlotArgs {
    /// A fit report written by `goniofit fit --json`.
    pub report: PathBuf,
    /// Folder for the pictures (PNG and SVG).
    #[arg(long, default_value = "fit-plots")]
    pub out: PathBuf,
}

impl PlotArgs {
    /// The report and the measurement file it names; the pictures in the `--out` folder.
    pub(crate) fn files(&self) -> FileSet {
        let mut set = FileSet::new().input("report", &self.report);
        let data = std::fs::read_to_string(&self.report)
            .ok()
            .and_then(|text| serde_json::from_str::<FitReport>(&text).ok())
            .and_then(|report| saved_input(&report));
        if let Some(data) = data {
            set = set.input("the report's input", &data);
        }
        set.pictures("--out", &self.out, &crate::plot::fit::PICTURES)
    }
}

/// The absolute path of the fitted file a report names (None for a fit of arrays).
pub(super) fn saved_input(report: &FitReport) -> Option<PathBuf> {
    let path = &report.setting.input.path;
    (!path.is_empty()).then(|| PathBuf::from(path))
}

/// A fit report read back with the data it fitted: the fit's model, fitted values (layout
/// order) and number of free parameters, configuration and input, and the unit of λ.
pub(crate) struct SavedFit {
    pub report: FitReport,
    pub model: String,
    pub values: Vec<f64>,
    pub n_free: usize,
    pub config: FitConfig,
    pub input: FitInput,
    pub layout: ParamLayout,
    pub unit: Option<String>,
}

/// Read a report written by `goniofit fit --json` and re-read the file it fitted (warning
/// when the file changed since). Errors: not such a report (a bad input, exit 2), or the
/// data no longer readable.
pub(crate) fn read_saved_fit(path: &Path) -> anyhow::Result<SavedFit> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let bad = |what: &str| Error::File {
        path: path.to_path_buf(),
        message: format!(
            "not a goniofit fit report ({what}); write one with `goniofit fit --json`"
        ),
    };
    let report: FitReport = serde_json::from_str(&text).map_err(|e| match e.classify() {
        serde_json::error::Category::Data => bad(&e.to_string()),
        _ => bad("not JSON"),
    })?;
    let replay = report
        .replay
        .clone()
        .ok_or_else(|| bad("no 'replay' block"))?;
    let settings = replay.settings;
    settings.check(crate::settings::Front::Json)?;
    let opts = settings.read_options()?;
    // The report's absolute input path (a fit of arrays has none).
    let file = saved_input(&report).ok_or_else(|| bad("no input file"))?;
    let ds = io::read_dataset(&file, &opts)
        .with_context(|| format!("re-reading the data of {}", crate::io::shown(path)))?;
    let want = &report.setting.input.sha256;
    if !want.is_empty() {
        let now = super::fit::input_info(&file)?.sha256;
        if &now != want {
            eprintln!(
                "goniofit: warning: {} changed since the fit (sha256 {now}, the report has {want}); what follows uses the file as it is now",
                crate::io::shown(&file)
            );
        }
    }
    let (model, factors, values, n_free) =
        (replay.model, replay.factors, replay.values, replay.n_free);
    let input = settings
        .dataset_fit(&ds, false)
        .input(&ds, model.starts_with("kbs"))?;
    // The factors of the fitted model (an `auto` choice's are not among the settings).
    let config = settings.fit_config(&format!("{model} {factors}"), ds.sigma_l.is_some());
    let m = crate::model::by_name(&model, &config.model_opts)?;
    let layout = ParamLayout::new(m.as_ref(), &input.channel_names);
    if layout.len() != values.len() {
        return Err(bad("parameter count does not match the model").into());
    }
    let unit = settings.wavelength_unit(&ds);
    Ok(SavedFit {
        report,
        model,
        values,
        n_free,
        config,
        input,
        layout,
        unit,
    })
}

pub(crate) fn run(args: PlotArgs) -> anyhow::Result<u8> {
    let SavedFit {
        report,
        values,
        n_free,
        config,
        input,
        layout,
        unit,
        ..
    } = read_saved_fit(&args.report)?;
    let written = plot_fit(
        &args.out,
        &config,
        &input,
        (&layout, &values, None, n_free),
        (&report.status_line(), &report.undetermined()),
        unit.as_deref(),
    )?;
    eprintln!(
        "goniofit: wrote {} pictures to {}",
        written.len(),
        crate::io::shown(&args.out)
    );
    Ok(0)
}
