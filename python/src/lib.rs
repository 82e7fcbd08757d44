//! `goniofit._goniofit`: the Python binding of the goniofit library.
//!
//! A thin layer: numpy arrays in, the library's own types out. Arrays become an
//! [`io::arrays`] dataset (the readers' checks, errors naming array and index), the fit is
//! [`fit::dataset::fit_dataset`] (the CLI's path: candidates, BIC, joint-fit note) and the
//! reports are [`report::outcome`]'s, so a fit from Python prints and serialises exactly as
//! the CLI's. No physics or fitting logic lives here.
//!
//! Boundary rules: every library error becomes a Python exception (`ValueError` for the
//! user's input or usage, `OSError` for files, `RuntimeError` for internal failures); a
//! panic is caught ([`std::panic::catch_unwind`]) and becomes a `RuntimeError`; fits run
//! with the GIL released, on rayon threads, while the calling thread polls Python's signal
//! handlers so that Ctrl-C stops them (through the fit's stop flag; the interpreter keeps
//! its own signal handling).

mod convert;
mod design;
mod options;
mod result;
mod run;

use convert::{json_to_py, to_py_err};
use goniofit::settings;
use goniofit::{arrays, Geometry, ModelOptions, ReadOptions};
use numpy::{IntoPyArray, PyArrayMethods, PyReadonlyArray1};
use options::{FitOptions, SampleArrays};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use result::FitResult;
use std::path::PathBuf;

/// Fit a model to one measurement: float64 arrays in (angles in degrees unless
/// ``radians=True``), a ``FitResult`` out. The public ``goniofit.fit`` converts array-likes
/// and documents every option.
#[pyfunction]
#[pyo3(signature = (theta_i, theta_r, phi_r, L, **options))]
#[allow(non_snake_case)]
fn _fit<'py>(
    py: Python<'py>,
    theta_i: PyReadonlyArray1<'py, f64>,
    theta_r: PyReadonlyArray1<'py, f64>,
    phi_r: PyReadonlyArray1<'py, f64>,
    L: PyReadonlyArray1<'py, f64>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<FitResult> {
    let opts = FitOptions::from_kwargs(options)?;
    let ds = SampleArrays::new(&opts, &theta_i, &theta_r, &phi_r, &L)?.dataset(&opts)?;
    let mut outcomes = run::fit_all(py, &opts, vec![("arrays".to_string(), ds)], true)?;
    let outcome = outcomes.pop().expect("one job, one outcome");
    Ok(FitResult::new(outcome, &opts))
}

/// The engine of ``fit(group=...)``, ``fit_many`` and ``fit_frame``: fit the samples of
/// every group code ``0..n_groups`` on its own, in parallel with the GIL released
/// (``codes``: one code per sample, as ``pandas.factorize`` returns; ``labels``: the name of
/// each group in reports). Returns the ``FitResult`` list, or with ``summary=True`` the
/// summary columns (one entry per group) as a dict of arrays and lists.
#[pyfunction]
#[pyo3(signature = (theta_i, theta_r, phi_r, L, codes, labels, summary, **options))]
#[allow(non_snake_case, clippy::too_many_arguments)]
fn _fit_codes<'py>(
    py: Python<'py>,
    theta_i: PyReadonlyArray1<'py, f64>,
    theta_r: PyReadonlyArray1<'py, f64>,
    phi_r: PyReadonlyArray1<'py, f64>,
    L: PyReadonlyArray1<'py, f64>,
    codes: PyReadonlyArray1<'py, i64>,
    labels: Vec<String>,
    summary: bool,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<Py<PyAny>> {
    let opts = FitOptions::from_kwargs(options)?;
    let ds = SampleArrays::new(&opts, &theta_i, &theta_r, &phi_r, &L)?.dataset(&opts)?;
    let jobs = run::split_codes(&ds, codes.as_slice()?, &labels)?;
    let outcomes = run::fit_all(py, &opts, jobs, false)?;
    if summary {
        return Ok(result::summary_columns(py, &outcomes)?.into_any().unbind());
    }
    let results: Vec<FitResult> = outcomes
        .into_iter()
        .map(|o| FitResult::new(o, &opts))
        .collect();
    Ok(results.into_pyobject(py)?.into_any().unbind())
}

