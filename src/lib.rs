//! goniofit: fit physical light-scattering models to gonioreflectometer measurements.
//!
//! Layers: [`geometry`] (angles and per-sample quantities), [`model`] (one file per model),
//! [`lm`] (Levenberg–Marquardt as an argmin solver, on argmin, nalgebra and std alone),
//! [`fit`] (the fit pipeline and its statistics), [`io`] (readers and
//! writers), [`report`] and [`plot`].

pub mod design;
pub mod error;
pub mod fit;
pub mod geometry;
pub mod io;
pub mod lm;
pub mod model;
pub mod plot;
pub mod recover;
pub mod report;
pub mod settings;
pub mod synth;
pub mod workprec;

pub use error::{Error, Result};
