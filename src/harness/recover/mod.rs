//! Synthetic recovery: draw KBS scenes across regimes, generate seeded noisy data with
//! [`crate::harness::synth::generate`], fit each with [`crate::fit::driver::fit`] from the default
//! (data-driven) starting values, and compare what the fit reports with the truth.
//!
//! For every scene only the quantities the fit says the data determines are scored
//! (docs/conventions.md, "Models"):
//!
//! | verdict | scored quantities | truth |
//! |---|---|---|
//! | `full` | σ, T, scale, T/σ | the drawn values |
//! | `rough` | T/σ, amplitude | T/σ, s·(T/σ)² |
//! | `smooth` | T, amplitude | T, s·(σ/λ)² |
//! | `partial` | every parameter or derived quantity marked determined | as above |
//!
//! Each scored quantity gives a relative error |v − t|/t and, when the fit reports a
//! standard error, whether the truth lies inside v ± 2·se. The fraction of such truths is
//! the *coverage*; for a calibrated fit it is close to 0.954 (a normal distribution's mass
//! within two standard deviations).
//!
//! Scenes are drawn by a seeded `StdRng`, so a (`scenes`, `seed`) pair always gives the same
//! scenes, data and — up to the parallel summation order inside the model — the same fits.
//! The data carry their noise standard deviations as weights 1/σ_L², as a user with a
//! `sigma_L` column would fit them.

use crate::error::{Error, Result};
use crate::fit::driver::{self, FitConfig, FitInput, FitResult, Verdict};
use crate::fit::problem::Channels;
use crate::fit::stats::adequacy::AdequacyVerdict;
use crate::geometry::median;
use crate::geometry::{Geometry, Quantity};
use crate::harness::synth::{self, Layout, Noise, NoiseKind};
use crate::model::fresnel::Fresnel;
use crate::model::shadowing::Shadowing;
use crate::model::{self, ModelOptions};
use goniofit_lm::{LmConfig, Stop, Termination};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::time::Duration;

pub(crate) mod outliers;
mod text;
pub(crate) use outliers::Outlier;

/// Two-sided normal coverage of ±2 standard errors.
pub(crate) const NOMINAL_COVERAGE: f64 = 0.9545;

/// Width of the coverage interval, in standard errors.
pub(crate) const COVERAGE_K: f64 = 2.0;

/// Where a scene lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum Regime {
    /// g ≪ 1 everywhere (σ/λ from 0.003 to 0.015).
    Smooth,
    /// g around 1 (σ/λ from 0.08 to 0.4): all of σ, T, scale are determined.
    Intermediate,
    /// g ≫ 1 everywhere (σ/λ from 4 to 10).
    Rough,
    /// Incidence from 70° to 89° (the grazing layout), intermediate roughness.
    Grazing,
}

impl Regime {
    /// All regimes, in report order.
    pub(crate) const ALL: [Regime; 4] = [
        Regime::Smooth,
        Regime::Intermediate,
        Regime::Rough,
        Regime::Grazing,
    ];

    /// Lower-case name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Regime::Smooth => "smooth",
            Regime::Intermediate => "intermediate",
            Regime::Rough => "rough",
            Regime::Grazing => "grazing",
        }
    }
}

/// One synthetic scene: truth, layout and noise.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct Scene {
    /// Index of the scene in the run's draw order (0-based); [`RecoverConfig::only`] selects
    /// scenes by it.
    pub id: usize,
    /// The regime, which follows from the id (smooth, intermediate, rough, grazing in turn).
    pub regime: Regime,
    /// Whether the layout is the sparse or the dense one.
    pub dense: bool,
    /// The layout as [`Layout::describe`] writes it.
    pub layout: String,
    /// True RMS height σ, in units of λ (the scene's wavelength is 1), drawn log-uniformly
    /// within the regime's range.
    pub sigma: f64,
    /// True correlation length T, in units of λ: σ times a ratio T/σ drawn log-uniformly from 2
    /// to 12, or (smooth scenes) T/λ drawn from 0.3 to 3.
    #[serde(rename = "T")]
    pub corr_len: f64,
    /// True scale factor s on the lobe, drawn log-uniformly from 0.1 to 10.
    pub scale: f64,
    /// Wavelength λ of the synthetic data: always 1, so σ and T are in units of λ.
    pub wavelength: f64,
    /// The noise on the exact values: level ε from the run's configuration, relative for even
    /// ids and Poisson-like for odd ones, with a seed drawn from the run's stream.
    pub noise: Noise,
    /// The factors on the lobe ([`RecoverConfig`]) and their truths: the index n (with a
    /// Fresnel factor) and κ (conductor).
    #[serde(skip_serializing_if = "is_default")]
    pub fresnel: Fresnel,
    /// The shadowing factor on the truth's and the fit's lobe (omitted from JSON when none).
    #[serde(skip_serializing_if = "is_default")]
    pub shadowing: Shadowing,
    /// True refractive index n with a Fresnel factor (None without one).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n: Option<f64>,
    /// True extinction coefficient κ with a conductor's Fresnel factor (None otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub kappa: Option<f64>,
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

