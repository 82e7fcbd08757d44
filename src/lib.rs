//! goniofit: fit physical light-scattering models to gonioreflectometer measurements.
//!
//! Layers, from the bottom: [`error`]; [`lm`] (Levenberg–Marquardt as an argmin solver, its
//! own crate, `goniofit-lm`, importing nothing of this one); [`geometry`] (angles, per-sample
//! quantities, measurement layouts); [`io`] (readers and writers); [`model`] (one file per
//! model); [`fit`] (the fit pipeline and its statistics); [`design`] (what to measure
//! next); [`plot`] and [`report`]; [`harness`] (synthetic data, recovery and work–precision
//! runs). [`settings`] validates the numeric options of every command.

#![warn(missing_docs)]

pub mod cli;
mod commands;
pub mod design;
pub mod error;
pub mod fit;
pub mod geometry;
pub mod harness;
pub mod io;
pub mod model;
pub mod plot;
pub mod report;
pub mod settings;

pub use error::{Error, Result};
/// The Levenberg–Marquardt solver, the workspace crate `goniofit-lm` (lm/).
pub use goniofit_lm as lm;
pub use goniofit_lm::Stop;

// Measured data: reading a file, the samples' angles and per-sample quantities.
pub use geometry::layout::AnglesDeg;
pub use geometry::{Geometry, PerSample, Quantity, Sample};
pub use io::{parse_length, read_dataset as read, Dataset, ReadOptions};

// Models: by name, evaluated on a geometry.
pub use model::fresnel::Fresnel;
pub use model::shadowing::Shadowing;
pub use model::{
    by_name as model, parse_assignments, parse_params, EvalMode, Model, ModelOptions, ParamSpec,
    MODEL_NAMES,
};

// Fits: a dataset's fit as the command runs it, or one model on prepared arrays.
pub use fit::dataset::{fit_dataset, DatasetFit, Outcome, AUTO_CANDIDATES};
pub use fit::driver::{fit_model, FitConfig, FitInput, FitResult, ParamResult, Verdict};
pub use fit::problem::loss::{Loss, LossKind};
pub use fit::problem::{Channels, ResidualKind};
pub use report::json::FitReport;

/// The KBS series: ln q(g, a) and its derivatives, exact over g ∈ [1e-12, 1e6].
pub mod series {
    pub use crate::model::series::{
        asymptotic, auto, ln_q, ln_q_batch, rough, series, smooth, LnQ, G_DOMAIN_MAX,
    };
}

/// The statistics behind the profile-likelihood intervals.
pub mod stats {
    pub use crate::fit::stats::profile::{threshold as profile_threshold, CROSS_TOL};
    pub use crate::fit::stats::quantile::student_t_quantile;
}

/// Synthetic measurements: a model's values on a layout of angles, with seeded noise.
pub mod synth {
    pub use crate::harness::synth::{
        generate, truth_path, CsvOptions, Layout, Noise, NoiseKind, Truth,
    };
}

/// The library's tests against references, properties and pictures (tests/lib/).
#[cfg(test)]
#[path = "../tests/lib/main.rs"]
mod lib_tests;

/// Helpers the tests share (tests/common/).
#[cfg(test)]
#[path = "../tests/common/mod.rs"]
mod common;
