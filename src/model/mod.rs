//! Reflectance models. Each model evaluates a whole prepared batch ([`Geometry`]) at once:
//! the values and, on request, the analytic Jacobian with respect to its parameters.
//!
//! The model layer knows nothing of files, fits or plots.

pub(crate) mod domain;
pub(crate) mod fresnel;
pub(crate) mod kbs;
pub(crate) mod lambert;
mod lanes;
pub(crate) mod mixed;
pub(crate) mod series;
pub(crate) mod shadowing;
pub(crate) mod specular;

use crate::error::{Error, Result};
use crate::geometry::Geometry;

/// Description of one model parameter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// Name as used on the command line (`sigma`, `T`, `scale`, ...).
    pub name: &'static str,
    /// Unit, for reports.
    pub unit: &'static str,
    /// Whether the parameter must be strictly positive (fitted in log space).
    pub positive: bool,
    /// The exclusive lower bound of a positive parameter's domain: 0, or 1 for the index of
    /// a dielectric (fitted as ln(p − lower)).
    pub lower: f64,
    /// One-line meaning.
    pub doc: &'static str,
}

/// How a sample's KBS value was evaluated (reported per sample by `auto`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    /// A closed form (Lambertian, specular lobe): nothing to choose.
    Closed,
    /// Smooth-surface approximation: the m = 1 term of the series (eq. 42).
    Smooth,
    /// Rough-surface approximation e^{−a/g}/g (eq. 43), possibly with asymptotic corrections.
    Rough,
    /// The series, truncated where its remainder is below the tolerance.
    Series,
}

impl Mode {
    /// All modes, in report order.
    pub const ALL: [Mode; 4] = [Mode::Closed, Mode::Smooth, Mode::Rough, Mode::Series];

    /// Lower-case name, as in reports and the residuals file.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Closed => "closed",
            Mode::Smooth => "smooth",
            Mode::Rough => "rough",
            Mode::Series => "series",
        }
    }
}

/// How the KBS sum S(g, a) is evaluated.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum EvalMode {
    /// Per sample, the cheapest evaluation whose error bound meets the tolerance.
    #[default]
    Auto,
    /// Always the series (truncated at the tolerance).
    Series,
    /// Always the smooth approximation (eq. 42).
    Smooth,
    /// Always the rough approximation (eq. 43).
    Rough,
}

/// The range of the relative accuracy target of the KBS evaluation.
pub(crate) const TOL_RANGE: (f64, f64) = (1e-16, 0.1);

/// Options shared by the model constructors.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ModelOptions {
    /// KBS evaluation mode (ignored by the other models).
    pub mode: EvalMode,
    /// Relative accuracy target for the KBS sum.
    pub tol: f64,
    /// Patch half-sizes (X, Y) in the unit of λ: when given, KBS includes the coherent ρ0²
    /// term and uses A = 4XY; otherwise A = λ² and no coherent term.
    pub patch: Option<(f64, f64)>,
    /// Fresnel factor on the KBS lobe (`fresnel`; ignored by the other models).
    pub fresnel: fresnel::Fresnel,
    /// Shadowing–masking factor on the KBS lobe (`shadowing`; ignored by the others).
    pub shadowing: shadowing::Shadowing,
}

impl Default for ModelOptions {
    fn default() -> Self {
        ModelOptions {
            mode: EvalMode::Auto,
            tol: 1e-10,
            patch: None,
            fresnel: fresnel::Fresnel::None,
            shadowing: shadowing::Shadowing::None,
        }
    }
}

impl ModelOptions {
    /// The factor options as command-line text (` --fresnel dielectric --shadowing smith`),
    /// empty for the paper's model: what a report appends to the model's name.
    pub fn factors_label(&self) -> String {
        let mut s = String::new();
        if self.fresnel != fresnel::Fresnel::None {
            s += &format!(" --fresnel {}", self.fresnel.name());
        }
        if self.shadowing != shadowing::Shadowing::None {
            s += &format!(" --shadowing {}", self.shadowing.name());
        }
        s
    }