impl Scene {
    /// The parameters of the scene's model: σ, T, scale, then n (and κ) with a Fresnel factor.
    fn model_options(&self) -> ModelOptions {
        ModelOptions {
            fresnel: self.fresnel,
            shadowing: self.shadowing,
            ..ModelOptions::default()
        }
    }

    fn params(&self) -> Vec<f64> {
        let mut p = vec![self.sigma, self.corr_len, self.scale];
        p.extend(self.n);
        p.extend(self.kappa);
        p
    }

    fn layout_value(&self) -> Result<Layout> {
        Layout::parse(&self.layout)
    }
}

/// One scored quantity of one scene.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct Check {
    /// Report name of the quantity (`sigma`, `T`, `scale`, `T/sigma`, `amplitude`, `n`,
    /// `kappa`).
    pub name: String,
    /// The scene's true value (for `amplitude`, s·(T/σ)² under a rough verdict, s·(σ/λ)²
    /// otherwise).
    pub truth: f64,
    /// The fitted (or derived) value the fit reports.
    pub value: f64,
    /// The standard error the fit reports, None when it reports none or a non-finite one.
    pub stderr: Option<f64>,
    /// |value − truth| / truth.
    pub rel_error: f64,
    /// Whether |value − truth| ≤ 2·stderr (None without a standard error).
    pub covered: Option<bool>,
}

/// The outcome of one scene.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct SceneResult {
    /// The scene that was fitted.
    pub scene: Scene,
    /// Number of samples of the scene's data (0 when the data could not be generated).
    pub n: usize,
    /// None when the fit returned an error (then `error` says why).
    pub termination: Option<Termination>,
    /// The fit's verdict on what the data determines (None when the fit returned an error).
    pub verdict: Option<Verdict>,
    /// Whether the solver converged ([`FitResult::converged`]); false on an error.
    pub converged: bool,
    /// Wall seconds of the fit ([`FitResult::seconds`]); 0 on an error.
    pub seconds: f64,
    /// The quantities scored against the truth ([`score`]); empty on an error.
    pub checks: Vec<Check>,
    /// The error message when the data generation or the fit failed, else None.
    pub error: Option<String>,
    /// The adequacy verdict of the fit (None when the fit returned an error) and the codes
    /// of its reasons: a correct model with correct weights should be flagged in at most
    /// [`crate::fit::stats::adequacy::ALPHA`] of the scenes.
    pub adequacy: Option<AdequacyVerdict>,
    /// Codes of the adequacy reasons of the fit (empty on an error).
    pub adequacy_reasons: Vec<String>,
    /// With a Fresnel factor: whether the fit says the data determines n (None without
    /// the factor, or when the fit failed).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub n_determined: Option<bool>,
}

/// Error statistics of one quantity within a regime.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct QuantitySummary {
    /// Report name of the quantity (see [`Check::name`]).
    pub name: String,
    /// Scenes in which it was scored.
    pub n: usize,
    /// Median of |value − truth|/truth over those scenes (NaN ignored; NaN if none).
    pub median_rel_error: f64,
    /// Largest relative error over those scenes (0 if none).
    pub max_rel_error: f64,
    /// Fraction covered among those with a standard error (None if none had one).
    pub coverage: Option<f64>,
    /// Number of those checks that had a standard error (the denominator of `coverage`).
    pub n_with_stderr: usize,
}

