//! Ctrl-C during a fit: a real SIGINT to this process, handled as a host handles it (its
//! handler calls `stop::interrupt`), ends the run with `Termination::Interrupted` (and a
//! report), not a dead process. The signal reaches every fit running in the process, so
//! the other tests of this binary fit only in child processes.

#[cfg(unix)]
#[test]
fn sigint_interrupts_a_running_fit() {
    use goniofit::lm::{minimize, LeastSquaresProblem, LmConfig, Termination};
    use nalgebra::{DMatrix, DVector};
    use std::sync::atomic::{AtomicU64, Ordering};

    struct Slow(AtomicU64);
    impl LeastSquaresProblem for Slow {
        fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
            if self.0.fetch_add(1, Ordering::SeqCst) == 3 {
                let pid = std::process::id().to_string();
                let status = std::process::Command::new("kill")
                    .args(["-INT", &pid])
                    .status()
                    .expect("run kill");
                assert!(status.success());
                // Give the handler thread time to see the signal.
                std::thread::sleep(std::time::Duration::from_millis(200));
            }
            DVector::from_column_slice(&[10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0], 0.1])
        }
        fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
            DMatrix::from_row_slice(3, 2, &[-20.0 * x[0], 10.0, -1.0, 0.0, 0.0, 0.0])
        }
    }

    // The host's handler: the library installs none.
    ctrlc::set_handler(|| {
        goniofit::lm::stop::interrupt();
    })
    .expect("install the handler");
    let p = Slow(AtomicU64::new(0));
    let config = LmConfig {
        ftol: 0.0,
        xtol: 0.0,
        gtol: 0.0,
        ..LmConfig::default()
    };
    let rep = minimize(&p, DVector::from_column_slice(&[-1.2, 1.0]), &config);
    assert_eq!(rep.termination, Termination::Interrupted);
    assert_eq!(rep.evaluations, 4);
    // A later fit in the same process is not affected by the earlier Ctrl-C.
    let rep = minimize(
        &p,
        DVector::from_column_slice(&[-1.2, 1.0]),
        &LmConfig::default(),
    );
    assert!(rep.termination.converged(), "{:?}", rep.termination);
}
