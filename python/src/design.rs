//! `goniofit.design`: the library's experimental design ([`goniofit::design`]) from Python.
//! Arrays in (degrees), the CLI's JSON report plus the candidates as arrays out; the design
//! and its simulation run with the GIL released.

use crate::convert::{json_to_py, to_py_err};
use crate::{options, run};
use goniofit::design::{self, before_and_after, Grid, NoiseModel, Request, Scene, Simulation};
use goniofit::report::{design_json as json, DesignRun as Run};
use goniofit::{AnglesDeg, Sample};
use numpy::{IntoPyArray, PyReadonlyArray1};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Three angle arrays (degrees) of one length as geometries.
type AngleArrays<'py> = (
    PyReadonlyArray1<'py, f64>,
    PyReadonlyArray1<'py, f64>,
    PyReadonlyArray1<'py, f64>,
);

fn angles(what: &str, a: &AngleArrays<'_>) -> PyResult<Vec<AnglesDeg>> {
    let (ti, tr, pr) = (a.0.as_slice()?, a.1.as_slice()?, a.2.as_slice()?);
    if ti.len() != tr.len() || ti.len() != pr.len() {
        return Err(PyValueError::new_err(format!(
            "{what}: theta_i, theta_r and phi_r have {}, {} and {} entries",
            ti.len(),
            tr.len(),
            pr.len()
        )));
    }
    (0..ti.len())
        .map(|k| {
            let g = AnglesDeg {
                theta_i: ti[k],
                theta_r: tr[k],
                phi_r: pr[k],
            };
            g.sample()
                .validate()
                .map_err(|m| PyValueError::new_err(format!("{what}, index {k}: {m}")))?;
            Ok(g)
        })
        .collect()
}

/// The engine of ``goniofit.design``: returns the JSON report as a dict with the
/// candidates added as arrays (``theta_i``, ``theta_r``, ``phi_r``, ``value``, ``gain``,
/// ``reachable``, ``chosen``).
#[pyfunction]
#[pyo3(signature = (model, params, existing, candidates, *, noise, residual="relative", wavelength=1.0, unit=None, quantity="radiance", theta_max=85.0, step=2.5, in_plane=false, n=20, target="all", dynamic_range=design::DYNAMIC_RANGE, wavelengths=Vec::new(), simulate=0, seed=1))]
#[allow(clippy::too_many_arguments)]
pub fn _design<'py>(
    py: Python<'py>,
    model: &str,
    params: &Bound<'py, PyAny>,
    existing: Option<AngleArrays<'py>>,
    candidates: Option<AngleArrays<'py>>,
    noise: f64,
    residual: &str,
    wavelength: f64,
    unit: Option<String>,
    quantity: &str,
    theta_max: f64,
    step: f64,
    in_plane: bool,
    n: usize,
    target: &str,
    dynamic_range: f64,
    wavelengths: Vec<f64>,
    simulate: usize,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let m = goniofit::model(model, &goniofit::ModelOptions::default()).map_err(to_py_err)?;
    let scene = Scene {
        model: m.as_ref(),
        params: options::param_vector(m.as_ref(), params)?,
        wavelength,
        quantity: options::quantity(quantity)?,
        noise: NoiseModel::new(options::residual(residual)?, noise).map_err(to_py_err)?,
        unit,
    };
    let request = Request {
        existing: existing_samples(existing.as_ref())?,
        candidates: candidate_angles(candidates.as_ref(), theta_max, step, in_plane)?,
        n,
        target: target.to_string(),
        dynamic_range,
        wavelengths,
    };
    let (d, sim, sim_before) = run::interruptible(py, None, None, || {
        design_and_simulate(&scene, &request, simulate, seed)
    })?;
    let report = json(&Run {
        design: &d,
        scene: &scene,
        source: if request.existing.is_empty() {
            "none"
        } else {
            "arrays"
        },
        simulation: sim.as_ref(),
        simulation_before: sim_before.as_ref(),
    });
    let out = json_to_py(py, &report)?.cast_into::<PyDict>()?;
    out.set_item("candidate_table", candidate_table(py, &d)?)?;
    Ok(out)
}

/// The measured geometries from the `existing` arrays (none without them); a length
/// mismatch or an invalid angle is a `ValueError` naming `existing` and the index.
fn existing_samples(existing: Option<&AngleArrays<'_>>) -> PyResult<Vec<Sample>> {
    Ok(match existing {
        Some(a) => angles("existing", a)?
            .iter()
            .map(AnglesDeg::sample)
            .collect(),
        None => Vec::new(),
    })
}

/// The candidate geometries: the `candidates` arrays when given (checked as
/// [`existing_samples`] checks its own), else the reachable grid up to `theta_max` degrees
/// in steps of `step` degrees (in the plane of incidence only with `in_plane`).
fn candidate_angles(
    candidates: Option<&AngleArrays<'_>>,
    theta_max: f64,
    step: f64,
    in_plane: bool,
) -> PyResult<Vec<AnglesDeg>> {
    match candidates {
        Some(a) => angles("candidates", a),
        None => options::checked(
            Grid {
                theta_max_deg: theta_max,
                step_deg: step,
                in_plane,
            }
            .angles(),
        ),
    }
}

/// The design, and with `simulate` ≥ 1 draws its simulation: (design, fits of simulated
/// measurements at the measured and chosen geometries, the same at the measured ones alone
/// when they outnumber the parameters). Both simulations use `seed`.
fn design_and_simulate(
    scene: &Scene,
    request: &Request,
    simulate: usize,
    seed: u64,
) -> goniofit::Result<(design::Design, Option<Simulation>, Option<Simulation>)> {
    let d = design::design(scene, request)?;
    if simulate == 0 {
        return Ok((d, None, None));
    }
    let (before, after) =
        before_and_after(scene, &request.existing, &d.chosen, simulate, seed, None)?;
    Ok((d, Some(after), before))
}

/// The candidates as a dict of equal-length arrays: `theta_i`, `theta_r`, `phi_r` (degrees),
/// `value`, `gain` (floats), `reachable`, `chosen` (booleans), in the design's candidate
/// order.
fn candidate_table<'py>(py: Python<'py>, d: &design::Design) -> PyResult<Bound<'py, PyDict>> {
    let col = |f: &dyn Fn(&design::Candidate) -> f64| -> Vec<f64> {
        d.candidates.iter().map(f).collect()
    };
    let cand = PyDict::new(py);
    cand.set_item("theta_i", col(&|c| c.angles[0]).into_pyarray(py))?;
    cand.set_item("theta_r", col(&|c| c.angles[1]).into_pyarray(py))?;
    cand.set_item("phi_r", col(&|c| c.angles[2]).into_pyarray(py))?;
    cand.set_item("value", col(&|c| c.value).into_pyarray(py))?;
    cand.set_item("gain", col(&|c| c.gain).into_pyarray(py))?;
    let flag = |f: &dyn Fn(&design::Candidate) -> bool| -> Vec<bool> {
        d.candidates.iter().map(f).collect()
    };
    cand.set_item("reachable", flag(&|c| c.reachable).into_pyarray(py))?;
    cand.set_item("chosen", flag(&|c| c.chosen).into_pyarray(py))?;
    Ok(cand)
}
