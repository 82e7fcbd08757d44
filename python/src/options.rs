//! Keyword options of the fit functions → the library's settings ([`DatasetFit`]), and the
//! per-sample arrays → an [`arrays::Columns`] view. Every option maps to one CLI flag of
//! `goniofit fit`; [`FitOptions::cli_args`] writes the equivalent command line into the
//! report (`command`, `replay.args`).

use crate::convert::to_py_err;
use goniofit::lm::LmConfig;
use goniofit::report::SettingSource;
use goniofit::settings::{self, Front};
use goniofit::{
    arrays, DatasetFit, EvalMode, FitConfig, Fresnel, Loss, LossKind, Model, ModelOptions,
    Quantity, ResidualKind, Shadowing,
};
use numpy::PyReadonlyArray1;
use pyo3::exceptions::{PyRuntimeWarning, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

/// Options are named as Python spells them.
pub const PY: Front = Front::Python;

/// The option names the fit functions take (besides the four sample arrays).
pub const OPTION_NAMES: [&str; 27] = [
    "model",
    "wavelength",
    "quantity",
    "residual",
    "weights",
    "sigma_L",
    "init",
    "fix",
    "channel",
    "radians",
    "signed_theta_r",
    "mode",
    "tol",
    "patch",
    "floor",
    "max_iter",
    "timeout",
    "reduce",
    "threads",
    "warm_start",
    "absolute_sigma",
    "wavelength_unit",
    "intervals",
    "loss",
    "f_scale",
    "fresnel",
    "shadowing",
];

/// The fit options of one call.
#[derive(Debug, Clone)]
pub struct FitOptions {
    pub model: String,
    /// A scalar wavelength (overrides per-sample ones).
    pub wavelength: Option<f64>,
    /// Per-sample wavelengths.
    pub wavelengths: Option<Vec<f64>>,
    /// The unit of λ (and so of σ, T), e.g. `nm`; None when not stated.
    pub wavelength_unit: Option<String>,
    pub quantity: Quantity,
    quantity_name: String,
    pub residual: ResidualKind,
    residual_name: String,
    pub weights: Option<Vec<f64>>,
    pub sigma_l: Option<Vec<f64>>,
    pub init: Vec<(String, f64)>,
    pub fix: Vec<(String, f64)>,
    pub channel: Option<Vec<String>>,
    pub radians: bool,
    pub signed_theta_r: bool,
    pub model_opts: ModelOptions,
    mode_name: String,
    pub floor: Option<f64>,
    pub max_iter: u64,
    pub timeout: Option<f64>,
    pub reduce: bool,
    /// Threads for parallel group fits (None: all cores).
    pub threads: Option<usize>,
    /// Groups started at their neighbour's optimum (the CLI's `--warm-start`).
    pub warm_start: bool,
    /// Standard errors from `sigma_L` as stated (scipy's `absolute_sigma=True`).
    pub absolute_sigma: bool,
    /// Whether `quantity` was given (the report says where the quantity came from).
    quantity_given: bool,
    /// Profile-likelihood intervals: None = for a single fit, not for fits of many groups
    /// (as the CLI: one dataset gets them, `--by-group` does not).
    pub intervals: Option<bool>,
    /// The robust loss on the weighted residuals (scipy's names; `linear`: least squares).
    pub loss: LossKind,
    /// The loss scale C, in the unit of the weighted residual (unused with `linear`).
    pub f_scale: f64,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            model: "kbs".into(),
            wavelength: None,
            wavelengths: None,
            wavelength_unit: None,
            quantity: Quantity::Radiance,
            quantity_name: "radiance".into(),
            residual: ResidualKind::Absolute,
            residual_name: "absolute".into(),
            weights: None,
            sigma_l: None,
            init: Vec::new(),
            fix: Vec::new(),
            channel: None,
            radians: false,
            signed_theta_r: false,
            model_opts: ModelOptions::default(),
            mode_name: "auto".into(),
            floor: None,
            max_iter: 500,
            timeout: None,
            reduce: true,
            threads: None,
            warm_start: false,
            absolute_sigma: false,
            quantity_given: false,
            intervals: None,
            loss: LossKind::Linear,
            f_scale: 1.0,
        }
    }
}

