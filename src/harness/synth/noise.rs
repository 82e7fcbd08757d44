//! Seeded, reproducible noise on exact values (the formulas are in the module
//! documentation of [`crate::harness::synth`]).

use crate::error::{Error, Result};
use crate::model::domain::short_number;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

/// The shape of the noise (see the module documentation for the formulas).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NoiseKind {
    /// L (1 + ε z): constant relative error.
    #[default]
    Relative,
    /// L + ε max|L| z: constant error, ε a fraction of the peak value.
    Absolute,
    /// L + ε √(|L| max|L|) z: Poisson-like, variance ∝ L.
    Poisson,
}

impl NoiseKind {
    /// Lower-case name (`relative`, `absolute`, `poisson`).
    pub fn name(self) -> &'static str {
        match self {
            NoiseKind::Relative => "relative",
            NoiseKind::Absolute => "absolute",
            NoiseKind::Poisson => "poisson",
        }
    }
}

/// Seeded noise: kind, level ε ≥ 0 and seed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Noise {
    /// The shape: relative, absolute or Poisson-like.
    pub kind: NoiseKind,
    /// The level ε ≥ 0: a fraction of L (relative), of the peak max|L| (absolute), or of √(|L|
    /// max|L|) (Poisson-like); 0 gives the exact values.
    pub level: f64,
    /// Seed of the `StdRng` that draws the standard normal z of every value, in order.
    pub seed: u64,
}

impl Noise {
    /// No noise: the exact model values.
    pub fn none() -> Noise {
        Noise {
            kind: NoiseKind::Relative,
            level: 0.0,
            seed: 0,
        }
    }
}

/// Noisy values and their standard deviations (one per exact value).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Noisy {
    /// The noisy values, in the unit of the exact ones.
    pub value: Vec<f64>,
    /// The standard deviation σ_L of each value's noise (0 everywhere without noise).
    pub sigma_l: Vec<f64>,
}

/// Add seeded noise to `exact` (see the module documentation). `level` must be finite and
/// ≥ 0; with `level = 0` the values are `exact` bit for bit and every σ_L is 0.
pub(crate) fn add_noise(exact: &[f64], noise: &Noise) -> Result<Noisy> {
    if !(noise.level.is_finite() && noise.level >= 0.0) {
        return Err(Error::Usage(format!(
            "noise level {} must be finite and non-negative",
            noise.level
        )));
    }
    if noise.level == 0.0 {
        return Ok(Noisy {
            value: exact.to_vec(),
            sigma_l: vec![0.0; exact.len()],
        });
    }
    let eps = noise.level;
    let peak = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut rng = rand::rngs::StdRng::seed_from_u64(noise.seed);
    let mut value = Vec::with_capacity(exact.len());
    let mut sigma_l = Vec::with_capacity(exact.len());
    for &l in exact {
        let z: f64 = StandardNormal.sample(&mut rng);
        let sd = match noise.kind {
            NoiseKind::Relative => eps * l.abs(),
            NoiseKind::Absolute => eps * peak,
            NoiseKind::Poisson => eps * (l.abs() * peak).sqrt(),
        };
        value.push(match noise.kind {
            // Written as L(1 + εz) so that the relative error is exactly εz.
            NoiseKind::Relative => l * (1.0 + eps * z),
            _ => l + sd * z,
        });
        sigma_l.push(sd);
    }
    let bad = (0..value.len()).find(|&i| !(value[i].is_finite() && sigma_l[i].is_finite()));
    if let Some(i) = bad {
        return Err(Error::Usage(format!(
            "noise level {} overflows double precision: sample {} would get the value {} (standard deviation {}) from the exact {}; give a smaller --noise",
            short_number(eps),
            i + 1,
            short_number(value[i]),
            short_number(sigma_l[i]),
            short_number(exact[i])
        )));
    }
    Ok(Noisy { value, sigma_l })
}