/// Summary of one regime.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct RegimeSummary {
    /// The regime summarised.
    pub regime: Regime,
    /// Number of scenes of the regime in the run.
    pub scenes: usize,
    /// Count of scenes per verdict name (`error` for a fit that returned an error).
    pub verdicts: BTreeMap<String, usize>,
    /// Count of scenes per termination (its `Debug` name, or `error`).
    pub terminations: BTreeMap<String, usize>,
    /// Per scored quantity, in the order σ, T, scale, T/σ, amplitude, n, κ, then others.
    pub quantities: Vec<QuantitySummary>,
    /// Fraction of scored truths (with a standard error) inside ±2 se.
    pub coverage: Option<f64>,
    /// Number of scored truths of the regime that had a standard error.
    pub n_with_stderr: usize,
    /// Median wall seconds of the regime's fits that returned no error (NaN if none did).
    pub median_seconds: f64,
    /// Number of the regime's scenes whose data generation or fit returned an error.
    pub errors: usize,
}

/// The whole recovery run.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct RecoverReport {
    /// Number of scenes fitted (those selected by `only`, or all).
    pub scenes: usize,
    /// Seed of the scene draws (the same seed gives the same scenes).
    pub seed: u64,
    /// Fraction of all scored truths (with a standard error) inside ±2 standard errors.
    pub coverage: f64,
    /// The expected coverage of ±2 standard errors ([`NOMINAL_COVERAGE`]).
    pub nominal_coverage: f64,
    /// Number of scored truths (over all scenes) that had a standard error.
    pub n_with_stderr: usize,
    /// Count of scenes per termination (its `Debug` name, or `error`).
    pub terminations: BTreeMap<String, usize>,
    /// Number of scenes whose solver converged.
    pub converged: usize,
    /// Scenes whose fit the adequacy tests flag (misfit or noise), and the count of each
    /// reason among them.
    pub adequacy_flagged: usize,
    /// Count of each adequacy reason code among the flagged scenes.
    pub adequacy_reasons: BTreeMap<String, usize>,
    /// Number of scenes whose data generation or fit returned an error.
    pub errors: usize,
    /// Median wall seconds of the fits that returned no error (NaN if none did).
    pub median_seconds: f64,
    /// Wall seconds of the whole run: drawing, fitting (in parallel) and summarising.
    pub total_seconds: f64,
    /// Per regime present in the run, in the order of [`Regime::ALL`].
    pub regimes: Vec<RegimeSummary>,
    /// The scenes with a truth outside ±2 s.e., with the commands that reproduce each.
    pub outliers: Vec<Outlier>,
    /// Converged scenes that are confidently wrong (see [`outliers`]).
    pub wrong_converged: usize,
    /// Every scene's outcome, ordered by scene id.
    pub results: Vec<SceneResult>,
}

/// How to run a recovery.
#[derive(Debug, Clone)]
pub(crate) struct RecoverConfig {
    /// Number of scenes to draw.
    pub scenes: usize,
    /// Seed of the scene draws (scene parameters, layouts and noise seeds).
    pub seed: u64,
    /// Noise level ε of every scene (the kind alternates relative / Poisson-like).
    pub noise: f64,
    /// Wall-clock limit of one fit's solver.
    pub fit_timeout: Option<Duration>,
    /// Fit only the scenes with these ids (all `scenes` are still drawn, so each keeps the
    /// truth and noise it has in the whole run); None fits every scene.
    pub only: Option<Vec<usize>>,
    /// The factors on the lobe of every scene's truth and fit ([`draw_scenes_with`]).
    pub fresnel: Fresnel,
    /// The shadowing factor on the lobe of every scene's truth and fit.
    pub shadowing: Shadowing,
}

impl Default for RecoverConfig {
    fn default() -> Self {
        RecoverConfig {
            scenes: 30,
            seed: 11,
            noise: 0.01,
            fit_timeout: Some(Duration::from_secs(60)),
            only: None,
            fresnel: Fresnel::None,
            shadowing: Shadowing::None,
        }
    }
}

fn log_uniform(rng: &mut StdRng, lo: f64, hi: f64) -> f64 {
    (rng.gen_range(lo.ln()..hi.ln())).exp()
}

