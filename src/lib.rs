//! goniofit: fit physical light-scattering models to gonioreflectometer measurements.
//!
//! The library's surface is what a program or a binding needs: read a file ([`read`]) or
//! arrays ([`arrays`]) into a [`Dataset`], fit it ([`fit_dataset`] with the [`DatasetFit`]
//! its [`Settings`] make, or one [`Model`] on prepared arrays with [`fit_model`]), and render the outcome
//! ([`report`], [`plot`]); models evaluate on a [`Geometry`] of samples; [`design`] says
//! what to measure next; [`cli::main`] is the whole command line. Everything else is
//! private to the crate.
//!
//! ```
//! use goniofit::{fit_dataset, read, Quantity, ResidualKind, Settings};
//!
//! // One channel of a Cornell paint: BRDF samples, λ = 550 nm from the channel's name.
//! let settings = Settings {
//!     model: "kbs+lambert".into(),
//!     channel: Some("550nm".into()),
//!     quantity: Some(Quantity::Brdf),
//!     residual: ResidualKind::Log,
//!     ..Settings::default()
//! };
//! settings.check(goniofit::settings::Front::Json)?;
//! let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/cornell/garnet_red.astm");
//! let ds = read(&path, &settings.read_options()?)?;
//! let outcome = fit_dataset(&settings.dataset_fit(&ds, false), "garnet red 550 nm".into(), ds)?;
//! let fit = &outcome.result;
//! assert!(fit.converged());
//! for p in &fit.params {
//!     // σ and T in nm (λ's unit); a standard error where the data determines the parameter.
//!     println!("{} = {} ± {:?} (determined: {})", p.name, p.value, p.stderr, p.determined);
//! }
//! println!("{}", goniofit::report::to_text(&outcome, &Default::default()));
//! # Ok::<(), goniofit::Error>(())
//! ```
//!
//! Inside, the layers run one way, from the bottom: `error`; [`lm`] (Levenberg–Marquardt
//! as an argmin solver, its own crate, `goniofit-lm`); `geometry` (angles, per-sample
//! quantities, measurement layouts); `io` (readers and writers); `model` (one file per
//! model, [`series`] the KBS sum); `fit` (the fit pipeline and its statistics); [`design`];
//! [`plot`] and [`report`]; `harness` (synthetic data, recovery and work–precision runs);
//! the command line (`cli`, `commands`). [`settings`] holds what a fit is asked to do
//! ([`Settings`]: the CLI, the Python package and the report's replay share it) and
//! validates the numeric options of every front end.

#![warn(missing_docs)]
#![warn(unreachable_pub)]

pub mod cli;
mod commands;
pub mod design;
mod error;
mod fit;
mod geometry;
mod harness;
mod io;
mod model;
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
pub use io::csv::parse_columns;
pub use io::{parse_length, read_dataset_columns as read, Dataset, ReadOptions};

// Models: by name, evaluated on a geometry.
pub use model::domain::check_finite;
pub use model::fresnel::Fresnel;
pub use model::shadowing::Shadowing;
pub use model::{
    by_name as model, check_param_count, check_param_value, parse_assignments, parse_params,
    EvalMode, Model, ModelOptions, ParamSpec, MODEL_NAMES,
};

// Fits: a dataset's fit as the command runs it, or one model on prepared arrays.
pub use fit::dataset::batch::in_chains;
pub use fit::dataset::{
    check_magnitudes, fit_dataset, fit_dataset_near, DatasetFit, Outcome, AUTO_CANDIDATES,
};
pub use fit::driver::{fit_model, FitConfig, FitInput, FitResult, ParamResult, Verdict};
pub use fit::problem::loss::{Loss, LossKind};
pub use fit::problem::{Channels, ResidualKind};
pub use report::json::FitReport;
pub use settings::Settings;

/// Samples from arrays: a dataset built from per-sample columns (the Python binding's input).
pub mod arrays {
    pub use crate::io::arrays::{dataset, Columns};
}

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
