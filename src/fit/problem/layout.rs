//! The mapping between a model's parameters and the solver's free variables.
//!
//! Free variables: every parameter that is not fixed, through a [`Transform`]: the positive
//! nonlinear parameters (σ, T, w) as their logarithm, so the solver can never step to
//! σ ≤ 0; the linear amplitudes (scales, lobe strength) through p = u(√(x² + 1) − 1)
//! (lmfit's one-sided bound), which reaches the bound p = 0 at x = 0 instead of drifting
//! towards ln 0 when the data shows no such component. The amplitude's unit u is the
//! largest |value| measured ([`ParamLayout::set_amplitude_units`]): x is then a number
//! free of the unit of L, and a fit of the data in any unit takes the same steps.
//!
//! Joint multi-channel fits share every parameter except the linear scales (`scale`,
//! `scale_d`), which get one copy per channel (named `scale[550nm]`, ...).

use crate::model::Model;
use nalgebra::DVector;

/// Parameters that are per channel in a joint fit.
pub(crate) const PER_CHANNEL: [&str; 2] = ["scale", "scale_d"];

/// How a parameter p maps to the solver variable x.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Transform {
    /// x = p (unbounded).
    Identity,
    /// x = ln p (p > 0).
    Log,
    /// x = ln(p − lower) (p > lower > 0: a dielectric's index, above 1).
    LogAbove {
        /// The bound p stays above (1 for a dielectric's index).
        lower: f64,
    },
    /// p = u(√(x² + 1) − 1) ≥ 0, bounded below by 0, in units of u > 0 (the data's
    /// scale: see [`ParamLayout::set_amplitude_units`]).
    NonNegative {
        /// The unit u, in the parameter's own unit.
        unit: f64,
    },
}

/// Parameters that enter the model linearly: amplitudes, non-negative, and solved exactly
/// at each point of the starting-value grid ([`crate::fit::start::grid`]).
pub(crate) const LINEAR: [&str; 3] = ["scale", "scale_d", "B"];

impl Transform {
    /// The transform for a model parameter: log for positive nonlinear parameters,
    /// non-negative for the linear amplitudes, identity otherwise.
    pub fn for_spec(spec: &crate::model::ParamSpec) -> Self {
        match (spec.positive, LINEAR.contains(&spec.name)) {
            (true, false) if spec.lower > 0.0 => Transform::LogAbove { lower: spec.lower },
            (true, false) => Transform::Log,
            (true, true) => Transform::NonNegative { unit: 1.0 },
            _ => Transform::Identity,
        }
    }

    /// x from p (p is clamped into the domain).
    pub fn to_x(self, p: f64) -> f64 {
        match self {
            Transform::Identity => p,
            Transform::Log => p.max(f64::MIN_POSITIVE).ln(),
            Transform::LogAbove { lower } => (p - lower).max(f64::MIN_POSITIVE).ln(),
            Transform::NonNegative { unit } => {
                let p = (p / unit).max(0.0);
                (p * (p + 2.0)).sqrt()
            }
        }
    }

    /// p from x.
    #[allow(clippy::wrong_self_convention)]
    pub fn from_x(self, x: f64) -> f64 {
        match self {
            Transform::Identity => x,
            Transform::Log => x.exp(),
            Transform::LogAbove { lower } => lower + x.exp(),
            // √(x²+1) − 1 without cancellation for small x.
            Transform::NonNegative { unit } => unit * (x * x / ((x * x + 1.0).sqrt() + 1.0)),
        }
    }

    /// Whether x is a logarithm (of p, or of p above its lower bound).
    pub fn is_log(self) -> bool {
        matches!(self, Transform::Log | Transform::LogAbove { .. })
    }

    /// The exclusive lower bound of p (−∞ for the identity, 0 for the amplitudes' closed
    /// bound, which p reaches).
    pub fn lower(self) -> f64 {
        match self {
            Transform::Identity => f64::NEG_INFINITY,
            Transform::Log | Transform::NonNegative { .. } => 0.0,
            Transform::LogAbove { lower } => lower,
        }
    }

    /// Whether this is the amplitudes' one-sided bound at 0.
    pub fn is_non_negative(self) -> bool {
        matches!(self, Transform::NonNegative { .. })
    }

    /// The unit of the parameter's solver variable: u for an amplitude, else 1.
    pub fn unit(self) -> f64 {
        match self {
            Transform::NonNegative { unit } => unit,
            _ => 1.0,
        }
    }

    /// dp/dx at x.
    pub fn dp_dx(self, x: f64) -> f64 {
        match self {
            Transform::Identity => 1.0,
            Transform::Log | Transform::LogAbove { .. } => x.exp(),
            Transform::NonNegative { unit } => unit * (x / (x * x + 1.0).sqrt()),
        }
    }
}

/// One parameter of the (possibly joint) fit.
#[derive(Debug, Clone, PartialEq)]
pub struct FitParam {
    /// Report name: the model's name, with `[channel]` for per-channel copies.
    pub name: String,
    /// Index of the model parameter it feeds.
    pub spec: usize,
    /// Channel index for per-channel copies, None when shared.
    pub channel: Option<usize>,
    /// How the solver sees it.
    pub transform: Transform,
    /// Held at this value, not fitted.
    pub fixed: Option<f64>,
}