/// The scenes of a run: regimes in turn (smooth, intermediate, rough, grazing), the layout
/// alternating sparse/dense every full turn, parameters drawn log-uniformly.
pub(crate) fn draw_scenes(n: usize, seed: u64, noise: f64) -> Vec<Scene> {
    let mut rng = StdRng::seed_from_u64(seed);
    (0..n)
        .map(|id| {
            let regime = Regime::ALL[id % Regime::ALL.len()];
            let dense = (id / Regime::ALL.len()) % 2 == 1;
            let (sigma, ratio) = match regime {
                Regime::Smooth => (log_uniform(&mut rng, 0.003, 0.015), 0.0),
                Regime::Intermediate => (
                    log_uniform(&mut rng, 0.08, 0.4),
                    log_uniform(&mut rng, 2.0, 12.0),
                ),
                Regime::Rough => (
                    log_uniform(&mut rng, 4.0, 10.0),
                    log_uniform(&mut rng, 2.0, 12.0),
                ),
                Regime::Grazing => (
                    log_uniform(&mut rng, 0.08, 0.4),
                    log_uniform(&mut rng, 2.0, 12.0),
                ),
            };
            // Smooth surfaces: T/λ from 0.3 to 3 (a lobe visible across the hemisphere).
            let corr_len = if regime == Regime::Smooth {
                log_uniform(&mut rng, 0.3, 3.0)
            } else {
                sigma * ratio
            };
            let scale = log_uniform(&mut rng, 0.1, 10.0);
            let layout = match (regime, dense) {
                (Regime::Grazing, false) => "grazing 4x9x12",
                (Regime::Grazing, true) => "grazing 5x18x24",
                (_, false) => "hemisphere 3x9x12",
                (_, true) => "hemisphere 5x18x24",
            }
            .to_string();
            let kind = if id % 2 == 0 {
                NoiseKind::Relative
            } else {
                NoiseKind::Poisson
            };
            let noise = Noise {
                kind,
                level: noise,
                seed: rng.gen(),
            };
            Scene {
                id,
                regime,
                dense,
                layout,
                sigma,
                corr_len,
                scale,
                wavelength: 1.0,
                noise,
                fresnel: Fresnel::None,
                shadowing: Shadowing::None,
                n: None,
                kappa: None,
            }
        })
        .collect()
}

/// Seed offset of the index draws of [`draw_scenes_with`] (their own stream, so that the
/// scenes' other draws are those of [`draw_scenes`]).
const INDEX_STREAM: u64 = 0x006e_5f6b_6170_7061;

/// The layout of every twelfth scene (id ≡ 5 mod 12, an intermediate one) of a run with a
/// Fresnel factor: in-plane scans with θi, |θr| ≤ 40°, so no sample reaches θ_loc = 60°
/// and the fit must say that n is not determined.
pub(crate) const NARROW_LAYOUT: &str = "inplane theta_i=10,25,40 step=1 max=40";

/// [`draw_scenes`] with `fresnel` and `shadowing` on every scene's lobe: the same σ, T,
/// scale, layouts and noise, and n drawn log-uniformly from 1.3 to 2.5 (a paint's or a
/// glass's; κ from 0.5 to 5 for a conductor) from a stream of its own; with a Fresnel
/// factor, scenes id ≡ 5 (mod 12) on [`NARROW_LAYOUT`].
pub(crate) fn draw_scenes_with(
    n: usize,
    seed: u64,
    noise: f64,
    fresnel: Fresnel,
    shadowing: Shadowing,
) -> Vec<Scene> {
    let mut rng = StdRng::seed_from_u64(seed ^ INDEX_STREAM);
    let mut scenes = draw_scenes(n, seed, noise);
    for s in &mut scenes {
        s.fresnel = fresnel;
        s.shadowing = shadowing;
        if fresnel == Fresnel::None {
            continue;
        }
        s.n = Some(log_uniform(&mut rng, 1.3, 2.5));
        if fresnel == Fresnel::Conductor {
            s.kappa = Some(log_uniform(&mut rng, 0.5, 5.0));
        }
        if s.id % 12 == 5 {
            s.layout = NARROW_LAYOUT.to_string();
        }
    }
    scenes
}

/// Smallest σ_L a scene's weights use, relative to its largest σ_L: it only keeps the
/// weight of a sample whose value underflowed to 0 finite. Every other sample is weighted by
/// its true 1/σ_L², so that its standardized residual is N(0, 1) and χ²/(n − p) estimates 1:
/// a floor of 1e-9 would cut the weight of every sample of a narrow relative-noise lobe
/// below 1e-9 of its peak (1387 of 2160 samples of a smooth scene), so those samples would
/// add nothing to χ² yet count in n − p, the fit's s² would come out near 0.36 and its
/// standard errors 0.6 times too small (±2 s.e. would cover 0.84 of smooth truths).
pub(crate) const SIGMA_L_FLOOR: f64 = 1e-100;

