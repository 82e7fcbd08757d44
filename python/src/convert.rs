//! Library values → Python: errors (and panics) as exceptions, JSON values as Python
//! objects.

use goniofit::Error;
use pyo3::exceptions::{
    PyFileNotFoundError, PyOSError, PyRuntimeError, PyTimeoutError, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// A library error as a Python exception, `context` (e.g. a group's label) before the
/// message: `ValueError` for the user's input or usage (the message names file, line and
/// column, or array and index), `FileNotFoundError`/`OSError` for files, `RuntimeError`
/// for internal failures.
pub fn to_py_err_in(context: Option<&str>, e: Error) -> PyErr {
    let text = python_terms(&e.to_string());
    // Arrays passed in memory have no name worth printing.
    let msg = match context.filter(|c| *c != "arrays") {
        Some(c) => format!("{c}: {text}"),
        None => text,
    };
    match &e {
        Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            PyFileNotFoundError::new_err(msg)
        }
        Error::Io { .. } => PyOSError::new_err(msg),
        // The time limit came before the first model evaluation finished: nothing fitted.
        Error::Stopped(_) => PyTimeoutError::new_err(msg),
        _ if e.is_user_error() => PyValueError::new_err(msg),
        _ => PyRuntimeError::new_err(msg),
    }
}

/// A library message in a Python user's terms: the name the library gives arrays passed
/// in memory (`arrays: `) is dropped, and each command-line option (`--wavelength`,
/// `--signed-theta-r`, `--no-intervals`, `--by-group`) becomes the keyword argument that sets
/// it (`wavelength=`, `signed_theta_r=True`, `intervals=False`, `group=`).
pub fn python_terms(msg: &str) -> String {
    let mut rest = msg;
    while let Some(r) = rest.strip_prefix("arrays: ") {
        rest = r;
    }
    let mut out = String::with_capacity(rest.len());
    let mut chars = rest.char_indices().peekable();
    while let Some((i, c)) = chars.next() {
        let flag = c == '-'
            && rest[i..].starts_with("--")
            && rest[i + 2..].starts_with(|n: char| n.is_ascii_lowercase())
            && (i == 0 || !rest[..i].ends_with(|p: char| p.is_alphanumeric() || p == '-'));
        if !flag {
            out.push(c);
            continue;
        }
        let name: String = rest[i + 2..]
            .chars()
            .take_while(|n| n.is_ascii_alphanumeric() || *n == '-')
            .collect();
        out.push_str(&keyword(&name));
        // Skip the rest of the flag (its two dashes and its name).
        for _ in 0..name.chars().count() + 1 {
            chars.next();
        }
    }
    out
}

/// The keyword argument that sets command-line option `--name`.
fn keyword(name: &str) -> String {
    match name {
        "signed-theta-r" | "radians" => format!("{}=True", name.replace('-', "_")),
        "no-intervals" => "intervals=False".to_string(),
        "no-reduce" => "reduce=False".to_string(),
        "by-group" => "group=".to_string(),
        _ => format!("{}=", name.replace('-', "_")),
    }
}

/// [`to_py_err_in`] without context.
pub fn to_py_err(e: Error) -> PyErr {
    to_py_err_in(None, e)
}

/// A JSON value as Python objects (null → None, numbers → int or float exactly as
/// serialised, objects → dict in key order).
pub fn json_to_py<'py>(py: Python<'py>, v: &serde_json::Value) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    Ok(match v {
        Value::Null => py.None().into_bound(py),
        Value::Bool(b) => b.into_pyobject(py)?.to_owned().into_any(),
        Value::Number(n) => match (n.as_i64(), n.as_u64()) {
            (Some(i), _) => i.into_pyobject(py)?.into_any(),
            (None, Some(u)) => u.into_pyobject(py)?.into_any(),
            _ => n.as_f64().unwrap_or(f64::NAN).into_pyobject(py)?.into_any(),
        },
        Value::String(s) => s.into_pyobject(py)?.into_any(),
        Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| json_to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            PyList::new(py, items)?.into_any()
        }
        Value::Object(m) => {
            let d = PyDict::new(py);
            for (k, x) in m {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

/// A panic's message as a `RuntimeError` (a panic is a bug: it must never cross into
/// Python as a crash).
pub fn panic_error(payload: Box<dyn std::any::Any + Send>) -> PyErr {
    let msg = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".into());
    PyRuntimeError::new_err(format!(
        "goniofit internal error (a bug, please report it): {msg}"
    ))
}

/// `f()`, with a panic turned into a `RuntimeError`.
pub fn guard<T>(f: impl FnOnce() -> T) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).map_err(panic_error)
}

#[cfg(test)]
mod tests {
    use super::python_terms;

    #[test]
    fn messages_name_keyword_arguments_not_options() {
        assert_eq!(
            python_terms("arrays: arrays: KBS models need a wavelength: give --wavelength, a wavelength column"),
            "KBS models need a wavelength: give wavelength=, a wavelength column"
        );
        assert_eq!(
            python_terms("theta_r[0]: -5 is negative (in-plane scans: --signed-theta-r)"),
            "theta_r[0]: -5 is negative (in-plane scans: signed_theta_r=True)"
        );
        assert_eq!(
            python_terms("use --f-scale 0.03 or --no-intervals"),
            "use f_scale= 0.03 or intervals=False"
        );
        assert_eq!(
            python_terms("a range 1e-3--1e5 and x −−y"),
            "a range 1e-3--1e5 and x −−y"
        );
    }
}
