//! `goniofit synth`: synthetic measurements from known parameters, with seeded noise.
//!
//! Writes the CSV (`theta_i,theta_r,phi_r,L[,sigma_L][,wavelength]`, degrees) and, beside
//! it, the truth as JSON (`data.csv` → `data.truth.json`). Both are written atomically
//! (temporary file in the same folder, then renamed). Without `--out` the CSV goes to
//! standard output and the truth only where `--truth` says.

use super::args::{parse_patch, ModeArg, QuantityArg};
use crate::geometry::Quantity;
use crate::harness::synth::{self, CsvOptions, Layout, Noise, NoiseKind, Truth};
use crate::io::{self, FileSet};
use crate::model::{by_name, parse_params, Model};
use crate::settings::{self, Front};
use anyhow::Context;
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
#[command(allow_negative_numbers = true, after_help = AFTER_HELP)]
pub(crate) struct SynthArgs {
    /// Model name: kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert, lambert-specular.
    #[arg(long)]
    pub model: String,
    /// Parameters as name=value pairs, e.g. sigma=0.3,T=2,scale=1 (every parameter once).
    #[arg(long)]
    pub params: String,
    /// Wavelength, with its unit (633nm, 0.633um) or as a bare number; sigma, T and the
    /// wavelength column are in that unit (the truth JSON names it).
    #[arg(long, default_value = "1", allow_hyphen_values = true, value_parser = super::args::parse_wavelength)]
    pub wavelength: super::args::Wavelength,
    /// Layout: inplane (θi 15,30,45,60,75; signed θr −85..85 step 1), hemisphere
    /// (θi × θr × φr grid, default 5x18x36), grazing (θi 70..89°, same grid), or the path of
    /// a CSV with columns theta_i,theta_r,phi_r in degrees.
    #[arg(long, default_value = "hemisphere")]
    pub layout: String,
    /// Grid of the hemisphere and grazing layouts: θi x θr x φr counts.
    #[arg(long, value_name = "NIxNRxNP")]
    pub grid: Option<String>,
    /// Incidence angles of the inplane layout, degrees, comma-separated.
    #[arg(long, value_name = "DEG,...")]
    pub theta_i: Option<String>,
    /// θr step of the inplane layout, degrees.
    #[arg(long, value_name = "DEG")]
    pub step: Option<f64>,
    /// Largest |θr| of the inplane layout, degrees.
    #[arg(long, value_name = "DEG")]
    pub theta_r_max: Option<f64>,
    /// Keep only N samples, spread evenly over the layout order (every θi is kept).
    #[arg(long, value_name = "N")]
    pub samples: Option<usize>,
    /// Noise level ε (0 gives the exact model values).
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Noise shape: relative L(1+εz), absolute L+ε·max(L)·z, poisson L+ε·√(L·max L)·z.
    #[arg(long, value_enum, default_value_t = NoiseKindArg::Relative)]
    pub noise_kind: NoiseKindArg,
    /// Seed of the noise generator (same seed, same file).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Add a sigma_L column: the standard deviation of each value's noise.
    #[arg(long)]
    pub write_sigma: bool,
    /// Add a wavelength column (always written for the KBS models, whose σ and T are in
    /// its unit, so that `goniofit fit` reads λ from the file; `--no-wavelength` omits it).
    #[arg(long)]
    pub write_wavelength: bool,
    /// Omit the wavelength column even for a KBS model.
    #[arg(long, conflicts_with = "write_wavelength")]
    pub no_wavelength: bool,
    /// Write φr = 180° rows as signed θr < 0 at φr = 0.
    #[arg(long)]
    pub signed_theta_r: bool,
    /// KBS evaluation mode.
    #[arg(long, value_enum, default_value_t = ModeArg::Auto)]
    pub mode: ModeArg,
    /// KBS relative tolerance.
    #[arg(long, default_value = "1e-10")]
    pub tol: f64,
    /// Patch half-sizes X,Y (unit of λ): include the coherent term with A = 4XY.
    #[arg(long, value_name = "X,Y")]
    pub patch: Option<String>,
    /// Fresnel and shadowing factors on the KBS lobe.
    #[command(flatten)]
    pub factors: super::args::FactorArgs,
    /// Measured quantity: radiance, or BRDF = radiance / cos θi.
    #[arg(long, value_enum, default_value_t = QuantityArg::Radiance)]
    pub quantity: QuantityArg,
    /// Output CSV (default: standard output).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Truth JSON (default: beside --out, data.csv → data.truth.json).
    #[arg(long)]
    pub truth: Option<PathBuf>,
}