/// `radiance` or `brdf`.
pub fn quantity(name: &str) -> PyResult<Quantity> {
    match name.to_ascii_lowercase().as_str() {
        "radiance" => Ok(Quantity::Radiance),
        "brdf" => Ok(Quantity::Brdf),
        _ => Err(PyValueError::new_err(format!(
            "quantity '{name}': expected 'radiance' (L of eq. 28) or 'brdf' (L / cos θi)"
        ))),
    }
}

/// `auto`, `series`, `smooth` or `rough`.
pub fn eval_mode(name: &str) -> PyResult<EvalMode> {
    match name.to_ascii_lowercase().as_str() {
        "auto" => Ok(EvalMode::Auto),
        "series" => Ok(EvalMode::Series),
        "smooth" => Ok(EvalMode::Smooth),
        "rough" => Ok(EvalMode::Rough),
        _ => Err(PyValueError::new_err(format!(
            "mode '{name}': expected 'auto', 'series', 'smooth' or 'rough'"
        ))),
    }
}

/// A Fresnel factor by its CLI name: `none`, `dielectric`, `conductor`, `schlick`.
pub fn fresnel(name: &str) -> PyResult<Fresnel> {
    Fresnel::parse(name).ok_or_else(|| {
        PyValueError::new_err(format!(
            "fresnel '{name}': expected one of {}",
            Fresnel::ALL.map(Fresnel::name).join(", ")
        ))
    })
}

/// A shadowing factor by its CLI name: `none`, `smith`, `smith-correlated`.
pub fn shadowing(name: &str) -> PyResult<Shadowing> {
    Shadowing::parse(name).ok_or_else(|| {
        PyValueError::new_err(format!(
            "shadowing '{name}': expected one of {}",
            Shadowing::ALL.map(Shadowing::name).join(", ")
        ))
    })
}

/// A robust loss by scipy's name: `linear`, `soft_l1`, `huber`, `cauchy`, `arctan`.
fn loss(name: &str) -> PyResult<LossKind> {
    LossKind::from_name(name).ok_or_else(|| {
        PyValueError::new_err(format!(
            "loss '{name}': expected one of {}",
            LossKind::ALL.map(LossKind::name).join(", ")
        ))
    })
}

/// `absolute`, `relative` or `log`.
pub(crate) fn residual(name: &str) -> PyResult<ResidualKind> {
    match name.to_ascii_lowercase().as_str() {
        "absolute" => Ok(ResidualKind::Absolute),
        "relative" => Ok(ResidualKind::Relative),
        "log" => Ok(ResidualKind::Log),
        _ => Err(PyValueError::new_err(format!(
            "residual '{name}': expected 'absolute', 'relative' or 'log'"
        ))),
    }
}

