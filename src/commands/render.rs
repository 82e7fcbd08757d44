//! `goniofit render sphere`: a sphere lit from one side, each pixel's radiance from a model.

use crate::io::FileSet;
use crate::model::{by_name, parse_params, ModelOptions};
use crate::plot::sphere::{sphere_radiance, SpherePicture};
use crate::plot::write_picture;
use anyhow::Context;
use clap::{Args, Subcommand};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub(crate) struct RenderArgs {
    #[command(subcommand)]
    pub what: RenderWhat,
}

#[derive(Debug, Subcommand)]
pub(crate) enum RenderWhat {
    /// A sphere viewed along +z, lit from --light-deg off the view on the −x side; writes
    /// a PNG or SVG (by the extension of --out), brightness = L / L_max.
    Sphere(SphereArgs),
}

#[derive(Debug, Args)]
pub(crate) struct SphereArgs {
    /// Model name: kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert, lambert-specular.
    #[arg(long)]
    pub model: String,
    /// Parameters as name=value pairs, e.g. sigma=1,T=5,scale=1.
    #[arg(long)]
    pub params: String,
    /// Angle of the light from the view direction (degrees, 0–90), in the xz-plane on the −x side.
    #[arg(long, default_value_t = 45.0)]
    pub light_deg: f64,
    /// Image width = height in pixels.
    #[arg(long, default_value_t = 256)]
    pub size: u32,
    /// Wavelength, with its unit (633nm, 0.633um) or as a bare number, in the unit of sigma
    /// and T.
    #[arg(long, default_value = "1", allow_hyphen_values = true, value_parser = super::args::parse_wavelength)]
    pub wavelength: super::args::Wavelength,
    /// Draw a negative (darker = more light), as in the paper's Figure 4.
    #[arg(long)]
    pub negative: bool,
    /// Mark the view (+), light (x) and specular (o) directions.
    #[arg(long)]
    pub marks: bool,
    /// Output file, .png or .svg.
    #[arg(long)]
    pub out: PathBuf,
    /// Fresnel and shadowing factors on the KBS lobe.
    #[command(flatten)]
    pub factors: super::args::FactorArgs,
}

impl RenderArgs {
    /// The picture at `--out`, and its name printed on standard output.
    pub(crate) fn files(&self) -> FileSet {
        match &self.what {
            RenderWhat::Sphere(a) => FileSet::new().output("--out", &a.out).stdout(),
        }
    }
}

pub(crate) fn run(args: RenderArgs) -> anyhow::Result<u8> {
    match args.what {
        RenderWhat::Sphere(a) => sphere(a),
    }
}

fn sphere(a: SphereArgs) -> anyhow::Result<u8> {
    let model = by_name(&a.model, &a.factors.apply(ModelOptions::default()))?;
    let params = parse_params(model.as_ref(), &a.params)?;
    let image = sphere_radiance(model.as_ref(), &params, a.light_deg, a.wavelength.0, a.size)?;
    let pic = SpherePicture {
        image,
        negative: a.negative,
        marks: a.marks,
    };
    write_picture(&pic, &a.out).with_context(|| format!("writing {}", crate::io::shown(&a.out)))?;
    eprintln!(
        "goniofit: wrote {} ({}×{} px, a sphere lit from θ = {}°, model {} at {})",
        crate::io::shown(&a.out),
        a.size,
        a.size,
        a.light_deg,
        model.name(),
        crate::io::shown_text(&a.params)
    );
    crate::io::print_stdout(&format!("{}\n", crate::io::shown(&a.out)))?;
    Ok(0)
}
