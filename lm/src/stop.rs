//! Stop requests: a signal, a caller's flag and a deadline, shared by every stage of a fit
//! through one [`Stop`].
//!
//! The library installs no signal handler: the host owns its signals. A host that wants
//! Ctrl-C, SIGTERM or SIGHUP to stop running work calls [`interrupt`] from its handler: while
//! any [`Stop`] is alive it bumps a global generation counter that every running solver and
//! every evaluation that checks the token sees, and returns true; when none is alive
//! (nothing is being computed) it returns false and the host ends as it sees fit (the
//! command line removes its unfinished outputs and exits with 130). argmin is built
//! without its Ctrl-C handler. A host that owns its signals otherwise
//! (the Python interpreter) sets a [`Stop`]'s flag instead.

use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::Termination;

static INTERRUPTS: AtomicU64 = AtomicU64::new(0);
static ACTIVE_RUNS: AtomicUsize = AtomicUsize::new(0);

/// A signal arrived: every [`Stop`] alive now is requested, and true is returned; false
/// when no [`Stop`] is alive (nothing to stop: the caller decides what the signal does).
/// Safe to call from any thread at any time (two atomic operations).
pub fn interrupt() -> bool {
    if ACTIVE_RUNS.load(Ordering::SeqCst) == 0 {
        return false;
    }
    INTERRUPTS.fetch_add(1, Ordering::SeqCst);
    true
}

/// Marks work in progress for as long as it lives ([`interrupt`] then stops it).
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
/// refits, or a whole command): clones share it. It is requested once an [`interrupt`]
/// came after it was made (the host's signal handler), the caller's flag became true, or
/// the deadline passed.
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
    /// A stop request that fires `timeout` from now (never without one), on an
    /// [`interrupt`] from now on, or when `flag` becomes true.
    pub fn new(timeout: Option<Duration>, flag: Option<Arc<AtomicBool>>) -> Stop {
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
        let whole = Stop::new(None, Some(flag.clone()));
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
