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

/// The library's tests against references, properties and pictures (tests/lib/).
#[cfg(test)]
#[path = "../tests/lib/main.rs"]
mod lib_tests;

/// Helpers the tests share (tests/common/).
#[cfg(test)]
#[path = "../tests/common/mod.rs"]
mod common;
