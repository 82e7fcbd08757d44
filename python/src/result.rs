//! `FitResult`: a finished fit as Python sees it, every field taken from the library's
//! report of the outcome (the CLI's JSON report, [`report::outcome::report`]), so that
//! `to_dict()` is the CLI's `--json` key for key; and the summary columns of many fits.

use crate::convert::json_to_py;
use crate::convert::to_py_err;
use crate::options::{FitOptions, PY};
use goniofit::report::{self, InputInfo, RunInfo};
use goniofit::{plot, FitConfig, FitReport, Outcome, Settings};
use numpy::IntoPyArray;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use serde_json::Value;
use std::sync::OnceLock;

/// A finished fit (converged or not: see ``converged`` and ``termination``).
///
/// ``params`` and ``derived`` map a name to ``{"value", "stderr", "determined", "fixed",
/// "unit"}`` (``derived``: ``"doc"`` instead of ``"fixed"``/``"unit"``) exactly as the
/// CLI's JSON report; σ and T are in the unit of the wavelength, angles in the report's
/// ``w`` in radians. ``cost`` is ½ Σ wᵢ rᵢ². ``L_fit`` and ``residuals`` (fitted − measured
/// in the chosen residual form, unweighted) are numpy arrays in sample order.
#[pyclass(frozen, module = "goniofit")]
pub struct FitResult {
    outcome: Outcome,
    info: RunInfo,
    settings: Settings,
    report: OnceLock<FitReport>,
    json: OnceLock<Value>,
    /// The settings the pictures need (the chosen model with its factors, residual kind,
    /// floor), and the unit of λ they name.
    config: FitConfig,
    unit: Option<String>,
}

impl FitResult {
    /// The result of `outcome`, fitted with options `o` (the report's `command` is the
    /// equivalent CLI command).
    pub fn new(outcome: Outcome, o: &FitOptions) -> Self {
        let settings = o.settings.clone();
        let info = RunInfo {
            input: outcome.label.clone(),
            command: format!("{} ({})", settings.command_line(), outcome.label),
            version: env!("CARGO_PKG_VERSION").to_string(),
            setting: report::setting(
                &outcome.dataset,
                &outcome.input,
                (&settings, PY),
                InputInfo::default(),
            ),
            intervals: outcome.intervals.clone(),
            interval_seconds: outcome.interval_seconds,
        };
        let uncertainties = o.sigma_l.is_some();
        let config = settings.fit_config(&outcome.result.full_model(), uncertainties);
        let unit = settings.wavelength_unit(&outcome.dataset);
        FitResult {
            outcome,
            info,
            settings,
            report: OnceLock::new(),
            json: OnceLock::new(),
            config,
            unit,
        }
    }

    /// The CLI's report of this fit (built once).
    fn typed_report(&self) -> &FitReport {
        self.report
            .get_or_init(|| report::fit_report(&self.outcome, &self.info, &self.settings))
    }

    /// The report as a JSON value (built once).
    fn json(&self) -> &Value {
        self.json.get_or_init(|| self.typed_report().to_value())
    }

    /// The pictures' status line and the parameters the data does not determine.
    fn status(&self) -> (String, Vec<String>) {
        (
            self.typed_report().status_line(),
            self.typed_report().undetermined(),
        )
    }

    /// The report's pictures as (name, SVG document).
    fn svg_figures(&self) -> PyResult<Vec<(String, String)>> {
        let (line, undetermined) = self.status();
        plot::svg_of_outcome(
            &self.config,
            &self.outcome,
            (&line, &undetermined),
            self.unit.as_deref(),
        )
        .map_err(to_py_err)
    }

    fn field<'py>(&self, py: Python<'py>, key: &str) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, &self.json()[key])
    }
}

#[pymethods]
impl FitResult {
    /// The fitted model's name (the winner of ``model="auto"``).
    #[getter]
    fn model(&self) -> &str {
        &self.outcome.result.model
    }

    /// The lobe's factors as CLI options (``"--fresnel dielectric --shadowing smith"``),
    /// empty for the paper's model (the JSON report's ``factors``).
    #[getter]
    fn factors(&self) -> &str {
        self.outcome.result.factors.trim()
    }

