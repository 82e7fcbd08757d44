//! `goniofit design`: the next geometries to measure, chosen to determine a target
//! ([`crate::design`]), from a fit's report or a model with parameter values.

use super::args::{parse_wavelength, QuantityArg, Wavelength};
use super::fit_args::ResidualArg;
use super::plot::{read_saved_fit, SavedFit};
use crate::design::{self, candidates::Grid, simulate, NoiseModel, Request, Scene};
use crate::error::Error;
use crate::fit::driver::FitConfig;
use crate::fit::problem::ResidualKind;
use crate::geometry::{Quantity, Sample};
use crate::io::{self, FileSet};
use crate::model::{by_name, parse_params, Model, ModelOptions};
use crate::report::design::{self as report, Run};
use anyhow::Context;
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = AFTER_HELP)]
pub(crate) struct DesignArgs {
    /// A fit report (`goniofit fit --json > fit.json`): its model, values, wavelength,
    /// residual kind and noise (√ reduced χ²), and its data's geometries as measured.
    #[arg(long, value_name = "FIT.json", conflicts_with_all = ["model", "params", "wavelength", "quantity", "residual", "existing"])]
    pub from: Option<PathBuf>,
    /// Model name (without --from): kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert,
    /// lambert-specular.
    #[arg(long, required_unless_present = "from")]
    pub model: Option<String>,
    /// Parameter values, name=value pairs (every parameter once), e.g. sigma=190,T=1270,scale=1.
    #[arg(long, required_unless_present = "from")]
    pub params: Option<String>,
    /// Wavelength, with its unit (633nm) or a bare number in the unit of σ and T.
    #[arg(long, allow_hyphen_values = true, value_parser = parse_wavelength)]
    pub wavelength: Option<Wavelength>,
    /// Measured quantity (without --from).
    #[arg(long, value_enum)]
    pub quantity: Option<QuantityArg>,
    /// Residual kind of the noise model (without --from): absolute (ε in the unit of L),
    /// relative (ε a fraction of L), log (ε the standard deviation of ln L). Default relative.
    #[arg(long, value_enum)]
    pub residual: Option<ResidualArg>,
    /// Noise level ε of one sample (with --from: default the fit's √ reduced χ²).
    #[arg(long)]
    pub noise: Option<f64>,
    /// Geometries already measured (without --from): a CSV with theta_i,theta_r,phi_r in degrees.
    #[arg(long, value_name = "FILE")]
    pub existing: Option<PathBuf>,
    /// Candidate geometries: a CSV with theta_i,theta_r,phi_r in degrees (else a grid).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["theta_max", "step", "in_plane"])]
    pub candidates: Option<PathBuf>,
    /// Largest θi and θr of the candidate grid, degrees.
    #[arg(long, value_name = "DEG")]
    pub theta_max: Option<f64>,
    /// Step of the candidate grid (θi, θr and φr), degrees.
    #[arg(long, value_name = "DEG")]
    pub step: Option<f64>,
    /// Candidates only in the plane of incidence (φr = 0 and 180°).
    #[arg(long)]
    pub in_plane: bool,
    /// How many geometries to propose.
    #[arg(long, default_value_t = 20)]
    pub n: usize,
    /// What to determine: a parameter (sigma, T, scale, n, …), a derived quantity
    /// (T/sigma, beckmann_alpha, amplitude_rough, amplitude_smooth, reflectance_factor),
    /// or all (D-optimal: every parameter).
    #[arg(long, default_value = "all")]
    pub target: String,
    /// Dynamic range of the instrument: candidates below the largest predicted value over
    /// this are not measurable.
    #[arg(long, default_value_t = design::DYNAMIC_RANGE)]
    pub dynamic_range: f64,
    /// Other wavelengths to plan for (same unit), e.g. 420nm,480nm: each with its own
    /// amplitudes; the sentence names one that would determine the target.
    #[arg(long, value_name = "λ,...")]
    pub wavelengths: Option<String>,
    /// Write the proposed geometries as CSV (theta_i,theta_r,phi_r in degrees).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Print the design as JSON instead of text.
    #[arg(long)]
    pub json: bool,
    /// Folder for the picture (design.png and design.svg).
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Check the linearised figures: fit N simulated measurements at the measured and
    /// proposed geometries.
    #[arg(long, value_name = "N")]
    pub simulate: Option<usize>,
    /// Seed of the simulated noise.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

const AFTER_HELP: &str = "\
Examples:
  goniofit fit --model kbs+lambert --quantity brdf --channel 550nm --residual log --json \\
      data/cornell/garnet_red.astm > fit.json
  goniofit design --from fit.json --target sigma --n 20 --in-plane --out next.csv
  goniofit design --model kbs --params sigma=300,T=1500,scale=1 --wavelength 633nm \\
      --noise 0.02 --residual relative --existing scan.csv --target sigma --simulate 50";

impl DesignArgs {
    /// The report and its data, or the measured and candidate geometry files; the CSV, the
    /// picture and standard output.
    pub(crate) fn files(&self) -> FileSet {
        let mut set = FileSet::new().stdout();
        if let Some(f) = &self.from {
            set = set.input("--from", f);
        }
        for (opt, f) in [
            ("--existing", &self.existing),
            ("--candidates", &self.candidates),
        ] {
            if let Some(f) = f {
                set = set.input(opt, f);
            }
        }
        set = set.output_opt("--out", self.out.as_deref());
        match &self.plot {
            Some(dir) => set.pictures("--plot", dir, &[crate::plot::design::PICTURE]),
            None => set,
        }
    }
}

fn usage(m: String) -> anyhow::Error {
    Error::Usage(m).into()
}

/// The scene's parts: model, parameters, wavelength (value, unit), quantity, noise, the
/// measured geometries, and the fit settings a simulated measurement is fitted with.
struct Setup {
    model: Box<dyn Model>,
    params: Vec<f64>,
    wavelength: (f64, Option<String>),
    quantity: Quantity,
    noise: NoiseModel,
    existing: Vec<Sample>,
    source: String,
    fit: Option<FitConfig>,
}

pub(crate) fn run(a: DesignArgs) -> anyhow::Result<u8> {
    let setup = match &a.from {
        Some(path) => from_report(&a, read_saved_fit(path)?)?,
        None => from_model(&a)?,
    };
    let candidates = match &a.candidates {
        Some(f) => design::candidates::read(f)?,
        None => grid(&a).angles()?,
    };
    let scene = Scene {
        model: setup.model.as_ref(),
        params: setup.params.clone(),
        wavelength: setup.wavelength.0,
        quantity: setup.quantity,
        noise: setup.noise,
        unit: setup.wavelength.1.clone(),
    };
    let request = Request {
        existing: setup.existing.clone(),
        candidates,
        n: a.n,
        target: a.target.clone(),
        dynamic_range: a.dynamic_range,
        wavelengths: alternatives(&a, &setup.wavelength)?,
    };
    let d = design::design(&scene, &request)?;
    let (before, after) = match a.simulate {
        Some(draws) => {
            let (before, after) = simulate::before_and_after(
                &scene,
                &setup.existing,
                &d.chosen,
                draws,
                a.seed,
                setup.fit.as_ref(),
            )?;
            (before, Some(after))
        }
        None => (None, None),
    };
    let run = Run {
        design: &d,
        scene: &scene,
        source: &setup.source,
        simulation: after.as_ref(),
        simulation_before: before.as_ref(),
    };
    write_outputs(&a, &run)
}

/// The CSV, the picture, then the report (text or JSON) on standard output.
fn write_outputs(a: &DesignArgs, run: &Run) -> anyhow::Result<u8> {
    if let Some(out) = &a.out {
        io::write_bytes(out, report::csv(run.design).as_bytes())?;
    }
    if let Some(dir) = &a.plot {
        let pic = crate::plot::design::DesignPlot::new(run.design, run.scene)?;
        crate::plot::write_png_svg(&pic, dir, crate::plot::design::PICTURE)?;
    }
    let text = if a.json {
        let mut s = serde_json::to_string_pretty(&report::json(run)).context("formatting JSON")?;
        s.push('\n');
        s
    } else {
        report::text(run)
    };
    io::write_bytes(std::path::Path::new("-"), text.as_bytes())?;
    Ok(0)
}

fn grid(a: &DesignArgs) -> Grid {
    let d = Grid::default();
    Grid {
        theta_max_deg: a.theta_max.unwrap_or(d.theta_max_deg),
        step_deg: a.step.unwrap_or(d.step_deg),
        in_plane: a.in_plane,
    }
}

/// `--wavelengths` in the unit of the scene's wavelength (nm and µm converted).
fn alternatives(a: &DesignArgs, main: &(f64, Option<String>)) -> anyhow::Result<Vec<f64>> {
    let Some(text) = &a.wavelengths else {
        return Ok(Vec::new());
    };
    let factor = |unit: Option<&str>| -> anyhow::Result<f64> {
        Ok(match (main.1.as_deref(), unit) {
            (_, None) => 1.0,
            (Some(m), Some(u)) if m == u => 1.0,
            (Some("nm"), Some("µm")) => 1000.0,
            (Some("µm"), Some("nm")) => 1e-3,
            (m, Some(u)) => {
                return Err(usage(format!(
                    "--wavelengths: '{u}' cannot be converted to the unit of the wavelength ({})",
                    m.unwrap_or("none stated")
                )))
            }
        })
    };
    text.split(',')
        .map(|t| {
            let (v, u) = crate::io::parse_length(t)?;
            Ok(v * factor(u)?)
        })
        .collect()
}

/// The scene of a fit's report: the fit's model at its values, its data's geometries,
/// wavelength and quantity, its residual kind with `--noise` or √ reduced χ².
fn from_report(a: &DesignArgs, saved: SavedFit) -> anyhow::Result<Setup> {
    let SavedFit {
        report,
        model,
        values,
        config,
        input,
        layout,
        unit,
        ..
    } = saved;
    if layout.channel_names.len() > 1 {
        return Err(usage(
            "design plans for one channel: fit one channel (--channel NAME) and design from that report".into(),
        ));
    }
    let lambda = input.geo.wavelength[0];
    if (0..input.geo.len()).any(|i| input.geo.wavelength[i] != lambda) {
        return Err(usage(
            "design plans for one wavelength: the report's data has several".into(),
        ));
    }
    let weighted = report.setting.weights.source != "none";
    let level = match (a.noise, weighted) {
        (Some(e), _) => e,
        (None, true) => {
            return Err(usage(
                "the fit was weighted: give the noise of one new sample with --noise".into(),
            ))
        }
        (None, false) => report.reduced_chi2.unwrap_or(f64::NAN).sqrt(),
    };
    let m = by_name(&model, &config.model_opts)?;
    let existing = (0..input.geo.len())
        .map(|i| Sample {
            theta_i: input.geo.theta_i[i],
            theta_r: input.geo.theta_r[i],
            phi_r: input.geo.phi_r[i],
        })
        .collect();
    let fit = FitConfig {
        init: layout
            .params
            .iter()
            .zip(&values)
            .map(|(p, &v)| (p.name.clone(), v))
            .collect(),
        reduce: false,
        fix: Vec::new(),
        ..config.clone()
    };
    Ok(Setup {
        params: layout.model_params(&values, 0),
        model: m,
        wavelength: (lambda, unit),
        quantity: input.geo.quantity,
        noise: NoiseModel::new(config.residual, level)
            .with_context(|| "--noise (or the fit's √ reduced χ²)")?,
        existing,
        source: super::plot::saved_input(&report)
            .map_or("the fit's data".into(), |p| p.display().to_string()),
        fit: Some(fit),
    })
}

/// The scene of `--model --params --wavelength --noise --residual [--existing]`.
fn from_model(a: &DesignArgs) -> anyhow::Result<Setup> {
    let name = a.model.as_deref().unwrap_or_default();
    let model = by_name(name, &ModelOptions::default())?;
    let params = parse_params(model.as_ref(), a.params.as_deref().unwrap_or_default())?;
    let noise = a
        .noise
        .ok_or_else(|| usage("--noise: the noise of one sample is needed without --from".into()))?;
    let kind: ResidualKind = a.residual.unwrap_or(ResidualArg::Relative).into();
    let (lambda, unit) = a.wavelength.unwrap_or((1.0, None));
    let existing = match &a.existing {
        Some(f) => design::candidates::read(f)?
            .iter()
            .map(|x| x.sample())
            .collect(),
        None => Vec::new(),
    };
    Ok(Setup {
        model,
        params,
        wavelength: (lambda, unit.map(String::from)),
        quantity: a.quantity.unwrap_or_default().into(),
        noise: NoiseModel::new(kind, noise).context("--noise")?,
        source: a
            .existing
            .as_deref()
            .map_or_else(|| "none".to_string(), io::shown),
        existing,
        fit: None,
    })
}
