//! The command line's handling of Ctrl-C, SIGTERM and SIGHUP: while goniofit is computing
//! (a fit, a batch, a recovery run: any live stop request of the library), a signal stops
//! that work, which then reports its best point (exit 3, or 130 for `recover`); at any
//! other moment it removes the unfinished output temporaries and ends the process with
//! exit 130, as an unhandled SIGINT would.

/// Install the handler (once, at the start of `main`). If another handler is already
/// installed, signals keep their previous behaviour.
pub(crate) fn install() {
    let _ = ctrlc::set_handler(|| {
        if !goniofit_lm::stop::interrupt() {
            crate::io::output::remove_temporaries();
            std::process::exit(130);
        }
    });
}
