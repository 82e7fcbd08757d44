//! Fitting: Levenberg–Marquardt as an argmin solver ([`lm`]), covariance and
//! identifiability ([`stats`]), the reflectance least-squares problem ([`problem`]),
//! starting values ([`init`]), the whole fit ([`driver`]) and a dataset's fit with model
//! selection ([`dataset`]).

pub mod dataset;
pub mod driver;
pub mod init;
pub mod lm;
pub mod problem;
pub mod stats;