const AFTER_HELP: &str = "\
Layouts (angles in degrees; the CSV stores exactly these numbers):
  inplane     θr = k·step, |θr| ≤ max, at each θi; θr < 0 is written as |θr| at φr = 180
              (or as signed θr at φr = 0 with --signed-theta-r)
  hemisphere  θi: NI cell midpoints of [0, 90); θr: NR midpoints of (0, 90);
              φr: NP points -180 + 360·l/NP in [-180, 180)
  grazing     as hemisphere, θi evenly from 70 to 89 inclusive
  FILE.csv    header with theta_i,theta_r,phi_r (any order, extra columns ignored)
  --layout also takes sizes inline: 'hemisphere 10x30x60', 'inplane theta_i=30,60 max=80 step=0.5'.

Noise (z ~ N(0,1) per sample, M = largest |L| of the data set; sigma_L is the std. dev.):
  relative  L·(1 + ε·z)          sigma_L = ε·|L|
  absolute  L + ε·M·z            sigma_L = ε·M   (ε is a fraction of the peak)
  poisson   L + ε·√(|L|·M)·z     sigma_L = ε·√(|L|·M)
  Values are not clipped at 0. The same seed gives the same file.

Examples:
  goniofit synth --model kbs --params sigma=0.3,T=2,scale=1 --noise 0.01 --seed 1 --out data.csv
  goniofit synth --model lambert --params scale=1 --layout inplane --signed-theta-r --noise 0.02 \\
      --noise-kind absolute --write-sigma --out scan.csv";

#[derive(Debug, Clone, Copy, ValueEnum)]
pub(crate) enum NoiseKindArg {
    Relative,
    Absolute,
    Poisson,
}

fn usage(m: String) -> anyhow::Error {
    crate::error::Error::Usage(m).into()
}

/// Comma-separated numbers.
fn parse_list(text: &str, what: &str) -> anyhow::Result<Vec<f64>> {
    text.split(',')
        .map(|s| {
            s.trim()
                .parse::<f64>()
                .map_err(|_| usage(format!("{what}: '{}' is not a number", s.trim())))
        })
        .collect()
}

/// The layout from `--layout` and its modifiers; inplane-only and grid-only flags are
/// refused for other layouts rather than ignored.
fn build_layout(a: &SynthArgs) -> anyhow::Result<Layout> {
    let mut layout = Layout::parse(&a.layout)?;
    if let Some(g) = &a.grid {
        let (ni, nr, np) = synth::parse_grid(g)?;
        layout = layout.with_grid(ni, nr, np).map_err(|_| {
            usage(format!(
                "--grid applies to the hemisphere and grazing layouts, not '{}'",
                a.layout
            ))
        })?;
    }
    let inplane_flags = a.theta_i.is_some() || a.step.is_some() || a.theta_r_max.is_some();
    if inplane_flags {
        match &mut layout {
            Layout::InPlane {
                theta_i_deg,
                step_deg,
                theta_r_max_deg,
            } => {
                if let Some(t) = &a.theta_i {
                    *theta_i_deg = parse_list(t, "--theta-i")?;
                }
                if let Some(s) = a.step {
                    *step_deg = s;
                }
                if let Some(m) = a.theta_r_max {
                    *theta_r_max_deg = m;
                }
            }
            _ => {
                return Err(usage(format!(
                    "--theta-i, --step and --theta-r-max apply to the inplane layout, not '{}'",
                    a.layout
                )))
            }
        }
    }
    layout.validate()?;
    Ok(layout)
}

/// `goniofit synth`: evaluate the model on the layout, add the seeded noise, write the CSV
/// (to `--out` or standard output) and the truth JSON; exit code 0.
pub(crate) fn run(a: SynthArgs) -> anyhow::Result<u8> {
    let patch = a.patch.as_deref().map(parse_patch).transpose()?;
    let opts = a.factors.apply(settings::model_options(
        Front::Cli,
        a.mode.into(),
        a.tol,
        patch,
    )?);
    let model = by_name(&a.model, &opts)?;
    let params = parse_params(model.as_ref(), &a.params)?;
    let layout = build_layout(&a)?;
    let mut angles = layout.angles();
    if let Some(n) = a.samples {
        angles = synth::subsample(&angles, n)?;
    }
    let quantity: Quantity = a.quantity.into();
    let noise = a.noise();
    warn_accuracy(model.as_ref(), &params, &angles, a.wavelength.0, quantity);
    let data = synth::generate(
        model.as_ref(),
        &params,
        &angles,
        a.wavelength.0,
        quantity,
        &noise,
    )?;
    let mut csv_bytes = Vec::new();
    data.write_csv(&mut csv_bytes, &a.csv_options())
        .context("formatting the CSV")?;
    let truth = Truth {
        model: model.name().to_string(),
        params: Truth::params_by_name(model.as_ref(), &params),
        wavelength: a.wavelength.0,
        wavelength_unit: a.wavelength.1.map(String::from),
        quantity,
        mode: synth::eval_mode_name(opts.mode).to_string(),
        tol: a.tol,
        patch,
        fresnel: opts.fresnel,
        shadowing: opts.shadowing,
        layout: match &layout {
            Layout::Angles(_) => a.layout.clone(),
            l => l.describe(),
        },
        subsample: a.samples,
        noise,
        n: data.len(),
        signed_theta_r: a.signed_theta_r,
        data: a
            .out
            .as_deref()
            .and_then(Path::file_name)
            .map_or_else(|| "-".into(), |f| f.to_string_lossy().into_owned()),
        goniofit_version: env!("CARGO_PKG_VERSION").to_string(),
    };
    write_outputs(&a, &csv_bytes, &truth, data.len())?;
    Ok(0)
}

