//! Stops by signal and time limit. Apart from the other tests because `lm_interrupt` sends
//! SIGINT to this process: every fit running in it would be interrupted, so every other test
//! here runs goniofit as a child process, never a fit of its own.

#[path = "../common/mod.rs"]
mod common;

mod lm_interrupt;
mod signal_moments;
mod stops;

/// One timed run at a time in this binary: the tests that measure how long a run takes
/// after its stop take turns, so that each measures its own run.
static TURN: std::sync::Mutex<()> = std::sync::Mutex::new(());
