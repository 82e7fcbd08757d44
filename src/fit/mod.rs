//! Fitting with the Levenberg–Marquardt solver of [`crate::lm`]: covariance and
//! identifiability ([`stats`]), the reflectance least-squares problem ([`problem`]) and its parameters ([`layout`]),
//! starting values ([`init`]) and the whole fit ([`driver`]), whose stages each have a
//! file: prepare (`prepare`), start search (`start`), solve (`solve`), identify
//! (`identify`), reduce (`reduce`), accept (`accept`, with the domain's edges in `edges`)
//! and assemble (`assemble`); a dataset's fit with
//! model selection, shared by the CLI and the Python package ([`dataset`]).

pub mod adequacy;
pub mod amplitudes;
pub mod channels;
pub mod dataset;
pub mod driver;
pub mod grid_cache;
pub mod init;
pub mod layout;
pub mod loss;
pub mod problem;
pub mod profile;
pub mod quantile;
pub mod stats;
pub mod validity;
pub mod weights;

mod accept;
mod assemble;
mod bounds;
mod config;
mod edges;
mod identify;
mod prepare;
mod reduce;
mod result;
mod solve;
mod start;