/// The fit's data for a scene, with weights 1/σ_L² (σ_L floored at [`SIGMA_L_FLOOR`] of its
/// largest value).
pub(crate) fn scene_input(scene: &Scene) -> Result<FitInput> {
    let model = model::by_name("kbs", &scene.model_options())?;
    let params = scene.params();
    let angles = scene.layout_value()?.angles();
    let data = synth::generate(
        model.as_ref(),
        &params,
        &angles,
        scene.wavelength,
        Quantity::Radiance,
        &scene.noise,
    )?;
    let max_sd = data.sigma_l.iter().fold(0.0f64, |m, v| m.max(*v));
    let weight: Vec<f64> = if max_sd > 0.0 {
        data.sigma_l
            .iter()
            .map(|s| 1.0 / s.max(SIGMA_L_FLOOR * max_sd).powi(2))
            .collect()
    } else {
        vec![1.0; data.len()]
    };
    let geo = Geometry::new(&data.samples, &[data.wavelength], data.quantity)?;
    Ok(FitInput {
        geo,
        y: data.value.into(),
        weight: weight.into(),
        channel: Channels::single(data.samples.len()),
        channel_names: vec![String::new()],
    })
}

/// The truth of the parameters and ratio quantities a KBS fit reports, by report name (the
/// amplitude depends on the verdict: see [`score`]).
pub(crate) fn truths(scene: &Scene) -> BTreeMap<&'static str, f64> {
    let ratio = scene.corr_len / scene.sigma;
    let mut t = BTreeMap::from([
        ("sigma", scene.sigma),
        ("T", scene.corr_len),
        ("scale", scene.scale),
        ("T/sigma", ratio),
        ("beckmann_alpha", 2.0 / ratio),
    ]);
    t.extend(scene.n.map(|n| ("n", n)));
    t.extend(scene.kappa.map(|k| ("kappa", k)));
    t
}

fn check(name: &str, truth: f64, value: f64, stderr: Option<f64>) -> Check {
    let rel_error = if truth != 0.0 {
        ((value - truth) / truth).abs()
    } else {
        value.abs()
    };
    let stderr = stderr.filter(|s| s.is_finite());
    Check {
        name: name.to_string(),
        truth,
        value,
        stderr,
        rel_error,
        covered: stderr.map(|s| (value - truth).abs() <= COVERAGE_K * s),
    }
}

/// Score a finished fit against its scene: the determined quantities, per the verdict.
pub(crate) fn score(scene: &Scene, fit: &FitResult) -> Vec<Check> {
    let t = truths(scene);
    let s_l = scene.sigma / scene.wavelength;
    let ratio = scene.corr_len / scene.sigma;
    let amp_truth = match fit.verdict {
        Verdict::Rough => scene.scale * ratio * ratio,
        _ => scene.scale * s_l * s_l,
    };
    let mut out = Vec::new();
    let param = |name: &str| fit.params.iter().find(|p| p.name == name);
    let derived = |name: &str| fit.derived.iter().find(|d| d.name == name);
    let wanted: &[&str] = match fit.verdict {
        Verdict::Full => &["sigma", "T", "scale", "T/sigma"],
        Verdict::Rough => &["T/sigma", "amplitude"],
        Verdict::Smooth => &["T", "amplitude"],
        Verdict::Partial | Verdict::NotComputed => &["sigma", "T", "scale", "T/sigma", "amplitude"],
    };
    for &name in wanted {
        let truth = if name == "amplitude" {
            amp_truth
        } else {
            t[name]
        };
        if let Some(p) = param(name) {
            if p.determined || fit.verdict != Verdict::Partial {
                out.push(check(name, truth, p.value, p.stderr));
            }
        } else if let Some(d) = derived(name) {
            if d.determined || fit.verdict != Verdict::Partial {
                out.push(check(name, truth, d.value, d.stderr));
            }
        }
    }
    // The Fresnel factor's parameters, whatever the verdict on σ and T, where determined.
    for name in ["n", "kappa"] {
        if let (Some(&truth), Some(p)) = (t.get(name), param(name)) {
            if p.determined {
                out.push(check(name, truth, p.value, p.stderr));
            }
        }
    }
    out
}

