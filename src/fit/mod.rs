//! Fitting: Levenberg–Marquardt as an argmin solver ([`lm`]), covariance and
//! identifiability ([`stats`]), the reflectance least-squares problem ([`problem`]),
//! starting values ([`init`]) and the whole fit ([`driver`]), whose stages each have a
//! file: start search (`start`), solve (`solve`), identify (`identify`), reduce
//! (`reduce`), validate (`validate`) and assemble (`assemble`); a dataset's fit with
//! model selection, shared by the CLI and the Python package ([`dataset`]).

pub mod dataset;
pub mod driver;
pub mod init;
pub mod lm;
pub mod problem;
pub mod stats;
pub mod weights;

mod assemble;
mod identify;
mod reduce;
mod solve;
mod start;
mod validate;
