//! Validation harnesses, apart from the physics: synthetic data sets from a model and a
//! measurement layout ([`synth`]), the recovery of known parameters from many of them
//! ([`recover`]), and the work–precision benchmark of the model's evaluation modes and of
//! the solver ([`workprec`]). The CLI's `synth`, `recover` and `bench` commands and the
//! tests run them; nothing below them in the library uses them.

pub(crate) mod recover;
pub(crate) mod synth;
pub(crate) mod workprec;