/// Fit one scene (its solver limited by `config.fit_timeout`), stopped by `stop` too: a
/// fit that a signal or the caller's flag cut short (`stop` requested as
/// [`Termination::Interrupted`]) is no result of the scene's and gives None.
pub(crate) fn run_scene(scene: &Scene, config: &RecoverConfig, stop: &Stop) -> Option<SceneResult> {
    let stop = stop.part(config.fit_timeout);
    let result = fit_scene(scene, config, &stop);
    (stop.requested() != Some(Termination::Interrupted)).then_some(result)
}

/// Fit one scene under `stop` (the scene's own limit and the run's signals).
fn fit_scene(scene: &Scene, config: &RecoverConfig, stop: &Stop) -> SceneResult {
    let fail = |n: usize, e: Error| SceneResult {
        scene: scene.clone(),
        n,
        termination: None,
        verdict: None,
        converged: false,
        seconds: 0.0,
        checks: Vec::new(),
        error: Some(e.to_string()),
        adequacy: None,
        adequacy_reasons: Vec::new(),
        n_determined: None,
    };
    let input = match scene_input(scene) {
        Ok(i) => i,
        Err(e) => return fail(0, e),
    };
    let n = input.y.len();
    let fit_config = FitConfig {
        model_opts: scene.model_options(),
        weights_are_uncertainties: true,
        lm: LmConfig {
            timeout: config.fit_timeout,
            stop: Some(stop.clone()),
            ..FitConfig::default().lm
        },
        ..FitConfig::default()
    };
    match driver::fit(&input, &fit_config) {
        Ok(fit) => SceneResult {
            scene: scene.clone(),
            n,
            termination: Some(fit.termination),
            verdict: Some(fit.verdict),
            converged: fit.converged(),
            seconds: fit.seconds,
            checks: score(scene, &fit),
            error: None,
            adequacy: Some(fit.adequacy.verdict),
            adequacy_reasons: fit
                .adequacy
                .reasons
                .iter()
                .map(|r| r.code.to_string())
                .collect(),
            n_determined: fit
                .params
                .iter()
                .find(|p| p.name == "n")
                .map(|p| p.determined),
        },
        Err(e) => fail(n, e),
    }
}

fn termination_name(r: &SceneResult) -> String {
    match r.termination {
        Some(t) => format!("{t:?}"),
        None => "error".to_string(),
    }
}

fn coverage_of<'a>(checks: impl Iterator<Item = &'a Check>) -> (Option<f64>, usize) {
    let c: Vec<bool> = checks.filter_map(|c| c.covered).collect();
    let n = c.len();
    let inside = c.iter().filter(|&&b| b).count();
    ((n > 0).then(|| inside as f64 / n as f64), n)
}

/// Summarise scene results of a run of `config`.
pub(crate) fn summarize(
    results: Vec<SceneResult>,
    config: &RecoverConfig,
    total_seconds: f64,
) -> RecoverReport {
    let seed = config.seed;
    let mut regimes = Vec::new();
    for regime in Regime::ALL {
        let rs: Vec<&SceneResult> = results
            .iter()
            .filter(|r| r.scene.regime == regime)
            .collect();
        if rs.is_empty() {
            continue;
        }
        regimes.push(regime_summary(regime, &rs));
    }
    let (coverage, n_with_stderr) = coverage_of(results.iter().flat_map(|r| r.checks.iter()));
    let mut terminations = BTreeMap::new();
    for r in &results {
        *terminations.entry(termination_name(r)).or_insert(0) += 1;
    }
    let secs: Vec<f64> = results
        .iter()
        .filter(|r| r.error.is_none())
        .map(|r| r.seconds)
        .collect();
    let outliers = outliers::outliers(&results, config);
    let flagged: Vec<&SceneResult> = results
        .iter()
        .filter(|r| r.adequacy.is_some_and(AdequacyVerdict::flagged))
        .collect();
    let mut adequacy_reasons = BTreeMap::new();
    for code in flagged.iter().flat_map(|r| &r.adequacy_reasons) {
        *adequacy_reasons.entry(code.to_string()).or_insert(0) += 1;
    }
    RecoverReport {
        scenes: results.len(),
        seed,
        coverage: coverage.unwrap_or(f64::NAN),
        nominal_coverage: NOMINAL_COVERAGE,
        n_with_stderr,
        terminations,
        converged: results.iter().filter(|r| r.converged).count(),
        adequacy_flagged: flagged.len(),
        adequacy_reasons,
        errors: results.iter().filter(|r| r.error.is_some()).count(),
        median_seconds: median(&secs),
        total_seconds,
        regimes,
        wrong_converged: outliers.iter().filter(|o| o.wrong).count(),
        outliers,
        results,
    }
}

