//! Library values → Python: errors as exceptions, JSON values as Python objects.

use goniofit::Error;
use pyo3::exceptions::{
    PyFileNotFoundError, PyOSError, PyRuntimeError, PyTimeoutError, PyValueError,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// A library error as a Python exception, `context` (e.g. a group's label) before the
/// message: `ValueError` for the user's input or usage (the message names file, line and
/// column, or array and index), `FileNotFoundError`/`OSError` for files, `RuntimeError`
/// for internal failures.
pub fn to_py_err_in(context: Option<&str>, e: Error) -> PyErr {
    let msg = match context {
        Some(c) => format!("{c}: {e}"),
        None => e.to_string(),
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
