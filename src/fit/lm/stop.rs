//! Stop requests: Ctrl-C, SIGTERM, SIGHUP, a caller's flag and a deadline, shared by every
//! stage of a fit through one [`Stop`].
//!
//! argmin's Executor installs its own handler bound to the flag of the *first* run in the
//! process (later runs cannot be interrupted, and Ctrl-C is swallowed between runs). Instead
//! [`super::minimize`] turns the Executor's handler off, and one process-wide handler
//! (installed on first use) bumps a global generation counter while any [`Stop`] is alive
//! (every running solver and every evaluation that checks the token sees the change). When
//! none is alive — nothing is being computed — it runs the cleanup registered with
//! [`on_exit`] (the command line removes its unfinished output temporaries there) and exits
//! the process with status 130, as an unhandled SIGINT would.

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Once, OnceLock};
use std::time::{Duration, Instant};

use super::Termination;

static INTERRUPTS: AtomicU64 = AtomicU64::new(0);
static ACTIVE_RUNS: AtomicUsize = AtomicUsize::new(0);
static HANDLER: Once = Once::new();
static CLEANUP: OnceLock<fn()> = OnceLock::new();

/// Install the process-wide handler (once; later calls do nothing). A [`Stop`] installs it
/// on first use; a program that wants Ctrl-C handled the same way everywhere (also while
/// nothing is being fitted) calls this at its start.
pub fn install_handler() {
    HANDLER.call_once(|| {
        // If another handler is already installed (e.g. by a direct argmin Executor run),
        // Ctrl-C keeps working through that one; nothing else to do.
        let _ = ctrlc::set_handler(|| {
            if ACTIVE_RUNS.load(Ordering::SeqCst) == 0 {
                if let Some(cleanup) = CLEANUP.get() {
                    cleanup();
                }
                std::process::exit(130);
            }
            INTERRUPTS.fetch_add(1, Ordering::SeqCst);
        });
    });
}

/// Register `cleanup`, run by the handler just before it ends the process (a signal while no
/// [`Stop`] is alive). Only the first registration counts. It runs on the handler's thread
/// while other threads may still be working, so it must be safe to call at any time.
pub fn on_exit(cleanup: fn()) {
    let _ = CLEANUP.set(cleanup);
}

/// Marks work in progress for as long as it lives (the handler then interrupts instead of
/// exiting).
#[derive(Debug)]
struct Active;

impl Active {
    fn start() -> Self {
        ACTIVE_RUNS.fetch_add(1, Ordering::SeqCst);
        Active
    }
}

impl Drop for Active {
    fn drop(&mut self) {
        ACTIVE_RUNS.fetch_sub(1, Ordering::SeqCst);
    }
}

/// One stop request for a whole piece of work (a fit with its start search, solves and
/// refits, or a whole command): clones share it. It is requested once Ctrl-C, SIGTERM or
/// SIGHUP arrived after it was made, the caller's flag became true, or the deadline passed.
/// While any `Stop` is alive, those signals interrupt instead of ending the process.
/// Checking costs two atomic loads and, with a deadline, one clock read (≈ 20 ns).
#[derive(Debug, Clone)]
pub struct Stop(Arc<StopInner>);

#[derive(Debug)]
struct StopInner {
    deadline: Option<Instant>,
    generation: u64,
    flag: Option<Arc<AtomicBool>>,
    _active: Active,
}

impl Stop {
    /// A stop request that fires `timeout` from now (never without one), on a signal from
    /// now on, or when `flag` becomes true.
    pub fn new(timeout: Option<Duration>, flag: Option<Arc<AtomicBool>>) -> Stop {
        install_handler();
        Stop::without_handler(timeout, flag)
    }

    /// As [`Stop::new`], but without installing goniofit's signal handler, for a host that
    /// owns the signals (the Python interpreter): only `flag` and the deadline (and the
    /// signals, if the handler was installed by an earlier [`Stop::new`]) stop the work.
    pub fn without_handler(timeout: Option<Duration>, flag: Option<Arc<AtomicBool>>) -> Stop {
        let active = Active::start();
        Stop(Arc::new(StopInner {
            // A limit beyond what the clock can represent is no limit.
            deadline: timeout.and_then(|t| Instant::now().checked_add(t)),
            generation: INTERRUPTS.load(Ordering::SeqCst),
            flag,
            _active: active,
        }))
    }

    /// A stop request for one part of this piece of work with a time limit of its own: it
    /// is requested when this one is (the same signals and flag, from this one's start), or
    /// once `timeout` from now has passed (or this one's deadline, if sooner). A timeout too
    /// large for the clock is no limit.
    pub fn part(&self, timeout: Option<Duration>) -> Stop {
        let own = timeout.and_then(|t| Instant::now().checked_add(t));
        let deadline = match (self.0.deadline, own) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        Stop(Arc::new(StopInner {
            deadline,
            generation: self.0.generation,
            flag: self.0.flag.clone(),
            _active: Active::start(),
        }))
    }

    /// Why the work must stop, if it must: [`Termination::Interrupted`] (a signal or the
    /// flag; it wins over a deadline that passed too) or [`Termination::Timeout`].
    pub fn requested(&self) -> Option<Termination> {
        let s = &self.0;
        if INTERRUPTS.load(Ordering::SeqCst) != s.generation
            || s.flag.as_ref().is_some_and(|f| f.load(Ordering::SeqCst))
        {
            Some(Termination::Interrupted)
        } else if s.deadline.is_some_and(|d| Instant::now() >= d) {
            Some(Termination::Timeout)
        } else {
            None
        }
    }

    /// Whether [`Self::requested`] has a reason.
    pub fn is_requested(&self) -> bool {
        self.requested().is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_part_stops_with_its_whole_and_at_its_own_deadline() {
        let flag = Arc::new(AtomicBool::new(false));
        let whole = Stop::without_handler(None, Some(flag.clone()));
        let part = whole.part(Some(Duration::from_millis(30)));
        let unlimited = whole.part(None);
        // A limit past the clock's range is no limit (no overflow).
        let huge = whole.part(Some(Duration::from_secs(u64::MAX)));
        assert_eq!(part.requested(), None);
        std::thread::sleep(Duration::from_millis(40));
        assert_eq!(part.requested(), Some(Termination::Timeout));
        for other in [&whole, &unlimited, &huge] {
            assert_eq!(other.requested(), None);
        }
        flag.store(true, Ordering::SeqCst);
        for s in [&whole, &part, &unlimited, &huge] {
            assert_eq!(s.requested(), Some(Termination::Interrupted));
        }
    }
}
