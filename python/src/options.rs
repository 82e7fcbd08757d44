//! Keyword options of the fit functions → the library's [`Settings`] (every keyword but
//! the per-sample arrays, checked by [`Settings::check`]), and the per-sample arrays → an
//! [`arrays::Columns`] view.

use crate::convert::to_py_err;
use goniofit::settings::{self, Front};
use goniofit::{
    arrays, EvalMode, Fresnel, LossKind, Model, Quantity, ResidualKind, Settings, Shadowing,
};
use numpy::PyReadonlyArray1;
use pyo3::exceptions::{PyRuntimeWarning, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

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

/// A fit call's keywords: the fit's settings, and the per-sample arrays beside them.
#[derive(Debug, Clone, Default)]
pub struct FitOptions {
    /// What the fit is asked to do (the keywords that are not per-sample arrays).
    pub settings: Settings,
    /// Per-sample weights.
    pub weights: Option<Vec<f64>>,
    /// Per-sample standard uncertainties of L.
    pub sigma_l: Option<Vec<f64>>,
    /// Per-sample wavelengths (a scalar `wavelength` is a setting).
    pub wavelengths: Option<Vec<f64>>,
    /// Per-sample channel labels: a joint fit of the channels.
    pub channel: Option<Vec<String>>,
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
    /// keyword is a `TypeError`, a bad value a `ValueError` naming the option
    /// ([`Settings::check`]); more threads than cores a `RuntimeWarning`.
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
        checked(o.settings.check(PY))?;
        if let (_, Some(note)) = checked(settings::threads(PY, o.settings.threads))? {
            let py = kwargs.py();
            let category = py.get_type::<PyRuntimeWarning>();
            PyErr::warn(py, &category, &std::ffi::CString::new(note)?, 1)?;
        }
        Ok(o)
    }

    fn set(&mut self, key: &str, v: &Bound<'_, PyAny>) -> PyResult<()> {
        let s = &mut self.settings;
        match key {
            "model" => s.model = v.extract()?,
            "wavelength_unit" => s.wavelength_unit = Some(v.extract()?),
            "wavelength" if v.is_instance_of::<PyString>() => {
                // As the CLI's --wavelength: a number with an optional unit (633nm, 0.633um).
                let text: String = v.extract()?;
                let (l, unit) = goniofit::parse_length(&text).map_err(to_py_err)?;
                s.wavelength = Some(l);
                if let Some(u) = unit {
                    s.wavelength_unit = Some(u.to_string());
                }
            }
            "wavelength" => match v.extract::<f64>() {
                Ok(l) => s.wavelength = Some(l),
                Err(_) => self.wavelengths = Some(vector(v, "wavelength")?),
            },
            "quantity" => s.quantity = Some(quantity(&v.extract::<String>()?)?),
            "residual" => s.residual = residual(&v.extract::<String>()?)?,
            "weights" => self.weights = Some(vector(v, "weights")?),
            "sigma_L" => self.sigma_l = Some(vector(v, "sigma_L")?),
            "init" => s.init = assignments(v, "init")?,
            "fix" => s.fix = assignments(v, "fix")?,
            "channel" => self.channel = Some(v.extract()?),
            "radians" => s.radians = v.extract()?,
            "signed_theta_r" => s.signed_theta_r = v.extract()?,
            "mode" => s.mode = eval_mode(&v.extract::<String>()?)?,
            "tol" => s.tol = v.extract()?,
            "patch" => s.patch = Some(v.extract()?),
            "floor" => s.floor = Some(v.extract()?),
            "max_iter" => s.max_iter = v.extract()?,
            "timeout" => s.timeout = Some(v.extract()?),
            "reduce" => s.reduce = v.extract()?,
            "threads" => s.threads = Some(v.extract()?),
            "warm_start" => s.warm_start = v.extract()?,
            "absolute_sigma" => s.absolute_sigma = v.extract()?,
            "intervals" => s.intervals = Some(v.extract()?),
            "loss" => s.loss = loss(&v.extract::<String>()?)?,
            "f_scale" => s.f_scale = v.extract()?,
            "fresnel" => s.fresnel = fresnel(&v.extract::<String>()?)?,
            "shadowing" => s.shadowing = shadowing(&v.extract::<String>()?)?,
            _ => return Err(unknown(key)),
        }
        Ok(())
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
        let s = &o.settings;
        let ds = arrays::dataset("arrays", &cols, s.radians, s.signed_theta_r)?;
        // As the CLI after reading: values and weights the fit cannot square are refused.
        goniofit::check_magnitudes(&ds)?;
        Ok(ds)
    }
}
