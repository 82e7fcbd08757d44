//! Running fits from Python: panics caught at the boundary, the GIL released while rayon
//! threads fit, and Ctrl-C (Python's own SIGINT handler) turned into the library's
//! interrupt flag.

use crate::convert::{guard, panic_error, to_py_err, to_py_err_in};
use crate::options::{checked, FitOptions, PY};
use goniofit::settings;
use goniofit::{check_finite, fit_dataset_near, in_chains, Dataset, Geometry, Model, Outcome};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

/// How often the calling thread looks for a pending Ctrl-C while a fit runs.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// Run `work` on another thread with the GIL released (on a rayon pool of `threads`
/// threads, all cores when None), while this thread runs Python's signal handlers every
/// [`SIGNAL_POLL`]. On Ctrl-C (`KeyboardInterrupt` from a handler) `interrupt` is set, the
/// running fits end after their current step, and the handler's exception is returned.
pub fn interruptible<T: Send>(
    py: Python<'_>,
    interrupt: Option<Arc<AtomicBool>>,
    threads: Option<usize>,
    work: impl FnOnce() -> goniofit::Result<T> + Send,
) -> PyResult<T> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("thread pool: {e}")))?;
    let outcome = py.detach(|| {
        std::thread::scope(|s| {
            let (done_tx, done_rx) = mpsc::channel::<()>();
            let worker = s.spawn(move || {
                let r = catch_unwind(AssertUnwindSafe(|| pool.install(work)));
                let _ = done_tx.send(());
                r
            });
            let mut signal: Option<PyErr> = None;
            while let Err(mpsc::RecvTimeoutError::Timeout) = done_rx.recv_timeout(SIGNAL_POLL) {
                if signal.is_none() {
                    if let Err(e) = Python::attach(|py| py.check_signals()) {
                        if let Some(flag) = &interrupt {
                            flag.store(true, Ordering::SeqCst);
                        }
                        signal = Some(e);
                    }
                }
            }
            let joined = worker.join().unwrap_or_else(Err);
            (joined, signal)
        })
    });
    match outcome {
        (_, Some(signal)) => Err(signal),
        (Err(payload), None) => Err(panic_error(payload)),
        (Ok(r), None) => r.map_err(to_py_err),
    }
}

/// Samples per block of [`evaluate_interruptible`]: a pending Ctrl-C is seen between
/// blocks.
const EVAL_BLOCK: usize = 4096;

/// The model's values at `geo` and, with `jacobian`, its Jacobian (column-major, n × number
/// of parameters), computed with the GIL released one block of [`EVAL_BLOCK`] samples at a
/// time, so that Ctrl-C raises `KeyboardInterrupt` within one block's evaluation (every
/// evaluation's work is bounded, see `goniofit::model::series`). A single block is
/// evaluated directly (no thread to start), as its work is that bound. A value or
/// derivative that is not finite (parameters beyond double precision) is the `ValueError`
/// the command line's `eval` gives (exit 2 there).
pub fn evaluate_interruptible(
    py: Python<'_>,
    model: &dyn Model,
    p: &[f64],
    geo: &Geometry,
    jacobian: bool,
) -> PyResult<(Vec<f64>, Option<Vec<f64>>)> {
    let (values, jac) = evaluate_blocks(py, model, p, geo, jacobian)?;
    let n = geo.len();
    let check = |v: &[f64], what: &str| check_finite(model, p, geo, v, what);
    check(&values, "").map_err(to_py_err)?;
    if let Some(j) = &jac {
        for (column, spec) in j.chunks_exact(n.max(1)).zip(model.params()) {
            check(column, &format!("'s derivative by {}", spec.name)).map_err(to_py_err)?;
        }
    }
    Ok((values, jac))
}

