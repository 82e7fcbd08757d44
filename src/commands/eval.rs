//! `goniofit eval`: a model's values at the angles of a CSV (or ASTM) file.
//!
//! Prints the input rows — every original column, original header names — with a column
//! `L_model` appended (or, when the input already has an `L_model` column, e.g. an earlier
//! eval's output, that column's values replaced). Values are written with full precision: the shortest decimal that
//! parses back to the same `f64`, in scientific notation (`1.2345678901234567e-3`).
//!
//! Wavelength: the KBS models need one. `--wavelength` sets it for every sample (and then
//! overrides a wavelength column or ASTM channel wavelengths); without it the file's
//! per-sample wavelengths are used; with neither, a KBS model is an error. Lambertian and
//! specular models do not depend on λ.

use super::args::{parse_patch, ModeArg, QuantityArg};
use crate::geometry::Geometry;
use crate::io::{self, FileSet};
use crate::model;
use crate::settings::{self, Front};
use anyhow::Context;
use clap::Args;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct EvalArgs {
    /// Model name: kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert, lambert-specular.
    #[arg(long)]
    pub model: String,
    /// Parameters as name=value pairs, e.g. sigma=0.3,T=2,scale=1.
    #[arg(long)]
    pub params: String,
    /// Wavelength for every sample, with its unit (633nm, 0.633um) or as a bare number (the
    /// unit of sigma and T); overrides the file's.
    #[arg(long, allow_hyphen_values = true, value_parser = super::args::parse_wavelength)]
    pub wavelength: Option<super::args::Wavelength>,
    /// Output quantity.
    #[arg(long, value_enum, default_value_t = QuantityArg::Radiance)]
    pub quantity: QuantityArg,
    /// Patch half-sizes X,Y (unit of λ): adds the coherent term ρ0² with A = 4XY.
    #[arg(long, value_name = "X,Y")]
    pub patch: Option<String>,
    /// Fresnel and shadowing factors on the KBS lobe.
    #[command(flatten)]
    pub factors: super::args::FactorArgs,
    /// KBS evaluation mode.
    #[arg(long, value_enum, default_value_t = ModeArg::Auto)]
    pub mode: ModeArg,
    /// Relative accuracy target of the KBS sum.
    #[arg(long, default_value = "1e-10")]
    pub tol: f64,
    /// Angles are in radians (CSV; ASTM files are always radians).
    #[arg(long)]
    pub radians: bool,
    /// θr < 0 means θr = |θr| at φr + 180° (signed in-plane view angles).
    #[arg(long)]
    pub signed_theta_r: bool,
    /// Column mappings role=name,... (roles: theta_i, theta_r, phi_r, L, weight, sigma_L,
    /// wavelength, group).
    #[arg(long, value_name = "ROLE=NAME,...")]
    pub columns: Vec<String>,
    /// ASTM files: the channel to read (e.g. 550nm), or `all`.
    #[arg(long)]
    pub channel: Option<String>,
    /// Write the table to this file (atomically) instead of stdout.
    #[arg(long, short = 'o', value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Input CSV with columns theta_i, theta_r, phi_r (others are passed through), or an
    /// ASTM E1392 file.
    pub file: PathBuf,
}

impl EvalArgs {
    /// The input file; the table to `--out` or standard output.
    pub(crate) fn files(&self) -> FileSet {
        super::args::table_files(&self.file, self.out.as_deref())
    }
}

pub(crate) fn run(args: EvalArgs) -> anyhow::Result<u8> {
    let opts = super::args::table_read_options(
        &args.columns,
        (args.radians, args.signed_theta_r),
        (args.channel.clone(), 1),
        false,
    )?;
    let patch = args.patch.as_deref().map(parse_patch).transpose()?;
    let mopts = args.factors.apply(settings::model_options(
        Front::Cli,
        args.mode.into(),
        args.tol,
        patch,
    )?);
    let model = model::by_name(&args.model, &mopts)?;
    let params = model::parse_params(model.as_ref(), &args.params)?;

    let out = args.out.clone().unwrap_or_else(|| PathBuf::from("-"));
    let ds = io::read_dataset(&args.file, &opts)?;

    let needs_wavelength =
        model.name().starts_with("kbs") || args.model.to_ascii_lowercase().starts_with("kbs");
    let wavelength: Vec<f64> = match (args.wavelength.map(|w| w.0), &ds.wavelength) {
        (Some(l), _) => {
            if !(l.is_finite() && l > 0.0) {
                return Err(crate::error::Error::Usage(format!(
                    "--wavelength {l} must be finite and positive"
                ))
                .into());
            }
            vec![l]
        }
        (None, Some(w)) => w.clone(),
        (None, None) if needs_wavelength => {
            return Err(crate::error::Error::Usage(format!(
                "model {} needs a wavelength: give --wavelength L (the unit of sigma and T) or a wavelength column in {}",
                args.model,
                crate::io::shown(&args.file)
            ))
            .into())
        }
        (None, None) => vec![1.0],
    };

    let geo = Geometry::new(&ds.samples, &wavelength, args.quantity.into())
        .with_context(|| format!("preparing the samples of {}", crate::io::shown(&args.file)))?;
    for w in model::domain::accuracy_warnings(model.as_ref(), &params, &geo) {
        eprintln!("goniofit: warning: {w}");
    }
    let values = model::domain::evaluate_checked(model.as_ref(), &params, &geo)?;

    // Append L_model; a file that already has one (an earlier eval's output) gets it replaced.
    let mut headers = ds.headers.clone();
    let existing = headers.iter().position(|h| h == "L_model");
    if existing.is_none() {
        headers.push("L_model".into());
    }
    let rows: Vec<Vec<String>> = ds
        .rows
        .iter()
        .zip(&values)
        .map(|(r, v)| {
            let mut r = r.clone();
            match existing {
                Some(j) => r[j] = io::format_value(*v),
                None => r.push(io::format_value(*v)),
            }
            r
        })
        .collect();
    io::write_csv(&out, &headers, &rows)?;
    Ok(0)
}
