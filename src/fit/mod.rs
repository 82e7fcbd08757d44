//! Fitting: Levenberg–Marquardt as an argmin [`Solver`](argmin::core::Solver) ([`lm`]) and
//! the statistics of a finished fit ([`stats`]).
//!
//! Cost convention everywhere in this module: `cost = ½ Σ r̃ᵢ²` with weighted residuals
//! `r̃ᵢ = √wᵢ rᵢ` (as MINPACK, scipy and Ceres).

pub mod lm;
pub mod stats;