/// The evaluation of [`evaluate_interruptible`], unchecked.
fn evaluate_blocks(
    py: Python<'_>,
    model: &dyn Model,
    p: &[f64],
    geo: &Geometry,
    jacobian: bool,
) -> PyResult<(Vec<f64>, Option<Vec<f64>>)> {
    let (n, k) = (geo.len(), p.len());
    if n <= EVAL_BLOCK {
        return guard(|| {
            let mut values = vec![0.0; n];
            let mut jac = jacobian.then(|| vec![0.0; n * k]);
            model.eval(geo, p, &mut values, jac.as_deref_mut());
            (values, jac)
        });
    }
    let flag = Arc::new(AtomicBool::new(false));
    let stop = flag.clone();
    interruptible(py, Some(flag), Some(1), move || {
        let mut values = vec![0.0; n];
        let mut jac = jacobian.then(|| vec![0.0; n * k]);
        for start in (0..n).step_by(EVAL_BLOCK) {
            if stop.load(Ordering::SeqCst) {
                return Err(goniofit::Error::Stopped("interrupted".into()));
            }
            let end = (start + EVAL_BLOCK).min(n);
            let len = end - start;
            let mut block_jac = jacobian.then(|| vec![0.0; len * k]);
            let block = geo.slice(start..end);
            model.eval(&block, p, &mut values[start..end], block_jac.as_deref_mut());
            if let (Some(all), Some(part)) = (jac.as_mut(), block_jac) {
                for (c, column) in part.chunks_exact(len).enumerate() {
                    all[c * n + start..c * n + end].copy_from_slice(column);
                }
            }
        }
        Ok((values, jac))
    })
}

/// The datasets of group codes `0..labels.len()` (`codes[i]`: the group of sample i),
/// labelled for the reports; a code out of range, or a group without samples, is an error
/// naming it.
pub fn split_codes(
    ds: &Dataset,
    codes: &[i64],
    labels: &[String],
) -> PyResult<Vec<(String, Dataset)>> {
    if codes.len() != ds.len() {
        return Err(PyValueError::new_err(format!(
            "group has {} elements, theta_i has {}: give one group per sample",
            codes.len(),
            ds.len()
        )));
    }
    let n_groups = labels.len();
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); n_groups];
    for (i, &c) in codes.iter().enumerate() {
        let k = usize::try_from(c)
            .ok()
            .filter(|&k| k < n_groups)
            .ok_or_else(|| {
                PyValueError::new_err(format!(
                    "codes[{i}]: {c} is not a group code in 0..{n_groups}"
                ))
            })?;
        members[k].push(i);
    }
    members
        .into_iter()
        .zip(labels)
        .map(|(idx, label)| {
            if idx.is_empty() {
                return Err(PyValueError::new_err(format!(
                    "group {label} has no samples"
                )));
            }
            Ok((label.clone(), ds.subset(&idx)))
        })
        .collect()
}

/// Fit every job in parallel (rayon, GIL released, Ctrl-C interrupts all of them); the
/// first failing job's error is raised with its label in front. `single`: one dataset (profile intervals unless `intervals=False`).
pub fn fit_all(
    py: Python<'_>,
    o: &FitOptions,
    jobs: Vec<(String, Dataset)>,
    single: bool,
) -> PyResult<Vec<Outcome>> {
    // All cores (rayon's default) unless the call names a count, capped at the cores.
    let threads = match o.settings.threads {
        Some(_) => Some(checked(settings::threads(PY, o.settings.threads))?.0),
        None => None,
    };
    let interrupt = Arc::new(AtomicBool::new(false));
    let stop = interrupt.clone();
    let warm = o.settings.warm_start && !single;
    let results = interruptible(py, Some(interrupt.clone()), threads, move || {
        Ok(in_chains(jobs, warm, |(label, ds), previous| {
            // After Ctrl-C the jobs not yet started are skipped (the call raises
            // KeyboardInterrupt and drops every result).
            if stop.load(Ordering::SeqCst) {
                return Err((label, goniofit::Error::Usage("interrupted".into())));
            }
            let near = previous.and_then(|r: &Result<Outcome, _>| r.as_ref().ok());
            let mut spec = o.settings.dataset_fit(&ds, single);
            spec.config.lm.interrupt = Some(interrupt.clone());
            let r = fit_dataset_near(&spec, label.clone(), ds, near);
            r.map_err(|e| (label, e))
        }))
    })?;
    results
        .into_iter()
        .map(|r| r.map_err(|(label, e)| to_py_err_in(Some(&label), e)))
        .collect()
}