/// Prints the model's accuracy warnings for these parameters on these angles (one
/// `goniofit: warning:` line each, to standard error); nothing when the angles do not form
/// a valid geometry (generation then reports the problem).
fn warn_accuracy(
    model: &dyn Model,
    params: &[f64],
    angles: &[synth::AnglesDeg],
    wavelength: f64,
    quantity: Quantity,
) {
    let samples: Vec<_> = angles.iter().map(synth::AnglesDeg::sample).collect();
    if let Ok(geo) = crate::geometry::Geometry::new(&samples, &[wavelength], quantity) {
        for w in crate::model::domain::accuracy_warnings(model, params, &geo) {
            eprintln!("goniofit: warning: {w}");
        }
    }
}

/// Writes the CSV to `--out` (standard output without it) and the truth JSON (pretty,
/// newline-terminated) where [`SynthArgs::truth_file`] says, both atomically; with `--out`,
/// one line on standard error naming the files and the number of samples `n`.
fn write_outputs(a: &SynthArgs, csv_bytes: &[u8], truth: &Truth, n: usize) -> anyhow::Result<()> {
    let truth_file = a.truth_file();
    let out_path = a.out.clone().unwrap_or_else(|| PathBuf::from("-"));
    io::write_bytes(&out_path, csv_bytes)?;
    if let Some(tp) = &truth_file {
        let mut json = serde_json::to_vec_pretty(truth).context("formatting the truth JSON")?;
        json.push(b'\n');
        io::write_bytes(tp, &json)?;
    }
    if let Some(path) = &a.out {
        eprintln!(
            "goniofit synth: wrote {} samples to {}{}",
            n,
            crate::io::shown(path),
            truth_file
                .as_ref()
                .map(|t| format!(" (truth: {})", crate::io::shown(t)))
                .unwrap_or_default()
        );
    }
    Ok(())
}

impl SynthArgs {
    /// The noise of `--noise`, `--noise-kind` and `--seed`.
    fn noise(&self) -> Noise {
        Noise {
            kind: match self.noise_kind {
                NoiseKindArg::Relative => NoiseKind::Relative,
                NoiseKindArg::Absolute => NoiseKind::Absolute,
                NoiseKindArg::Poisson => NoiseKind::Poisson,
            },
            level: self.noise,
            seed: self.seed,
        }
    }

    /// The CSV's optional columns: `sigma_L` with `--write-sigma`; `wavelength` with
    /// `--write-wavelength` or for a KBS model unless `--no-wavelength`; signed θr with
    /// `--signed-theta-r`.
    fn csv_options(&self) -> CsvOptions {
        CsvOptions {
            sigma: self.write_sigma,
            wavelength: self.write_wavelength
                || (!self.no_wavelength && self.model.to_ascii_lowercase().starts_with("kbs")),
            signed_theta_r: self.signed_theta_r,
        }
    }

    /// The truth JSON's path: `--truth`, else beside `--out` (none without either).
    fn truth_file(&self) -> Option<PathBuf> {
        self.truth
            .clone()
            .or_else(|| self.out.as_deref().map(synth::truth_path))
    }

    /// The layout file (when `--layout` names one); the CSV to `--out` or standard output,
    /// and the truth JSON.
    pub(crate) fn files(&self) -> FileSet {
        let mut set = FileSet::new();
        if let Some(layout) = Layout::file_of(&self.layout) {
            set = set.input("--layout", layout);
        }
        set = match &self.out {
            Some(out) => set.output("--out", out),
            None => set.stdout(),
        };
        let truth = self.truth_file();
        let option = if self.truth.is_some() {
            "--truth"
        } else {
            "the truth file"
        };
        set.output_opt(option, truth.as_deref())
    }
}