    /// A model name followed by factor options as [`Self::factors_label`] writes them
    /// (`kbs+lambert --fresnel dielectric --shadowing smith`): the bare name and these
    /// options with the factors named there (the others as they are). Tokens that are not
    /// a known factor option are left out.
    pub fn with_factors_of(self, named: &str) -> (String, ModelOptions) {
        let mut words = named.split_whitespace();
        let name = words.next().unwrap_or_default().to_string();
        let mut opts = self;
        while let Some(flag) = words.next() {
            let value = words.next().unwrap_or_default();
            match flag {
                "--fresnel" => {
                    opts.fresnel = fresnel::Fresnel::parse(value).unwrap_or(opts.fresnel)
                }
                "--shadowing" => {
                    opts.shadowing = shadowing::Shadowing::parse(value).unwrap_or(opts.shadowing)
                }
                _ => {}
            }
        }
        (name, opts)
    }

    /// Whether a factor multiplies the KBS lobe.
    pub fn has_factors(&self) -> bool {
        self.fresnel != fresnel::Fresnel::None || self.shadowing != shadowing::Shadowing::None
    }
}

/// Checks that `params` has one value per parameter of `model`.
pub fn check_param_count(model: &dyn Model, params: &[f64]) -> Result<()> {
    if params.len() == model.params().len() {
        Ok(())
    } else {
        Err(Error::Usage(format!(
            "model {} takes {} parameters, got {}",
            model.name(),
            model.params().len(),
            params.len()
        )))
    }
}

/// A reflectance model evaluated over a prepared batch of samples.
pub trait Model: Send + Sync {
    /// The name the model is chosen by (`kbs`, `lambert`, ...).
    fn name(&self) -> &'static str;

    /// The parameters, in the order of the parameter slice.
    fn params(&self) -> &'static [ParamSpec];

    /// Radiance L for every sample of `geo` into `out` (length `geo.len()`); when `jac` is
    /// given (length `geo.len() * params().len()`, column-major: column j holds ∂L/∂p_j for
    /// all samples), the analytic Jacobian too. Finite for every sample in the valid domain
    /// and every parameter vector with positive σ, T, w.
    fn radiance(&self, geo: &Geometry, p: &[f64], out: &mut [f64], jac: Option<&mut [f64]>);

    /// The evaluation options the model was built with (None for models that take none):
    /// two models of one name and options give the same values.
    fn options(&self) -> Option<ModelOptions> {
        None
    }

    /// [`Self::radiance`]'s values and the evaluation mode of each sample at parameters `p`,
    /// from one evaluation (every sample `Mode::Closed` for a model in closed form).
    fn radiance_modes(&self, geo: &Geometry, p: &[f64], out: &mut [f64]) -> Vec<Mode> {
        self.radiance(geo, p, out, None);
        vec![Mode::Closed; geo.len()]
    }

    /// [`Self::eval`]'s values (no Jacobian) and each sample's evaluation mode.
    fn eval_modes(&self, geo: &Geometry, p: &[f64], out: &mut [f64]) -> Vec<Mode> {
        let modes = self.radiance_modes(geo, p, out);
        to_quantity(geo, out);
        modes
    }

    /// The measured quantity (radiance or BRDF, per `geo.quantity`) and its Jacobian.
    fn eval(&self, geo: &Geometry, p: &[f64], out: &mut [f64], jac: Option<&mut [f64]>) {
        let n = geo.len();
        match jac {
            Some(j) => {
                self.radiance(geo, p, out, Some(&mut *j));
                j.chunks_mut(n.max(1)).for_each(|col| to_quantity(geo, col));
            }
            None => self.radiance(geo, p, out, None),
        }
        to_quantity(geo, out);
    }

