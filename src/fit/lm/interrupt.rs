//! Ctrl-C: one process-wide handler, installed on first use.
//!
//! argmin's Executor installs its own handler bound to the flag of the *first* run in the
//! process (later runs cannot be interrupted, and Ctrl-C is swallowed between runs). Instead
//! [`super::minimize`] turns the Executor's handler off and installs one that bumps a global
//! generation counter while a fit is running (every running solver sees the change) and,
//! when no fit is running, exits the process with status 130 as an unhandled SIGINT would.

use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::Once;

static INTERRUPTS: AtomicU64 = AtomicU64::new(0);
static ACTIVE_RUNS: AtomicUsize = AtomicUsize::new(0);
static HANDLER: Once = Once::new();

/// The number of interrupts received so far; a run that started at generation `g` has been
/// interrupted once this differs from `g`.
pub(super) fn generation() -> u64 {
    INTERRUPTS.load(Ordering::SeqCst)
}

/// Install the process-wide handler (once; later calls do nothing).
pub(super) fn install_handler() {
    HANDLER.call_once(|| {
        // If another handler is already installed (e.g. by a direct argmin Executor run),
        // Ctrl-C keeps working through that one; nothing else to do.
        let _ = ctrlc::set_handler(|| {
            if ACTIVE_RUNS.load(Ordering::SeqCst) == 0 {
                std::process::exit(130);
            }
            INTERRUPTS.fetch_add(1, Ordering::SeqCst);
        });
    });
}

/// Marks a run as active for as long as it lives (the handler then interrupts instead of
/// exiting).
pub(super) struct ActiveRun;

impl ActiveRun {
    pub(super) fn start() -> Self {
        ACTIVE_RUNS.fetch_add(1, Ordering::SeqCst);
        ActiveRun
    }
}

impl Drop for ActiveRun {
    fn drop(&mut self) {
        ACTIVE_RUNS.fetch_sub(1, Ordering::SeqCst);
    }
}