/// The summary of one regime's scenes `rs`: verdicts and terminations counted, each
/// quantity's errors and coverage, the regime's coverage and median fit time.
fn regime_summary(regime: Regime, rs: &[&SceneResult]) -> RegimeSummary {
    let mut verdicts = BTreeMap::new();
    let mut terminations = BTreeMap::new();
    for r in rs {
        let v = r.verdict.map_or("error", Verdict::name).to_string();
        *verdicts.entry(v).or_insert(0) += 1;
        *terminations.entry(termination_name(r)).or_insert(0) += 1;
    }
    let quantities = quantity_summaries(rs);
    let (coverage, n_with_stderr) = coverage_of(rs.iter().flat_map(|r| r.checks.iter()));
    let secs: Vec<f64> = rs
        .iter()
        .filter(|r| r.error.is_none())
        .map(|r| r.seconds)
        .collect();
    RegimeSummary {
        regime,
        scenes: rs.len(),
        verdicts,
        terminations,
        quantities,
        coverage,
        n_with_stderr,
        median_seconds: median(&secs),
        errors: rs.iter().filter(|r| r.error.is_some()).count(),
    }
}

/// Per quantity checked in `rs` (in the order σ, T, scale, T/σ, amplitude, n, κ, then
/// others): its count, median and largest relative error, and coverage.
fn quantity_summaries(rs: &[&SceneResult]) -> Vec<QuantitySummary> {
    let mut names: Vec<String> = Vec::new();
    for r in rs {
        for c in &r.checks {
            if !names.contains(&c.name) {
                names.push(c.name.clone());
            }
        }
    }
    let order = ["sigma", "T", "scale", "T/sigma", "amplitude", "n", "kappa"];
    names.sort_by_key(|n| order.iter().position(|o| o == n).unwrap_or(order.len()));
    names
        .iter()
        .map(|name| {
            let cs: Vec<&Check> = rs
                .iter()
                .flat_map(|r| r.checks.iter())
                .filter(|c| &c.name == name)
                .collect();
            let errs: Vec<f64> = cs.iter().map(|c| c.rel_error).collect();
            let (coverage, n_with_stderr) = coverage_of(cs.iter().copied());
            QuantitySummary {
                name: name.clone(),
                n: cs.len(),
                median_rel_error: median(&errs),
                max_rel_error: errs.iter().fold(0.0f64, |m, v| m.max(*v)),
                coverage,
                n_with_stderr,
            }
        })
        .collect()
}

/// Run a recovery: draw the scenes, fit them in parallel (rayon), summarise. `on_done` is
/// called once per finished scene (e.g. to advance a progress bar). Once `stop` is
/// requested as an interrupt (a signal, or its flag) no scene is started, the running fits
/// end at their next step, and the run is [`Error::Stopped`] (saying how many scenes were
/// fitted): a recovery cut short has no summary, and its interrupted scenes are no errors.
/// `stop`'s deadline, if any, limits each scene's fit like `config.fit_timeout`.
pub(crate) fn run(
    config: &RecoverConfig,
    stop: &Stop,
    on_done: &(dyn Fn(&SceneResult) + Sync),
) -> Result<RecoverReport> {
    let t0 = std::time::Instant::now();
    let mut scenes = draw_scenes_with(
        config.scenes,
        config.seed,
        config.noise,
        config.fresnel,
        config.shadowing,
    );
    if let Some(only) = &config.only {
        scenes.retain(|s| only.contains(&s.id));
    }
    let interrupted = || stop.requested() == Some(Termination::Interrupted);
    let results: Vec<Option<SceneResult>> = scenes
        .par_iter()
        .map(|s| {
            if interrupted() {
                return None;
            }
            let r = run_scene(s, config, stop)?;
            on_done(&r);
            Some(r)
        })
        .collect();
    let mut results: Vec<SceneResult> = results.into_iter().flatten().collect();
    if interrupted() || results.len() < scenes.len() {
        return Err(Error::Stopped(format!(
            "interrupted after {} of {} scenes were fitted: no summary",
            results.len(),
            scenes.len()
        )));
    }
    results.sort_by_key(|r| r.scene.id);
    Ok(summarize(results, config, t0.elapsed().as_secs_f64()))
}
