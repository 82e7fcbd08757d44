//! Fitting: Levenberg–Marquardt as an argmin solver ([`lm`]), covariance and
//! identifiability ([`stats`]), the reflectance least-squares problem ([`problem`]),
//! starting values ([`init`]) and the whole fit ([`driver`]).

pub mod driver;
pub mod init;
pub mod lm;
pub mod problem;
pub mod stats;
pub mod weights;
