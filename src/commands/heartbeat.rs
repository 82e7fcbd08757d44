//! Progress lines for a run whose standard error is not a terminal (a pipe, a log file, a
//! batch system): nothing for the first [`FIRST`], then one line every [`EVERY`] with the
//! time so far, the stage, and for a batch the datasets done of the total with an estimate
//! of the time left. A terminal gets indicatif's bars and spinners instead; `--quiet`
//! silences both.

use std::io::IsTerminal;
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// Quiet time before the first line: short runs print nothing.
pub(crate) const FIRST: Duration = Duration::from_secs(2);
/// Time between lines.
pub(crate) const EVERY: Duration = Duration::from_secs(5);

/// What the run is doing now.
#[derive(Debug, Default)]
struct State {
    stage: String,
    done: u64,
    total: u64,
    /// When `done` started counting (the batch's start).
    counting_since: Option<Instant>,
}

/// The progress line writer; lines stop when it is dropped.
pub(crate) struct Heartbeat {
    state: Arc<Mutex<State>>,
    quit: Option<Sender<()>>,
    thread: Option<JoinHandle<()>>,
}

impl Heartbeat {
    /// Lines on standard error when `enabled` and standard error is not a terminal;
    /// otherwise a heartbeat that records the stage and prints nothing.
    pub(crate) fn start(enabled: bool) -> Heartbeat {
        Heartbeat::to(enabled && !std::io::stderr().is_terminal(), |line| {
            eprintln!("{line}")
        })
    }

    /// Lines to `write` when `enabled` (the writer runs on the heartbeat's own thread).
    pub(crate) fn to(enabled: bool, write: impl Fn(&str) + Send + 'static) -> Heartbeat {
        Heartbeat::timed(enabled, (FIRST, EVERY), write)
    }

    /// [`Heartbeat::to`] with the first line after `first` and then one every `every`.
    fn timed(
        enabled: bool,
        (first, every): (Duration, Duration),
        write: impl Fn(&str) + Send + 'static,
    ) -> Heartbeat {
        let state = Arc::new(Mutex::new(State::default()));
        if !enabled {
            return Heartbeat {
                state,
                quit: None,
                thread: None,
            };
        }
        let (quit, rx) = mpsc::channel::<()>();
        let shared = Arc::clone(&state);
        let t0 = Instant::now();
        let thread = std::thread::spawn(move || {
            let mut wait = first;
            while let Err(RecvTimeoutError::Timeout) = rx.recv_timeout(wait) {
                if let Ok(s) = shared.lock() {
                    write(&line(&s, t0.elapsed()));
                }
                wait = every;
            }
        });
        Heartbeat {
            state,
            quit: Some(quit),
            thread: Some(thread),
        }
    }

    /// The stage, in words ("reading data/x.csv", "fitting 40 datasets").
    pub(crate) fn stage(&self, stage: impl Into<String>) {
        if let Ok(mut s) = self.state.lock() {
            s.stage = stage.into();
        }
    }

    /// Start counting `total` datasets.
    pub(crate) fn count(&self, total: u64) {
        if let Ok(mut s) = self.state.lock() {
            (s.done, s.total, s.counting_since) = (0, total, Some(Instant::now()));
        }
    }

    /// One more dataset done.
    pub(crate) fn inc(&self) {
        if let Ok(mut s) = self.state.lock() {
            s.done += 1;
        }
    }
}

impl Drop for Heartbeat {
    fn drop(&mut self) {
        drop(self.quit.take());
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// One progress line: "goniofit: 12 s: fitting 40 datasets: 17 of 40 done, about 16 s left".
fn line(s: &State, elapsed: Duration) -> String {
    let mut out = format!("goniofit: {} s: {}", elapsed.as_secs(), s.stage);
    if s.total > 0 {
        out += &format!(": {} of {} done", s.done, s.total);
        if let (Some(since), true) = (s.counting_since, s.done > 0) {
            let per = since.elapsed().as_secs_f64() / s.done as f64;
            let left = per * (s.total - s.done.min(s.total)) as f64;
            out += &format!(", about {} left", duration_text(left));
        }
    }
    out
}

/// Seconds in words a reader takes in at a glance: "16 s", "4 min", "2.5 h".
fn duration_text(secs: f64) -> String {
    if secs < 90.0 {
        format!("{} s", secs.round())
    } else if secs < 5400.0 {
        format!("{} min", (secs / 60.0).round())
    } else {
        format!("{:.1} h", secs / 3600.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_line_says_the_stage_the_count_and_the_time_left() {
        let s = State {
            stage: "fitting 40 datasets".into(),
            done: 10,
            total: 40,
            counting_since: Some(Instant::now() - Duration::from_secs(20)),
        };
        let l = line(&s, Duration::from_secs(22));
        // 2 s a dataset, 30 left: 60 s.
        assert_eq!(
            l,
            "goniofit: 22 s: fitting 40 datasets: 10 of 40 done, about 60 s left"
        );
        let single = State {
            stage: "fitting data/x.astm".into(),
            ..State::default()
        };
        assert_eq!(
            line(&single, Duration::from_secs(7)),
            "goniofit: 7 s: fitting data/x.astm"
        );
        assert_eq!(duration_text(300.0), "5 min");
        assert_eq!(duration_text(9000.0), "2.5 h");
    }

    #[test]
    fn nothing_is_written_before_the_first_interval_or_when_disabled() {
        let lines = Arc::new(Mutex::new(Vec::<String>::new()));
        let sink = Arc::clone(&lines);
        let hb = Heartbeat::to(true, move |l| sink.lock().unwrap().push(l.to_string()));
        hb.stage("fitting");
        drop(hb);
        assert!(
            lines.lock().unwrap().is_empty(),
            "a run shorter than FIRST prints nothing"
        );
        let hb = Heartbeat::to(false, |_| panic!("disabled"));
        hb.stage("x");
    }

    #[test]
    fn a_long_run_gets_a_line_per_interval_with_its_count() {
        let lines = Arc::new(Mutex::new(Vec::<String>::new()));
        let sink = Arc::clone(&lines);
        let ms = Duration::from_millis;
        let hb = Heartbeat::timed(true, (ms(50), ms(100)), move |l| {
            sink.lock().unwrap().push(l.to_string())
        });
        hb.stage("fitting 4 datasets");
        hb.count(4);
        hb.inc();
        std::thread::sleep(ms(400));
        drop(hb);
        let lines = lines.lock().unwrap();
        assert!((2..=6).contains(&lines.len()), "{lines:?}");
        assert!(lines[0].starts_with("goniofit: 0 s: fitting 4 datasets: 1 of 4 done, about "));
    }
}