/// Evaluate a model at sample angles (degrees unless ``radians=True``): returns the values
/// (radiance, or BRDF with ``quantity="brdf"``), and with ``jacobian=True`` also the
/// analytic Jacobian, shape (n, number of parameters), columns in the model's parameter
/// order. ``params``: a dict name → value, or a sequence in the model's order.
/// ``fresnel`` and ``shadowing``: the factors on a KBS lobe (the CLI's ``--fresnel``,
/// ``--shadowing``; ``n``, ``kappa`` then follow ``scale`` among the parameters).
#[pyfunction]
#[pyo3(signature = (model, params, theta_i, theta_r, phi_r, *, wavelength=None, quantity="radiance", mode="auto", tol=1e-10, patch=None, jacobian=false, radians=false, fresnel="none", shadowing="none"))]
#[allow(clippy::too_many_arguments)]
fn evaluate<'py>(
    py: Python<'py>,
    model: &str,
    params: &Bound<'py, PyAny>,
    theta_i: PyReadonlyArray1<'py, f64>,
    theta_r: PyReadonlyArray1<'py, f64>,
    phi_r: PyReadonlyArray1<'py, f64>,
    wavelength: Option<&Bound<'py, PyAny>>,
    quantity: &str,
    mode: &str,
    tol: f64,
    patch: Option<(f64, f64)>,
    jacobian: bool,
    radians: bool,
    fresnel: &str,
    shadowing: &str,
) -> PyResult<Py<PyAny>> {
    let model_opts = ModelOptions {
        fresnel: options::fresnel(fresnel)?,
        shadowing: options::shadowing(shadowing)?,
        ..options::checked(settings::model_options(
            options::PY,
            options::eval_mode(mode)?,
            tol,
            patch,
        ))?
    };
    let m = goniofit::model(model, &model_opts).map_err(to_py_err)?;
    let p = options::param_vector(m.as_ref(), params)?;
    let quantity = options::quantity(quantity)?;
    let (ti, tr, pr) = (theta_i.as_slice()?, theta_r.as_slice()?, phi_r.as_slice()?);
    let lambda = match wavelength {
        None => vec![1.0],
        Some(w) => options::per_sample(w, ti.len(), "wavelength")?,
    };
    for &l in &lambda {
        options::checked(settings::length(options::PY, "wavelength", l))?;
    }
    let cols = arrays::Columns {
        theta_i: ti,
        theta_r: tr,
        phi_r: pr,
        wavelength: (lambda.len() > 1).then_some(&lambda[..]),
        ..arrays::Columns::default()
    };
    let ds = arrays::dataset("arrays", &cols, radians, false).map_err(to_py_err)?;
    let geo =
        convert::guard(|| Geometry::new(&ds.samples, &lambda, quantity))?.map_err(to_py_err)?;
    let (values, jac) = run::evaluate_interruptible(py, m.as_ref(), &p, &geo, jacobian)?;
    let values = values.into_pyarray(py);
    match jac {
        None => Ok(values.into_any().unbind()),
        Some(j) => {
            // Column-major (n × p) from the model: as a (p, n) row-major array, transposed.
            let k = p.len();
            let arr = numpy::PyArray1::from_vec(py, j).reshape([k, values.len()?])?;
            let t = arr.call_method0("transpose")?;
            Ok((values, t).into_pyobject(py)?.into_any().unbind())
        }
    }
}