    /// Parameter name → {value, stderr, determined, fixed, unit}.
    #[getter]
    fn params<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, "params")
    }

    /// Derived quantity name → {value, stderr, determined, doc} (T/sigma, rms slope,
    /// the amplitude the rough regime determines, ...).
    #[getter]
    fn derived<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, "derived")
    }

    /// ½ Σ wᵢ rᵢ² at the optimum (the solver's cost, as MINPACK and scipy).
    #[getter]
    fn cost(&self) -> f64 {
        self.outcome.result.cost
    }

    /// Whether the solver met a convergence criterion (a usable optimum).
    #[getter]
    fn converged(&self) -> bool {
        self.outcome.result.converged()
    }

    /// Why the solver stopped: ``ftol``, ``xtol``, ``gtol``, ``predicted`` (converged) or
    /// ``maxiterations``, ``maxevaluations``, ``timeout``, ``interrupted``, ...
    #[getter]
    fn termination<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, "termination")
    }

    /// What the data determines: ``full``, ``rough`` (only T/σ and the amplitude),
    /// ``smooth`` (only T and s·σ²) or ``partial``.
    #[getter]
    fn verdict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, "verdict")
    }

    /// Whether the model describes the data and the weights match the noise: ``{"verdict":
    /// "adequate" | "misfit" | "noise" | "not_computed" | "exact", "headline", "reasons": [{"code",
    /// "text", "p"}], "alpha", "tests", "r2", "reduced_chi2", "chi2_p", "runs", "spread",
    /// "regions"}``, as the CLI's JSON ``adequacy`` (a verdict, not a failure).
    #[getter]
    fn adequacy<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        self.field(py, "adequacy")
    }

    /// The report's notes (plain-language statements about the fit).
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.outcome.result.notes.clone()
    }

    /// The fitted values (radiance or BRDF, as measured) per sample; empty (as
    /// ``residuals`` and ``std_residuals``) when a time limit or interrupt cut their
    /// evaluation after the solve (a fit whose evaluations are slow; the notes say so).
    #[getter]
    #[allow(non_snake_case)]
    fn L_fit<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        self.outcome.result.fitted.clone().into_pyarray(py)
    }

    /// The residuals per sample (fitted − measured in the chosen residual form, unweighted).
    #[getter]
    fn residuals<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        self.outcome.result.residuals.clone().into_pyarray(py)
    }

    /// Standardised residuals √wᵢ rᵢ / s per sample.
    #[getter]
    fn std_residuals<'py>(&self, py: Python<'py>) -> Bound<'py, numpy::PyArray1<f64>> {
        self.outcome.result.std_residuals.clone().into_pyarray(py)
    }

    /// Number of samples fitted.
    #[getter]
    fn n(&self) -> usize {
        self.outcome.result.n
    }

    /// The CLI's text report of this fit.
    fn report(&self) -> String {
        report::to_text(&self.outcome, &self.info)
    }

    /// The CLI's JSON report of this fit (``goniofit fit --json``), key for key.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_to_py(py, self.json())
    }

    /// The CLI's JSON report as text.
    fn to_json(&self) -> PyResult<String> {
        serde_json::to_string_pretty(self.typed_report())
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))
    }

    /// The report's pictures, by name (``fit_log``, ``fit_linear``, ``residuals_theta``,
    /// ``residuals_phi``, ``polar``, ``contour``, ``hemisphere_1`` …) in the report's
    /// order: SVG documents (``format="svg"``), PNG files' bytes (``"png"``), or
    /// matplotlib figures (``"matplotlib"``, when matplotlib is installed). Empty when the
    /// fit was stopped before its fitted values were evaluated.
    #[pyo3(signature = (format = "svg"))]
    fn figures<'py>(&self, py: Python<'py>, format: &str) -> PyResult<Bound<'py, PyDict>> {
        let out = PyDict::new(py);
        match format {
            "svg" => {
                for (name, svg) in self.svg_figures()? {
                    out.set_item(name, svg)?;
                }
            }
            "png" | "matplotlib" => {
                let (line, undetermined) = self.status();
                let pngs = py.detach(|| {
                    plot::png_of_outcome(
                        &self.config,
                        &self.outcome,
                        (&line, &undetermined),
                        self.unit.as_deref(),
                    )
                });
                for (name, png) in pngs.map_err(to_py_err)? {
                    out.set_item(name, PyBytes::new(py, &png))?;
                }
                if format == "matplotlib" {
                    return py
                        .import("goniofit._figures")?
                        .call_method1("to_matplotlib", (out,))?
                        .cast_into::<PyDict>()
                        .map_err(PyErr::from);
                }
            }
            other => {
                return Err(PyValueError::new_err(format!(
                    "format={other:?}: give \"svg\", \"png\" or \"matplotlib\""
                )))
            }
        }
        Ok(out)
    }

    /// The report as HTML for notebooks: status, the model comparison of ``auto``, the
    /// tables, and the fit on a log scale.
    fn _repr_html_(&self) -> String {
        let (line, undetermined) = self.status();
        let key = plot::key_svg_of_outcome(
            &self.config,
            &self.outcome,
            (&line, &undetermined),
            self.unit.as_deref(),
        )
        .ok()
        .flatten();
        report::html_fragment(
            &self.outcome.result,
            &self.info,
            &report::comparison(&self.outcome),
            key.as_deref(),
        )
    }

    fn __repr__(&self) -> String {
        let r = &self.outcome.result;
        format!(
            "<goniofit.FitResult model={} n={} converged={} cost={:.7e} verdict={:?}>",
            r.model,
            r.n,
            if r.converged() { "True" } else { "False" },
            r.cost,
            r.verdict
        )
    }
}