    /// Index of the named parameter.
    fn param_index(&self, name: &str) -> Result<usize> {
        self.params()
            .iter()
            .position(|s| s.name.eq_ignore_ascii_case(name))
            .ok_or_else(|| Error::Param {
                name: name.to_string(),
                message: format!(
                    "model {} has no such parameter (it has: {})",
                    self.name(),
                    self.params()
                        .iter()
                        .map(|s| s.name)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            })
    }
}

/// Radiance values (or one Jacobian column) of the samples of `geo` turned into its
/// measured quantity in place: unchanged for radiance, × each sample's output factor
/// (1/cos θi) for a BRDF.
fn to_quantity(geo: &Geometry, values: &mut [f64]) {
    if geo.quantity != crate::geometry::Quantity::Radiance {
        for (i, v) in values.iter_mut().enumerate() {
            *v *= geo.out_factor(i);
        }
    }
}

/// The model names goniofit knows, in help order.
pub const MODEL_NAMES: [&str; 6] = [
    "kbs",
    "kbs-smooth",
    "kbs-rough",
    "kbs+lambert",
    "lambert",
    "lambert-specular",
];

/// Build a model by name (case-insensitive).
pub fn by_name(name: &str, opts: &ModelOptions) -> Result<Box<dyn Model>> {
    let name_lc = name.to_ascii_lowercase();
    let mut kbs_opts = *opts;
    Ok(match name_lc.as_str() {
        "kbs" => Box::new(kbs::Kbs::new(kbs_opts)?),
        "kbs-smooth" => {
            kbs_opts.mode = EvalMode::Smooth;
            Box::new(kbs::Kbs::new(kbs_opts)?)
        }
        "kbs-rough" => {
            kbs_opts.mode = EvalMode::Rough;
            Box::new(kbs::Kbs::new(kbs_opts)?)
        }
        "kbs+lambert" => Box::new(mixed::KbsLambert::new(kbs_opts)?),
        "lambert" => Box::new(lambert::Lambert),
        "lambert-specular" => Box::new(specular::LambertSpecular),
        _ => return Err(Error::UnknownModel(name.to_string())),
    })
}

/// Parse `k=v,k=v` into a full parameter vector for `model`. Every parameter must be given
/// exactly once, and positive parameters must be > 0.
pub fn parse_params(model: &dyn Model, text: &str) -> Result<Vec<f64>> {
    let specs = model.params();
    let mut values: Vec<Option<f64>> = vec![None; specs.len()];
    for (name, value) in parse_assignments(text)? {
        let j = model.param_index(&name)?;
        if values[j].is_some() {
            return Err(Error::Param {
                name,
                message: "given twice".into(),
            });
        }
        values[j] = Some(value);
    }
    specs
        .iter()
        .zip(&values)
        .map(|(spec, v)| {
            let v = v.ok_or_else(|| Error::Param {
                name: spec.name.into(),
                message: format!("missing (model {} needs it)", model.name()),
            })?;
            check_param_value(spec, v)?;
            Ok(v)
        })
        .collect()
}

/// Check a parameter value against its domain.
pub fn check_param_value(spec: &ParamSpec, v: f64) -> Result<()> {
    if !v.is_finite() || (spec.positive && v <= spec.lower) {
        return Err(Error::Param {
            name: spec.name.into(),
            message: format!(
                "value {v} is outside its domain ({})",
                if spec.positive {
                    format!("> {}", spec.lower)
                } else {
                    "finite".into()
                }
            ),
        });
    }
    Ok(())
}

/// Parse `k=v,k=v` pairs (empty text gives none); every value must be a finite number
/// (`nan`, `inf`, `1e400` are refused, naming the parameter).
pub fn parse_assignments(text: &str) -> Result<Vec<(String, f64)>> {
    let mut out = Vec::new();
    for part in text.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let (k, v) = part.split_once('=').ok_or_else(|| Error::Param {
            name: part.to_string(),
            message: "expected name=value".into(),
        })?;
        let value: f64 = v.trim().parse().map_err(|_| Error::Param {
            name: k.trim().to_string(),
            message: format!("'{}' is not a number", v.trim()),
        })?;
        if !value.is_finite() {
            return Err(Error::Param {
                name: k.trim().to_string(),
                message: format!(
                    "'{}' is not a finite number{}",
                    v.trim(),
                    if value.is_nan() {
                        " (NaN: not a number)"
                    } else {
                        ""
                    }
                ),
            });
        }
        out.push((k.trim().to_string(), value));
    }
    Ok(out)
}
