//! Fits of real and synthetic data against the best optima independent multi-starts found
//! (tests/ref/), and warm-started batches against cold ones: the long checks of where the
//! fits end.

#[path = "../common/mod.rs"]
mod common;

mod corpus;
mod factors_trust;
mod optimum_trust;
mod trust_matrix;
mod warm_start;
