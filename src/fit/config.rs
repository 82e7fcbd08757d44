//! What a fit is asked to do: the model, residual kind, starting values, fixed parameters
//! and solver settings ([`FitConfig`]), and the residual floor that follows from them.

use super::problem::loss::Loss;
use super::problem::ResidualKind;
use crate::model::ModelOptions;
use goniofit_lm::{LmConfig, Stop};

/// Everything about a fit except the data.
#[derive(Debug, Clone)]
pub struct FitConfig {
    /// The model's name, as [`crate::model::by_name`] takes it (`kbs`, `kbs+lambert`, …).
    pub model: String,
    /// The model's options: evaluation mode, series tolerance, patch, Fresnel and shadowing
    /// factors.
    pub model_opts: ModelOptions,
    /// What the residual of a sample is: absolute f − y, relative or logarithmic.
    pub residual: ResidualKind,
    /// The robust loss on the weighted residuals (default linear: plain least squares).
    pub loss: Loss,
    /// Floor for relative/log residuals; None: 1e-6 × max |y|.
    pub floor: Option<f64>,
    /// Starting values given by the user (name, value); names may carry `[channel]`.
    pub init: Vec<(String, f64)>,
    /// Parameters held fixed (name, value).
    pub fix: Vec<(String, f64)>,
    /// The Levenberg–Marquardt settings (tolerances, limits, time limit, stop request).
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
            loss: Loss::default(),
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

impl FitConfig {
    /// Whether the fit's stop request (`lm.stop`) has fired: later stages then keep the
    /// best point so far instead of refitting.
    pub fn stop_requested(&self) -> bool {
        self.lm.stop.as_ref().is_some_and(Stop::is_requested)
    }
}

/// The floor of relative and log residuals: `config.floor`, or 1e-6 × max |y|.
pub(crate) fn residual_floor(config: &FitConfig, y: &[f64]) -> f64 {
    config
        .floor
        .unwrap_or(1e-6 * y.iter().fold(0.0f64, |m, v| m.max(v.abs())))
}
