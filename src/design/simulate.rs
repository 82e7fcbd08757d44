//! The check of the linearised figures by simulation: noisy measurements drawn at the
//! measured and proposed geometries from the scene's model and noise, each fitted as
//! `goniofit fit` would, and the scatter of the estimates taken as the realised standard
//! error. Where a quantity's profile is far from quadratic (σ along the rough ridge) the
//! two differ, and the simulation is the one to believe.

use super::{Estimate, QuantityDef, Scene};
use crate::error::{Error, Result};
use crate::fit::driver::{self, FitConfig, FitInput};
use crate::fit::problem::{Channels, ResidualKind};
use crate::geometry::{Geometry, PerSample, Sample};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

/// What the simulated measurements gave.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Simulation {
    /// Measurements simulated.
    pub draws: usize,
    /// Fits that ended at finite values inside the domain (their estimates are the
    /// scatter's); the others are counted in `failed`.
    pub used: usize,
    /// Draws whose fit returned an error or ended at a non-finite or non-positive value
    /// (`draws` − `used`; left out of `spread`).
    pub failed: usize,
    /// Fits that did not converge (among `used`).
    pub not_converged: usize,
    /// Every quantity with the scatter of its estimates as the standard error (for the
    /// positive quantities: the standard deviation of ln estimate, times the true value).
    pub spread: Vec<Estimate>,
}

/// The fit settings of a simulated measurement: the scene's model and residual kind,
/// started at the truth, with no reduction to determined combinations (the estimate of
/// every parameter is the least-squares one, wherever the data leaves it).
pub(crate) fn fit_config(scene: &Scene) -> FitConfig {
    FitConfig {
        model: scene.model.name().to_string(),
        model_opts: scene.model.options().unwrap_or_default(),
        residual: scene.noise.kind,
        init: scene
            .model
            .params()
            .iter()
            .zip(&scene.params)
            .map(|(s, &v)| (s.name.to_string(), v))
            .collect(),
        reduce: false,
        ..FitConfig::default()
    }
}

/// A noisy measurement of values `f` under the scene's noise model, from `seed`.
fn noisy(f: &[f64], scene: &Scene, seed: u64) -> Vec<f64> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let eps = scene.noise.level;
    f.iter()
        .map(|&v| {
            let z: f64 = StandardNormal.sample(&mut rng);
            match scene.noise.kind {
                ResidualKind::Absolute => v + eps * z,
                ResidualKind::Relative => v * (1.0 + eps * z),
                ResidualKind::Log => v * (eps * z).exp(),
            }
        })
        .collect()
}

/// Simulate `draws` measurements at `samples` (the measured and the proposed geometries)
/// with seeds `seed`, `seed + 1`, …, fit each ([`fit_config`], or `config` when given) and
/// return the scatter of the estimates of every quantity in `defs`. Errors: no draws, or
/// geometry outside the valid domain.
pub(crate) fn simulate(
    scene: &Scene,
    samples: &[Sample],
    defs: &[QuantityDef],
    draws: usize,
    seed: u64,
    config: Option<&FitConfig>,
) -> Result<Simulation> {
    if draws < 2 {
        return Err(Error::Usage(format!(
            "--simulate {draws}: at least 2 simulated measurements are needed for a scatter"
        )));
    }
    let geo = Geometry::new(samples, &[scene.wavelength], scene.quantity)?;
    let mut exact = vec![0.0; geo.len()];
    scene.model.eval(&geo, &scene.params, &mut exact, None);
    let config = config.cloned().unwrap_or_else(|| fit_config(scene));
    let fits: Vec<Option<(Vec<f64>, bool)>> = (0..draws)
        .into_par_iter()
        .map(|k| {
            let y = noisy(&exact, scene, seed.wrapping_add(k as u64));
            let input = FitInput {
                geo: geo.clone(),
                y: y.into(),
                weight: PerSample::One {
                    value: 1.0,
                    len: samples.len(),
                },
                channel: Channels::single(samples.len()),
                channel_names: vec![String::new()],
            };
            let r = driver::fit_model(scene.model, &input, &config).ok()?;
            let ok = r.values.len() == scene.params.len()
                && r.values.iter().all(|v| v.is_finite() && *v > 0.0);
            let converged = r.converged();
            ok.then_some((r.values, converged))
        })
        .collect();
    let used: Vec<&(Vec<f64>, bool)> = fits.iter().flatten().collect();
    let spread = defs.iter().map(|d| scatter(d, &used)).collect();
    Ok(Simulation {
        draws,
        used: used.len(),
        failed: draws - used.len(),
        not_converged: used.iter().filter(|u| !u.1).count(),
        spread,
    })
}

/// The simulations of a design (see `simulate`, `draws` fits each, both with `seed`):
/// at the measured geometries alone (None unless they outnumber the parameters), and at
/// the measured and the `chosen` geometries (θi, θr, φr in degrees) together.
pub fn before_and_after(
    scene: &Scene,
    existing: &[Sample],
    chosen: &[[f64; 3]],
    draws: usize,
    seed: u64,
    config: Option<&FitConfig>,
) -> Result<(Option<Simulation>, Simulation)> {
    let defs = super::quantities(scene.model, &scene.params);
    let before = if existing.len() > scene.params.len() {
        Some(simulate(scene, existing, &defs, draws, seed, config)?)
    } else {
        None
    };
    let mut samples = existing.to_vec();
    samples.extend(
        chosen
            .iter()
            .map(|c| Sample::from_degrees(c[0], c[1], c[2])),
    );
    let after = simulate(scene, &samples, &defs, draws, seed, config)?;
    Ok((before, after))
}

/// The standard deviation of a quantity's design variable cᵀx̂ over the fits, as an
/// [`Estimate`] at the true value.
fn scatter(d: &QuantityDef, fits: &[&(Vec<f64>, bool)]) -> Estimate {
    let x: Vec<f64> = fits
        .iter()
        .map(|(p, _)| {
            p.iter()
                .zip(d.coef.iter())
                .map(|(v, c)| if d.log { c * v.ln() } else { c * v })
                .sum::<f64>()
        })
        .collect();
    let n = x.len() as f64;
    let sd = if x.len() >= 2 {
        let mean = x.iter().sum::<f64>() / n;
        (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        f64::NAN
    };
    let relative = if d.log { sd } else { sd / d.value.abs() };
    Estimate::of_relative(d, Some(relative))
}
