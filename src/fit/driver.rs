//! A whole fit: starting values, Levenberg–Marquardt, uncertainties, and the verdict on
//! what the data determines — with the reduced refit when it determines only combinations.
//!
//! Conventions written into every report:
//! - cost = ½ Σ wᵢ rᵢ² (the solver's), χ² = Σ wᵢ rᵢ², reduced χ² = χ²/(n − p);
//! - covariance = s² (JᵀJ)⁺ with s² = χ²/(n − p) (scaled by the residual variance, as
//!   lmfit's default and scipy's `curve_fit(absolute_sigma=False)`);
//! - AIC = n ln(χ²/n) + 2p, BIC = n ln(χ²/n) + p ln n (lmfit's definitions);
//! - a parameter is *determined* when its direction is not in the numerical null space of
//!   the Jacobian and its standard error in ln p is at most [`DETERMINED_MAX_LOG_SE`]
//!   (the data pins it within a factor e at one standard error).

use super::lm::{LmConfig, Termination};
pub use super::problem::FitInput;
use super::problem::{FitProblem, ParamLayout, ResidualKind, Transform};
use super::{assemble, identify, reduce, solve, start, validate};
use crate::error::{Error, Result};
use crate::model::{self, Mode, Model, ModelOptions};
use nalgebra::DMatrix;
use std::collections::BTreeMap;
use std::time::Instant;

/// Largest standard error of ln p for a parameter to count as determined.
pub const DETERMINED_MAX_LOG_SE: f64 = 1.0;

/// Standard error of ln σ above which a ridge along a regime's known direction counts as
/// undetermined (see `kbs_verdict`).
pub const LOOSE_LOG_SE: f64 = 0.05;

/// Alignment |cos| of the weakest direction with a regime's known direction.
pub const ALIGN: f64 = 0.98;

/// Median g above which the rough regime's ridge is expected.
pub const ROUGH_G: f64 = 3.0;

/// Median g below which the smooth regime's ridge is expected.
pub const SMOOTH_G: f64 = 0.3;

/// Accuracy of the model on the starting-value grid (it only ranks candidates).
pub const GRID_TOL: f64 = 1e-4;

/// Model accuracy of the quick refinement on a subsample (it only has to land near the
/// optimum; the full fit then works at the requested accuracy).
pub const REFINE_TOL: f64 = 1e-6;

/// Relative singular-value threshold below which a direction is undetermined.
pub const RANK_THRESHOLD: f64 = 1e-9;

/// Everything about a fit except the data.
#[derive(Debug, Clone)]
pub struct FitConfig {
    pub model: String,
    pub model_opts: ModelOptions,
    pub residual: ResidualKind,
    /// Floor for relative/log residuals; None: 1e-6 × max |y|.
    pub floor: Option<f64>,
    /// Starting values given by the user (name, value); names may carry `[channel]`.
    pub init: Vec<(String, f64)>,
    /// Parameters held fixed (name, value).
    pub fix: Vec<(String, f64)>,
    pub lm: LmConfig,
    /// Whether weights are inverse variances from a stated uncertainty column.
    pub weights_are_uncertainties: bool,
    /// Refit the reduced problem when the data determines only combinations.
    pub reduce: bool,
}

impl Default for FitConfig {
    fn default() -> Self {
        FitConfig {
            model: "kbs".into(),
            model_opts: ModelOptions::default(),
            residual: ResidualKind::Absolute,
            floor: None,
            init: Vec::new(),
            fix: Vec::new(),
            lm: LmConfig {
                predicted_stop: true,
                ..LmConfig::default()
            },
            weights_are_uncertainties: false,
            reduce: true,
        }
    }
}

/// One fitted parameter.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ParamResult {
    pub name: String,
    pub value: f64,
    /// Standard error; None when fixed or undetermined.
    pub stderr: Option<f64>,
    pub determined: bool,
    pub fixed: bool,
    pub unit: String,
}

/// A quantity derived from the parameters (T/σ, rms slope, determined combinations).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Derived {
    pub name: String,
    pub value: f64,
    pub stderr: Option<f64>,
    pub determined: bool,
    pub doc: String,
}

/// What the data determines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// Every free parameter is determined.
    Full,
    /// Rough regime: only T/σ and the amplitude s·(T/σ)² are determined.
    Rough,
    /// Smooth regime: only T and the amplitude s·σ² are determined.
    Smooth,
    /// Some directions are undetermined and match no known regime.
    Partial,
}