/// Read a measurement file (CSV, ASTM E1392, the NIST PTFE layout) into a dict of numpy
/// arrays: ``theta_i``, ``theta_r``, ``phi_r`` (degrees, or radians with ``radians=True``,
/// in goniofit's convention: φr = 0 the forward side), and where the file has them ``L``,
/// ``weights``, ``sigma_L``, ``wavelength``, ``channel`` (labels). ``channel``: an ASTM
/// channel such as ``"550nm"``, an RGL ``.bsdf`` channel (``"r"``, ``"g"``, ``"b"``), or
/// ``"all"``; ``csv_radians``, ``columns``,
/// ``signed_theta_r``: the CLI's ``--radians``, ``--columns``, ``--signed-theta-r``.
/// Errors carry the CLI's located messages (file, line, column, value) as ``ValueError``;
/// a missing file is ``FileNotFoundError``. Degrees are converted from the radians the
/// reader stores (one rounding): ``radians=True`` here and in ``fit`` reproduces the CLI's
/// numbers bit for bit.
#[pyfunction]
#[pyo3(signature = (path, channel=None, *, radians=false, csv_radians=false, columns=None, signed_theta_r=false, require_value=false, subsample=1))]
#[allow(clippy::too_many_arguments)]
fn read<'py>(
    py: Python<'py>,
    path: PathBuf,
    channel: Option<String>,
    radians: bool,
    csv_radians: bool,
    columns: Option<&str>,
    signed_theta_r: bool,
    require_value: bool,
    subsample: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let ds = convert::guard(|| {
        let opts = ReadOptions {
            radians: csv_radians,
            signed_theta_r,
            columns: goniofit::parse_columns(columns.unwrap_or(""))?,
            require_value,
            channel,
            subsample,
        };
        // The file's angles (CSV: degrees, or radians with `csv_radians`; ASTM: radians)
        // are handed back in the unit asked for (`radians`).
        let ds = goniofit::read(&path, &opts)?;
        Ok::<_, goniofit::Error>(ds)
    })?
    .map_err(to_py_err)?;
    let out = PyDict::new(py);
    let angle = |f: fn(&goniofit::Sample) -> f64| -> Vec<f64> {
        ds.samples
            .iter()
            .map(|s| if radians { f(s) } else { f(s).to_degrees() })
            .collect()
    };
    out.set_item("theta_i", angle(|s| s.theta_i).into_pyarray(py))?;
    out.set_item("theta_r", angle(|s| s.theta_r).into_pyarray(py))?;
    out.set_item("phi_r", angle(|s| s.phi_r).into_pyarray(py))?;
    if let Some(v) = &ds.value {
        out.set_item("L", v.clone().into_pyarray(py))?;
    }
    if let Some(s) = &ds.sigma_l {
        out.set_item("sigma_L", s.clone().into_pyarray(py))?;
    } else if let Some(w) = &ds.weight {
        out.set_item("weights", w.clone().into_pyarray(py))?;
    }
    if let Some(w) = &ds.wavelength {
        out.set_item("wavelength", w.clone().into_pyarray(py))?;
    }
    if let Some(c) = &ds.channel {
        out.set_item("channel", PyList::new(py, c)?)?;
    }
    if let Some(u) = &ds.wavelength_unit {
        out.set_item("wavelength_unit", u)?;
    }
    Ok(out)
}

/// The models goniofit knows, with their parameters: name → list of (parameter, unit, doc).
#[pyfunction]
fn models(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let out = PyDict::new(py);
    for name in goniofit::MODEL_NAMES {
        let m = goniofit::model(name, &ModelOptions::default()).map_err(to_py_err)?;
        let specs: Vec<(String, String, String)> = m
            .params()
            .iter()
            .map(|s| (s.name.to_string(), s.unit.to_string(), s.doc.to_string()))
            .collect();
        out.set_item(name, specs)?;
    }
    Ok(out)
}

/// A JSON text as Python objects (used by the pure-Python layer for stored reports).
#[pyfunction]
fn _json_roundtrip<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    let v: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    json_to_py(py, &v)
}

#[pymodule]
fn _goniofit(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(_fit, m)?)?;
    m.add_function(wrap_pyfunction!(_fit_codes, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(models, m)?)?;
    m.add_function(wrap_pyfunction!(_json_roundtrip, m)?)?;
    m.add_function(wrap_pyfunction!(design::_design, m)?)?;
    m.add_class::<FitResult>()?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("AUTO_CANDIDATES", goniofit::AUTO_CANDIDATES.to_vec())?;
    Ok(())
}