/// A 1-D float64 array (the Python layer converts array-likes before the call).
fn vector(v: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<f64>> {
    let a: PyReadonlyArray1<f64> = v
        .extract()
        .map_err(|_| PyTypeError::new_err(format!("{name}: expected a 1-D float64 array")))?;
    Ok(a.as_slice()?.to_vec())
}

/// A number or an array of `n` numbers, as per-sample values (a number gives one value).
pub fn per_sample(v: &Bound<'_, PyAny>, n: usize, name: &str) -> PyResult<Vec<f64>> {
    if let Ok(x) = v.extract::<f64>() {
        return Ok(vec![x]);
    }
    let out = vector(v, name)?;
    if out.len() != n {
        return Err(PyValueError::new_err(format!(
            "{name} has {} elements, theta_i has {n}: give one value per sample",
            out.len()
        )));
    }
    Ok(out)
}

/// `init` / `fix`: a dict name → value, or the CLI's `name=value,...` text.
fn assignments(v: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<(String, f64)>> {
    if let Ok(s) = v.cast::<PyString>() {
        return goniofit::parse_assignments(&s.to_cow()?).map_err(to_py_err);
    }
    let d = v.cast::<PyDict>().map_err(|_| {
        PyTypeError::new_err(format!(
            "{name}: expected a dict parameter → value (or 'name=value,...')"
        ))
    })?;
    d.iter()
        .map(|(k, val)| {
            let key: String = k.extract()?;
            let x: f64 = val
                .extract()
                .map_err(|_| PyTypeError::new_err(format!("{name}['{key}']: expected a number")))?;
            Ok((key, x))
        })
        .collect()
}

/// Parameter values for `model`: a dict name → value (every parameter, names as the model
/// spells them, case-insensitive) or a sequence in the model's order.
pub fn param_vector(m: &dyn Model, params: &Bound<'_, PyAny>) -> PyResult<Vec<f64>> {
    let specs = m.params();
    let p: Vec<f64> = if let Ok(d) = params.cast::<PyDict>() {
        let mut p = vec![f64::NAN; specs.len()];
        for (k, v) in d.iter() {
            let key: String = k.extract()?;
            let i = m.param_index(&key).map_err(to_py_err)?;
            p[i] = v.extract()?;
        }
        if let Some(i) = p.iter().position(|x| x.is_nan()) {
            return Err(PyValueError::new_err(format!(
                "parameter {}: missing (model {} takes {})",
                specs[i].name,
                m.name(),
                specs.iter().map(|s| s.name).collect::<Vec<_>>().join(", ")
            )));
        }
        p
    } else {
        params.extract().map_err(|_| {
            PyTypeError::new_err("params: expected a dict name → value or a sequence of numbers")
        })?
    };
    goniofit::check_param_count(m, &p).map_err(to_py_err)?;
    for (s, &v) in specs.iter().zip(&p) {
        goniofit::check_param_value(s, v).map_err(to_py_err)?;
    }
    Ok(p)
}

impl FitOptions {
    /// Options from a call's keyword arguments; `None` values keep the defaults. An unknown
    /// keyword is a `TypeError`, a bad value a `ValueError` naming the option.
    pub fn from_kwargs(kwargs: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let mut o = FitOptions::default();
        let Some(kwargs) = kwargs else {
            return Ok(o);
        };
        for (k, v) in kwargs.iter() {
            let key: String = k.extract()?;
            if v.is_none() {
                if !OPTION_NAMES.contains(&key.as_str()) {
                    return Err(unknown(&key));
                }
                continue;
            }
            o.set(&key, &v)?;
        }
        Ok(o)
    }

    fn set(&mut self, key: &str, v: &Bound<'_, PyAny>) -> PyResult<()> {
        match key {
            "model" => self.model = v.extract()?,
            "wavelength_unit" => self.wavelength_unit = Some(v.extract()?),
            "wavelength" if v.is_instance_of::<PyString>() => {
                // As the CLI's --wavelength: a number with an optional unit (633nm, 0.633um).
                let text: String = v.extract()?;
                let (l, unit) = goniofit::parse_length(&text).map_err(to_py_err)?;
                self.wavelength = Some(l);
                if let Some(u) = unit {
                    self.wavelength_unit = Some(u.to_string());
                }
            }
            "wavelength" => match v.extract::<f64>() {
                Ok(l) => self.wavelength = Some(checked(settings::length(PY, "wavelength", l))?),
                Err(_) => self.wavelengths = Some(vector(v, "wavelength")?),
            },
            "quantity" => {
                self.quantity_name = v.extract()?;
                self.quantity = quantity(&self.quantity_name)?;
                self.quantity_given = true;
            }
            "residual" => {
                self.residual_name = v.extract()?;
                self.residual = residual(&self.residual_name)?;
            }
            "weights" => self.weights = Some(vector(v, "weights")?),
            "sigma_L" => self.sigma_l = Some(vector(v, "sigma_L")?),
            "init" => self.init = assignments(v, "init")?,
            "fix" => self.fix = assignments(v, "fix")?,
            "channel" => self.channel = Some(v.extract()?),
            "radians" => self.radians = v.extract()?,
            "signed_theta_r" => self.signed_theta_r = v.extract()?,
            "mode" => {
                self.mode_name = v.extract()?;
                self.model_opts.mode = eval_mode(&self.mode_name)?;
            }
            "tol" => self.model_opts.tol = checked(settings::tol(PY, v.extract()?))?,
            "patch" => {
                let opts = self.model_opts;
                let patch = Some(v.extract::<(f64, f64)>()?);
                self.model_opts = ModelOptions {
                    fresnel: opts.fresnel,
                    shadowing: opts.shadowing,
                    ..checked(settings::model_options(PY, opts.mode, opts.tol, patch))?
                };
            }
            "floor" => self.floor = checked(settings::floor(PY, Some(v.extract()?)))?,
            "max_iter" => self.max_iter = v.extract()?,
            "timeout" => {
                let t: f64 = v.extract()?;
                checked(settings::timeout(PY, Some(t)))?;
                self.timeout = Some(t);
            }
            "reduce" => self.reduce = v.extract()?,
            "threads" => {
                let (n, note) = checked(settings::threads(PY, Some(v.extract()?)))?;
                if let Some(note) = note {
                    let category = v.py().get_type::<PyRuntimeWarning>();
                    PyErr::warn(v.py(), &category, &std::ffi::CString::new(note)?, 1)?;
                }
                self.threads = Some(n);
            }
            "warm_start" => self.warm_start = v.extract()?,
            "absolute_sigma" => self.absolute_sigma = v.extract()?,
            "intervals" => self.intervals = Some(v.extract()?),
            "loss" => self.loss = loss(&v.extract::<String>()?)?,
            "f_scale" => self.f_scale = checked(settings::f_scale(PY, v.extract()?))?,
            "fresnel" => self.model_opts.fresnel = fresnel(&v.extract::<String>()?)?,
            "shadowing" => self.model_opts.shadowing = shadowing(&v.extract::<String>()?)?,
            _ => return Err(unknown(key)),
        }
        Ok(())
    }

    /// The library's settings of a dataset's fit, with a fresh interrupt flag that the
    /// binding sets on Ctrl-C (the interpreter keeps its signals). `single`: one
    /// dataset (profile intervals unless `intervals=False`).
    pub fn dataset_fit(&self, single: bool) -> DatasetFit {
        let lm = LmConfig {
            max_iters: self.max_iter,
            // Checked when set (settings::timeout), so the conversion cannot fail.
            timeout: settings::timeout(PY, self.timeout).ok().flatten(),
            progress: false,
            interrupt: Some(Arc::new(AtomicBool::new(false))),
            ..FitConfig::default().lm
        };
        DatasetFit {
            model: self.model.clone(),
            quantity: self.quantity,
            wavelength: self.wavelength,
            config: FitConfig {
                model: self.model.clone(),
                model_opts: self.model_opts,
                residual: self.residual,
                loss: Loss {
                    kind: self.loss,
                    f_scale: self.f_scale,
                },
                floor: self.floor,
                init: self.init.clone(),
                fix: self.fix.clone(),
                lm,
                weights_are_uncertainties: self.sigma_l.is_some(),
                reduce: self.reduce,
            },
            absolute_sigma: self.absolute_sigma,
            intervals: self.intervals.unwrap_or(single),
        }
    }

    /// What the report's setting says about where the fit's choices came from.
    pub fn setting_source(&self) -> SettingSource {
        let wavelength_source = match (self.wavelength, &self.wavelengths) {
            (Some(_), _) => "wavelength keyword",
            (None, Some(_)) => "wavelength array",
            (None, None) => "none",
        };
        SettingSource {
            quantity: self.quantity,
            quantity_source: if self.quantity_given {
                "quantity keyword"
            } else {
                "default"
            }
            .into(),
            residual: self.residual,
            floor: self.floor,
            wavelength_source: wavelength_source.into(),
            wavelength_unit: self.wavelength_unit.clone(),
            loss: self.loss.name().into(),
            f_scale: (self.loss != LossKind::Linear).then_some(self.f_scale),
            absolute_sigma: self.absolute_sigma,
            ..SettingSource::default()
        }
    }

    /// The `goniofit fit` arguments equivalent to these options (without a file: the
    /// samples came as arrays).
    pub fn cli_args(&self) -> Vec<String> {
        let mut a: Vec<String> = vec!["fit".into(), "--model".into(), self.model.clone()];
        let mut flag = |name: &str, value: String| {
            a.push(format!("--{name}"));
            a.push(value);
        };
        flag("quantity", self.quantity_name.to_ascii_lowercase());
        flag("residual", self.residual_name.to_ascii_lowercase());
        flag("mode", self.mode_name.to_ascii_lowercase());
        flag("tol", format!("{:e}", self.model_opts.tol));
        flag("max-iter", self.max_iter.to_string());
        if self.loss != LossKind::Linear {
            flag("loss", self.loss.name().into());
            flag("f-scale", self.f_scale.to_string());
        }
        if let Some(l) = self.wavelength {
            flag("wavelength", l.to_string());
        }
        let join = |v: &[(String, f64)]| {
            v.iter()
                .map(|(k, x)| format!("{k}={x}"))
                .collect::<Vec<_>>()
                .join(",")
        };
        if !self.init.is_empty() {
            flag("init", join(&self.init));
        }
        if !self.fix.is_empty() {
            flag("fix", join(&self.fix));
        }
        if let Some((x, y)) = self.model_opts.patch {
            flag("patch", format!("{x},{y}"));
        }
        if self.model_opts.fresnel != Fresnel::None {
            flag("fresnel", self.model_opts.fresnel.name().into());
        }
        if self.model_opts.shadowing != Shadowing::None {
            flag("shadowing", self.model_opts.shadowing.name().into());
        }
        if let Some(f) = self.floor {
            flag("floor", f.to_string());
        }
        if let Some(t) = self.timeout {
            flag("timeout", t.to_string());
        }
        if self.radians {
            a.push("--radians".into());
        }
        if self.signed_theta_r {
            a.push("--signed-theta-r".into());
        }
        if !self.reduce {
            a.push("--no-reduce".into());
        }
        if self.absolute_sigma {
            a.push("--absolute-sigma".into());
        }
        if self.intervals == Some(false) {
            a.push("--no-intervals".into());
        }
        a
    }
}

fn unknown(key: &str) -> PyErr {
    PyTypeError::new_err(format!(
        "unexpected keyword argument '{key}' (fit options: {})",
        OPTION_NAMES.join(", ")
    ))
}

/// A value checked by [`goniofit::settings`] (as the CLI checks its options), its refusal
/// a `ValueError`.
pub fn checked<T>(r: goniofit::Result<T>) -> PyResult<T> {
    r.map_err(to_py_err)
}

/// The four sample arrays and the per-sample options of one call, owned.
pub struct SampleArrays {
    theta_i: Vec<f64>,
    theta_r: Vec<f64>,
    phi_r: Vec<f64>,
    value: Vec<f64>,
    weight: Option<Vec<f64>>,
    sigma_l: Option<Vec<f64>>,
    wavelength: Option<Vec<f64>>,
    channel: Option<Vec<String>>,
}

impl SampleArrays {
    /// The sample arrays with the per-sample options of `o`.
    pub fn new(
        o: &FitOptions,
        theta_i: &PyReadonlyArray1<f64>,
        theta_r: &PyReadonlyArray1<f64>,
        phi_r: &PyReadonlyArray1<f64>,
        value: &PyReadonlyArray1<f64>,
    ) -> PyResult<Self> {
        Ok(SampleArrays {
            theta_i: theta_i.as_slice()?.to_vec(),
            theta_r: theta_r.as_slice()?.to_vec(),
            phi_r: phi_r.as_slice()?.to_vec(),
            value: value.as_slice()?.to_vec(),
            weight: o.weights.clone(),
            sigma_l: o.sigma_l.clone(),
            wavelength: o.wavelengths.clone(),
            channel: o.channel.clone(),
        })
    }

    /// The library's checked dataset of these samples (`arrays` in reports); a bad
    /// element is a `ValueError` naming its array and index.
    pub fn dataset(&self, o: &FitOptions) -> PyResult<goniofit::Dataset> {
        crate::convert::guard(|| self.checked(o))?.map_err(to_py_err)
    }

    fn checked(&self, o: &FitOptions) -> goniofit::Result<goniofit::Dataset> {
        let cols = arrays::Columns {
            theta_i: &self.theta_i,
            theta_r: &self.theta_r,
            phi_r: &self.phi_r,
            value: Some(&self.value),
            weight: self.weight.as_deref(),
            sigma_l: self.sigma_l.as_deref(),
            wavelength: self.wavelength.as_deref(),
            channel: self.channel.as_deref(),
        };
        let ds = arrays::dataset("arrays", &cols, o.radians, o.signed_theta_r)?;
        // As the CLI after reading: values and weights the fit cannot square are refused.
        goniofit::check_magnitudes(&ds)?;
        Ok(ds)
    }
}
