//! Command-line argument types shared by several subcommands.

use clap::ValueEnum;
use goniofit::geometry::Quantity;
use goniofit::model::EvalMode;

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

/// Parse `X,Y` patch half-sizes.
pub fn parse_patch(text: &str) -> goniofit::Result<(f64, f64)> {
    let bad = || {
        goniofit::Error::Usage(format!(
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