/// A finished fit (converged or not).
#[derive(Debug, Clone)]
pub struct FitResult {
    pub model: String,
    pub params: Vec<ParamResult>,
    pub derived: Vec<Derived>,
    /// Names and correlation matrix of the free parameters of the reported fit.
    pub corr_names: Vec<String>,
    pub correlation: DMatrix<f64>,
    pub singular_values: Vec<f64>,
    pub condition: f64,
    pub verdict: Verdict,
    pub notes: Vec<String>,
    pub cost: f64,
    pub chi2: f64,
    pub reduced_chi2: f64,
    pub rms: f64,
    pub max_abs_residual: f64,
    pub r2: f64,
    pub aic: f64,
    pub bic: f64,
    pub n: usize,
    pub n_free: usize,
    pub iterations: u64,
    pub evaluations: u64,
    pub jacobian_evaluations: u64,
    pub termination: Termination,
    /// Wall time of the whole fit (starting values, refinement, LM, verdict).
    pub seconds: f64,
    /// Of which: up to the end of the starting-value refinement.
    pub init_seconds: f64,
    /// Of which: up to the grid's candidates (the automatic starting values, before any
    /// LM iteration).
    pub start_seconds: f64,
    pub modes: BTreeMap<String, usize>,
    /// Range of g = (2πσ/λ)²(cos θi + cos θr)² over the samples (KBS models).
    pub g_range: Option<(f64, f64)>,
    pub fitted: Vec<f64>,
    pub residuals: Vec<f64>,
    pub std_residuals: Vec<f64>,
    pub sample_modes: Vec<Mode>,
    /// Full parameter values in layout order (for plotting per channel).
    pub layout: ParamLayout,
    pub values: Vec<f64>,
    /// The grid point (layout order) whose quick refinement won, before any LM iteration.
    pub start: Vec<f64>,
}

impl FitResult {
    /// Whether the solver met a convergence criterion.
    pub fn converged(&self) -> bool {
        self.termination.converged()
    }

    /// Value of a parameter by (base) name, first channel.
    pub fn value(&self, name: &str) -> Option<f64> {
        self.layout.find(name).first().map(|&k| self.values[k])
    }
}

/// Resolve (name, value) pairs against a layout: a bare per-channel name applies to every
/// channel.
pub(super) fn assign(
    layout: &ParamLayout,
    pairs: &[(String, f64)],
    out: &mut [Option<f64>],
) -> Result<()> {
    for (name, v) in pairs {
        let ks = layout.find(name);
        if ks.is_empty() {
            return Err(Error::Param {
                name: name.clone(),
                message: format!(
                    "not a parameter of this fit (it has: {})",
                    layout
                        .params
                        .iter()
                        .map(|p| p.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            });
        }
        for k in ks {
            let fp = &layout.params[k];
            if !v.is_finite()
                || (fp.transform == Transform::Log && *v <= 0.0)
                || *v < 0.0 && fp.transform == Transform::NonNegative
            {
                return Err(Error::Param {
                    name: name.clone(),
                    message: format!("value {v} is outside its domain"),
                });
            }
            out[k] = Some(*v);
        }
    }
    Ok(())
}

/// Run a fit.
pub fn fit(input: &FitInput, config: &FitConfig) -> Result<FitResult> {
    let model = model::by_name(&config.model, &config.model_opts)?;
    fit_model(model.as_ref(), input, config)
}

/// Run a fit with a built model: start search → solve → identify → reduce → assemble
/// (validation of the input before, of the optimum inside the stages).
pub fn fit_model(model: &dyn Model, input: &FitInput, config: &FitConfig) -> Result<FitResult> {
    let t0 = Instant::now();
    let (layout, given) = validate::prepare(model, input, config)?;
    let floor = residual_floor(config, &input.y);
    // The full problem is built while the starting values are searched for on subsamples.
    let (problem, start) = rayon::join(
        || FitProblem::new(model, layout.clone(), input, config.residual, floor),
        || start::starting_point(model, &layout, input, config, floor, &given, t0),
    );
    let (problem, start) = (problem?, start?);
    let run = solve::run_lm(&problem, &start.p0, &config.lm);
    let identified = identify::identify(input, &problem, &run, config.reduce);
    let solved = reduce::reduce(model, input, config, problem, run, identified)?;
    let seconds = t0.elapsed().as_secs_f64();
    Ok(assemble::assemble(
        model, input, config, solved, seconds, start,
    ))
}

/// The floor of relative and log residuals: `config.floor`, or 1e-6 × max |y|.
pub fn residual_floor(config: &FitConfig, y: &[f64]) -> f64 {
    config
        .floor
        .unwrap_or(1e-6 * y.iter().fold(0.0f64, |m, v| m.max(v.abs())))
}

/// Standardized residuals √wᵢ rᵢ / s with s² = χ²/(n − p), or √wᵢ rᵢ when the weights are
/// inverse variances from stated uncertainties (or s = 0).
pub fn standardized_residuals(
    residuals: &[f64],
    sqrt_w: &[f64],
    n_free: usize,
    weights_are_uncertainties: bool,
) -> Vec<f64> {
    let chi2: f64 = residuals
        .iter()
        .zip(sqrt_w)
        .map(|(r, s)| (r * s).powi(2))
        .sum();
    let dof = residuals.len().saturating_sub(n_free).max(1) as f64;
    let s_hat = (chi2 / dof).sqrt();
    let scale = if weights_are_uncertainties || s_hat == 0.0 {
        1.0
    } else {
        1.0 / s_hat
    };
    residuals
        .iter()
        .zip(sqrt_w)
        .map(|(r, s)| r * s * scale)
        .collect()
}
