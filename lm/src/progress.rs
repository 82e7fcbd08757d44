//! The terminal progress line (`--progress`) as an argmin observer.

use argmin::core::observers::Observe;
use argmin::core::{Error as ArgminError, State, KV};

use super::LmState;

/// Terminal progress line as an argmin observer.
pub(super) struct ProgressObserver {
    bar: indicatif::ProgressBar,
}

impl ProgressObserver {
    pub(super) fn new() -> Self {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.set_style(
            indicatif::ProgressStyle::with_template("{spinner} LM {elapsed} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
        );
        ProgressObserver { bar }
    }
}

impl Observe<LmState> for ProgressObserver {
    fn observe_iter(&mut self, state: &LmState, kv: &KV) -> Result<(), ArgminError> {
        let get = |k: &str| kv.get(k).and_then(|v| v.get_float()).unwrap_or(f64::NAN);
        self.bar.set_message(format!(
            "iter {:>5}  cost {:.9e}  Δ {:.3e}  λ {:.3e}",
            state.get_iter(),
            state.get_best_cost(),
            get("delta"),
            get("lambda"),
        ));
        self.bar.tick();
        Ok(())
    }

    fn observe_final(&mut self, _state: &LmState) -> Result<(), ArgminError> {
        self.bar.finish_and_clear();
        Ok(())
    }
}
