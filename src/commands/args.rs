//! Command-line argument types shared by several subcommands.

use crate::fit::problem::loss::LossKind;
use crate::geometry::Quantity;
use crate::model::fresnel::Fresnel;
use crate::model::shadowing::Shadowing;
use crate::model::{EvalMode, ModelOptions};
use clap::ValueEnum;

/// A wavelength on the command line: the number and its unit (`nm`, `µm`), or no unit for
/// a bare number (then it is in the unit of σ and T, whatever that is).
pub(crate) type Wavelength = (f64, Option<&'static str>);

/// `--wavelength` of every command: a positive number with an optional unit (`633nm`,
/// `633 nm`, `0.633um`, `0.633µm`) or a bare number ([`crate::io::parse_length`]).
pub(crate) fn parse_wavelength(text: &str) -> Result<Wavelength, String> {
    crate::io::parse_length(text).map_err(|e| e.to_string())
}

/// The measured quantity, as chosen on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum QuantityArg {
    /// Radiance L = s cos²θi ⟨|ρ|²⟩ (eq. 28).
    #[default]
    Radiance,
    /// BRDF = L / cos θi.
    Brdf,
}

impl From<QuantityArg> for Quantity {
    fn from(q: QuantityArg) -> Self {
        match q {
            QuantityArg::Radiance => Quantity::Radiance,
            QuantityArg::Brdf => Quantity::Brdf,
        }
    }
}

/// The KBS evaluation mode, as chosen on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum ModeArg {
    /// Per sample, the cheapest evaluation that meets the tolerance.
    #[default]
    Auto,
    /// Always the series.
    Series,
    /// Always the smooth approximation (eq. 42).
    Smooth,
    /// Always the rough approximation (eq. 43).
    Rough,
}

impl From<ModeArg> for EvalMode {
    fn from(m: ModeArg) -> Self {
        match m {
            ModeArg::Auto => EvalMode::Auto,
            ModeArg::Series => EvalMode::Series,
            ModeArg::Smooth => EvalMode::Smooth,
            ModeArg::Rough => EvalMode::Rough,
        }
    }
}

/// The robust loss, as chosen on the command line (scipy's names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum LossArg {
    /// ρ(z) = z: plain least squares.
    #[default]
    Linear,
    /// ρ(z) = 2(√(1+z) − 1): a smooth l1, usually the first robust choice.
    #[value(name = "soft_l1", alias = "soft-l1")]
    SoftL1,
    /// ρ(z) = z up to z = 1, 2√z − 1 beyond.
    Huber,
    /// ρ(z) = ln(1+z): outliers weakened strongly; more local minima.
    Cauchy,
    /// ρ(z) = arctan z: a sample's cost is bounded.
    Arctan,
}

impl From<LossArg> for LossKind {
    fn from(l: LossArg) -> Self {
        match l {
            LossArg::Linear => LossKind::Linear,
            LossArg::SoftL1 => LossKind::SoftL1,
            LossArg::Huber => LossKind::Huber,
            LossArg::Cauchy => LossKind::Cauchy,
            LossArg::Arctan => LossKind::Arctan,
        }
    }
}

/// Parse `X,Y` patch half-sizes.
pub(crate) fn parse_patch(text: &str) -> crate::error::Result<(f64, f64)> {
    let bad = || {
        crate::error::Error::Usage(format!(
            "--patch '{text}': expected two positive numbers X,Y"
        ))
    };
    let (x, y) = text.split_once(',').ok_or_else(bad)?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    let y: f64 = y.trim().parse().map_err(|_| bad())?;
    if !(x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0) {
        return Err(bad());
    }
    Ok((x, y))
}

/// `--fresnel` and `--shadowing`: the factors on the KBS lobe (fit, eval, synth, render).
#[derive(Debug, Clone, Copy, Default, clap::Args)]
pub(crate) struct FactorArgs {
    /// Fresnel factor on the KBS lobe, normalised at normal incidence: dielectric (parameter
    /// n), conductor (n, kappa), schlick (n), or none (the paper's model).
    #[arg(long, value_enum, default_value = "none")]
    pub fresnel: FresnelArg,
    /// Shadowing–masking on the KBS lobe: Smith's G for the Gaussian slopes of T/σ
    /// (smith: G1(θi) G1(θr); smith-correlated: 1/(1 + Λi + Λr)), or none.
    #[arg(long, value_enum, default_value = "none")]
    pub shadowing: ShadowingArg,
}

impl FactorArgs {
    /// `opts` with these factors.
    pub(crate) fn apply(self, opts: ModelOptions) -> ModelOptions {
        ModelOptions {
            fresnel: self.fresnel.into(),
            shadowing: self.shadowing.into(),
            ..opts
        }
    }
}

/// `--fresnel`, as chosen on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum FresnelArg {
    #[default]
    None,
    Dielectric,
    Conductor,
    Schlick,
}

impl From<FresnelArg> for Fresnel {
    fn from(f: FresnelArg) -> Self {
        match f {
            FresnelArg::None => Fresnel::None,
            FresnelArg::Dielectric => Fresnel::Dielectric,
            FresnelArg::Conductor => Fresnel::Conductor,
            FresnelArg::Schlick => Fresnel::Schlick,
        }
    }
}

/// `--shadowing`, as chosen on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, ValueEnum)]
pub enum ShadowingArg {
    #[default]
    None,
    Smith,
    SmithCorrelated,
}

impl From<ShadowingArg> for Shadowing {
    fn from(s: ShadowingArg) -> Self {
        match s {
            ShadowingArg::None => Shadowing::None,
            ShadowingArg::Smith => Shadowing::Smith,
            ShadowingArg::SmithCorrelated => Shadowing::SmithCorrelated,
        }
    }
}

/// The read options of a command that reads one table (`eval`, `convert`): its `--columns`
/// mappings parsed, its angle flags, channel and MERL subsampling; `require_value`: whether the value column
/// `L` must be there.
pub(crate) fn table_read_options(
    columns: &[String],
    (radians, signed_theta_r): (bool, bool),
    (channel, subsample): (Option<String>, usize),
    require_value: bool,
) -> anyhow::Result<crate::io::ReadOptions> {
    let mut parsed = Vec::new();
    for c in columns {
        parsed.extend(crate::io::csv::parse_columns(c)?);
    }
    Ok(crate::io::ReadOptions {
        radians,
        signed_theta_r,
        columns: parsed,
        require_value,
        channel,
        subsample,
    })
}

/// The files of a command that reads `file` and writes one table to `out` (standard output
/// when none).
pub(crate) fn table_files(
    file: &std::path::Path,
    out: Option<&std::path::Path>,
) -> crate::io::FileSet {
    let set = crate::io::FileSet::new().input("input", file);
    match out {
        Some(out) => set.output("--out", out),
        None => set.stdout(),
    }
}
