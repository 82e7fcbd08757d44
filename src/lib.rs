//! goniofit: fit physical light-scattering models to gonioreflectometer measurements.
//!
//! Layers, each using only those before it: [`error`]; [`lm`] (Levenberg–Marquardt as an
//! argmin solver, on argmin, nalgebra and std alone); [`geometry`] (angles, per-sample
//! quantities, measurement layouts); [`model`] (one file per model); [`fit`] (the fit
//! pipeline and its statistics); [`io`] (readers and writers); [`design`] (what to measure
//! next); [`report`] and [`plot`]; [`harness`] (synthetic data, recovery and
//! work–precision runs). [`settings`] holds the limits the layers share.

pub mod design;
pub mod error;
pub mod fit;
pub mod geometry;
pub mod harness;
pub mod io;
pub mod lm;
pub mod model;
pub mod plot;
pub mod report;
pub mod settings;

pub use error::{Error, Result};