/// One entry per outcome for `fit_frame`: `model`, `samples`, `converged`, `termination`,
/// `verdict`, `adequacy`, `adequacy_reasons`, `cost`, `reduced_chi2`, `r2`, `iterations`,
/// then per parameter and derived
/// quantity `NAME`, `NAME_stderr` (NaN when undetermined or fixed) and `NAME_determined`;
/// a name absent from some fits (another model under `auto`) is NaN / False there.
pub fn summary_columns<'py>(py: Python<'py>, outcomes: &[Outcome]) -> PyResult<Bound<'py, PyDict>> {
    let out = PyDict::new(py);
    fit_columns(py, &out, outcomes)?;
    for name in &quantity_names(outcomes) {
        quantity_columns(py, &out, outcomes, name)?;
    }
    Ok(out)
}

/// The result of an outcome.
fn r(o: &Outcome) -> &goniofit::FitResult {
    &o.result
}

/// Sets the per-fit columns of [`summary_columns`] on `out`, in this order: `model`,
/// `samples`, `converged`, `termination`, `verdict` (as the JSON report spells them),
/// `adequacy`, `adequacy_reasons`, `cost`, `reduced_chi2`, `r2`, `iterations`,
/// `start_from` (`search`, or `neighbour` for a kept warm start); one entry per outcome
/// each.
fn fit_columns(py: Python<'_>, out: &Bound<'_, PyDict>, outcomes: &[Outcome]) -> PyResult<()> {
    let text = |f: &dyn Fn(&Outcome) -> String| outcomes.iter().map(f).collect::<Vec<String>>();
    out.set_item("model", text(&|o| r(o).full_model()))?;
    // The sample count as `samples`: `n` is the Fresnel factor's index where a fit has one.
    out.set_item(
        "samples",
        outcomes
            .iter()
            .map(|o| r(o).n as u64)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    out.set_item(
        "converged",
        outcomes
            .iter()
            .map(|o| r(o).converged())
            .collect::<Vec<_>>(),
    )?;
    // As the JSON report spells them (report::json).
    out.set_item(
        "termination",
        text(&|o| report::termination_name(r(o).termination)),
    )?;
    let verdict = |o: &Outcome| match serde_json::to_value(r(o).verdict) {
        Ok(Value::String(s)) => s,
        _ => String::new(),
    };
    out.set_item("verdict", text(&verdict))?;
    out.set_item(
        "adequacy",
        text(&|o| r(o).adequacy.verdict.name().to_string()),
    )?;
    out.set_item("adequacy_reasons", text(&|o| r(o).adequacy.codes()))?;
    let num = |f: &dyn Fn(&Outcome) -> f64| {
        outcomes
            .iter()
            .map(f)
            .collect::<Vec<f64>>()
            .into_pyarray(py)
    };
    out.set_item("cost", num(&|o| r(o).cost))?;
    out.set_item("reduced_chi2", num(&|o| r(o).reduced_chi2))?;
    out.set_item("r2", num(&|o| r(o).r2))?;
    out.set_item(
        "iterations",
        outcomes
            .iter()
            .map(|o| r(o).iterations)
            .collect::<Vec<_>>()
            .into_pyarray(py),
    )?;
    let start = |o: &Outcome| match r(o).started_near {
        true => "neighbour".to_string(),
        false => "search".to_string(),
    };
    out.set_item("start_from", text(&start))?;
    Ok(())
}

/// The names of every parameter, then derived quantity, of the outcomes, each once, in
/// order of first appearance.
fn quantity_names(outcomes: &[Outcome]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for o in outcomes {
        let all = r(o)
            .params
            .iter()
            .map(|p| &p.name)
            .chain(r(o).derived.iter().map(|d| &d.name));
        for n in all {
            if !names.contains(n) {
                names.push(n.clone());
            }
        }
    }
    names
}

/// Sets `name`, `name_stderr` and `name_determined` on `out`: per outcome, the value,
/// standard error (NaN when not given) and whether it is determined, of the parameter
/// called `name` or else the derived quantity; NaN / NaN / False where the fit has neither.
fn quantity_columns(
    py: Python<'_>,
    out: &Bound<'_, PyDict>,
    outcomes: &[Outcome],
    name: &str,
) -> PyResult<()> {
    let mut value = Vec::with_capacity(outcomes.len());
    let mut stderr = Vec::with_capacity(outcomes.len());
    let mut determined = Vec::with_capacity(outcomes.len());
    for o in outcomes {
        let p = r(o)
            .params
            .iter()
            .find(|p| p.name == name)
            .map(|p| (p.value, p.stderr, p.determined));
        let d = || {
            r(o).derived
                .iter()
                .find(|d| d.name == name)
                .map(|d| (d.value, d.stderr, d.determined))
        };
        let (v, se, det) = p.or_else(d).unwrap_or((f64::NAN, None, false));
        value.push(v);
        stderr.push(se.unwrap_or(f64::NAN));
        determined.push(det);
    }
    out.set_item(name, value.into_pyarray(py))?;
    out.set_item(format!("{name}_stderr"), stderr.into_pyarray(py))?;
    out.set_item(format!("{name}_determined"), determined)?;
    Ok(())
}
