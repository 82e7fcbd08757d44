//! Fits of real and synthetic data against the best optima independent multi-starts found
//! (tests/ref/), and seeded recoveries of known parameters: the long checks of where the
//! fits end.

#[path = "../common/mod.rs"]
mod common;

mod corpus;
mod factors_trust;
mod optimum_trust;
mod recover;
mod trust_matrix;
mod warm_start;