/// The full parameter list of a fit and the channel → model-parameter mapping.
#[derive(Debug, Clone)]
pub struct ParamLayout {
    /// Every fit parameter: per model parameter in the model's order, one shared entry, or
    /// one per channel for a per-channel scale of a joint fit.
    pub params: Vec<FitParam>,
    /// `index[c][j]`: the fit parameter that feeds model parameter j on channel c.
    pub index: Vec<Vec<usize>>,
    /// The channels' names (the `[channel]` suffixes; one empty name for a plain fit).
    pub channel_names: Vec<String>,
}

impl ParamLayout {
    /// The layout for `model` over the given channels (one unnamed channel for a plain fit).
    pub fn new(model: &dyn Model, channel_names: &[String]) -> Self {
        let specs = model.params();
        let n_ch = channel_names.len().max(1);
        let joint = channel_names.len() > 1;
        let mut params = Vec::new();
        let mut index = vec![vec![0; specs.len()]; n_ch];
        for (j, spec) in specs.iter().enumerate() {
            if joint && PER_CHANNEL.contains(&spec.name) {
                for (c, name) in channel_names.iter().enumerate() {
                    index[c][j] = params.len();
                    params.push(FitParam {
                        name: format!("{}[{name}]", spec.name),
                        spec: j,
                        channel: Some(c),
                        transform: Transform::for_spec(spec),
                        fixed: None,
                    });
                }
            } else {
                for row in index.iter_mut() {
                    row[j] = params.len();
                }
                params.push(FitParam {
                    name: spec.name.to_string(),
                    spec: j,
                    channel: None,
                    transform: Transform::for_spec(spec),
                    fixed: None,
                });
            }
        }
        ParamLayout {
            params,
            index,
            channel_names: channel_names.to_vec(),
        }
    }

    /// Set the unit u of every amplitude ([`Transform::NonNegative`]) to the largest |y| of
    /// its channel (`y`, `channel`: the fit's values and channel indices; a channel without
    /// a non-zero value takes the largest over all, and a fit with none keeps 1). The
    /// solver's variables are then the same numbers whatever the unit of L: a fit of the
    /// data scaled by any factor scales the amplitudes by it and leaves the rest.
    pub fn set_amplitude_units(&mut self, y: &[f64], channel: &super::channels::Channels) {
        let mut largest = vec![0.0f64; self.index.len().max(1)];
        for (i, v) in y.iter().enumerate() {
            let c = channel[i].min(largest.len() - 1);
            if v.is_finite() {
                largest[c] = largest[c].max(v.abs());
            }
        }
        let all = largest.iter().fold(0.0f64, |m, v| m.max(*v));
        for fp in &mut self.params {
            if let Transform::NonNegative { unit } = &mut fp.transform {
                let u = fp.channel.map_or(all, |c| largest[c]);
                *unit = [u, all, 1.0]
                    .into_iter()
                    .find(|v| v.is_normal())
                    .unwrap_or(1.0);
            }
        }
    }

    /// Number of fit parameters (free and fixed).
    pub fn len(&self) -> usize {
        self.params.len()
    }

    /// Whether there are no parameters.
    pub fn is_empty(&self) -> bool {
        self.params.is_empty()
    }

    /// Indices of the free parameters.
    pub fn free(&self) -> Vec<usize> {
        (0..self.params.len())
            .filter(|&k| self.params[k].fixed.is_none())
            .collect()
    }

    /// Indices of fit parameters whose model name (without channel) is `name`.
    pub fn find(&self, name: &str) -> Vec<usize> {
        self.params
            .iter()
            .enumerate()
            .filter(|(_, p)| {
                p.name.eq_ignore_ascii_case(name)
                    || p.name
                        .split('[')
                        .next()
                        .is_some_and(|base| base.eq_ignore_ascii_case(name))
            })
            .map(|(k, _)| k)
            .collect()
    }

    /// Solver variables from full parameter values (free parameters only).
    pub fn to_x(&self, p: &[f64]) -> DVector<f64> {
        let free = self.free();
        DVector::from_iterator(
            free.len(),
            free.iter().map(|&k| self.params[k].transform.to_x(p[k])),
        )
    }

    /// Full parameter values from solver variables (fixed parameters from the layout).
    #[allow(clippy::wrong_self_convention)]
    pub fn from_x(&self, x: &DVector<f64>) -> Vec<f64> {
        let mut it = x.iter();
        self.params
            .iter()
            .map(|fp| match fp.fixed {
                Some(v) => v,
                None => fp
                    .transform
                    .from_x(*it.next().expect("x has one entry per free parameter")),
            })
            .collect()
    }

    /// Model parameters for channel `c` from full parameter values.
    pub fn model_params(&self, p: &[f64], c: usize) -> Vec<f64> {
        self.index[c].iter().map(|&k| p[k]).collect()
    }
}
