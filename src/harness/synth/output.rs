//! A synthetic data set and what is written of it: the CSV table and the truth JSON.

use super::noise::{add_noise, Noise, Noisy};
use crate::error::{Error, Result};
use crate::geometry::layout::{subsample, AnglesDeg, Layout};
use crate::geometry::{Geometry, Quantity, Sample};
use crate::model::{EvalMode, Model, ModelOptions};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

/// All vectors have one entry per sample, in layout order.
#[derive(Debug, Clone)]
pub struct SynthData {
    /// Directions in degrees, as written to the CSV.
    pub angles: Vec<AnglesDeg>,
    /// The same directions as the model saw them ([`AnglesDeg::sample`]).
    pub samples: Vec<Sample>,
    /// Wavelength (unit of σ, T), the same for every sample.
    pub wavelength: f64,
    /// Radiance or BRDF.
    pub quantity: Quantity,
    /// The model's values (the measured quantity, per `quantity`).
    pub exact: Vec<f64>,
    /// `exact` plus noise.
    pub value: Vec<f64>,
    /// Standard deviation of the noise of each value.
    pub sigma_l: Vec<f64>,
}

/// Evaluate `model` at `params` (in the order of `model.params()`) on `angles` and add
/// `noise`. Errors: a parameter vector of the wrong length, angles or wavelength outside
/// the domain, a bad noise level ([`Error::Usage`]), or a non-finite model value
/// ([`Error::Numerical`]).
pub fn generate(
    model: &dyn Model,
    params: &[f64],
    angles: &[AnglesDeg],
    wavelength: f64,
    quantity: Quantity,
    noise: &Noise,
) -> Result<SynthData> {
    let samples: Vec<Sample> = angles.iter().map(AnglesDeg::sample).collect();
    let geo = Geometry::new(&samples, &[wavelength], quantity)?;
    let exact = evaluate(model, params, &geo)?;
    let Noisy { value, sigma_l } = add_noise(&exact, noise)?;
    Ok(SynthData {
        angles: angles.to_vec(),
        samples,
        wavelength,
        quantity,
        exact,
        value,
        sigma_l,
    })
}

/// The model's values on a prepared batch, checked: right parameter count, every value
/// finite ([`crate::model::domain::evaluate_checked`]).
pub(crate) fn evaluate(model: &dyn Model, params: &[f64], geo: &Geometry) -> Result<Vec<f64>> {
    crate::model::domain::evaluate_checked(model, params, geo)
}

/// Which optional columns `SynthData::write_csv` writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CsvOptions {
    /// Add a `sigma_L` column (the noise standard deviation of each value).
    pub sigma: bool,
    /// Add a `wavelength` column.
    pub wavelength: bool,
    /// Write rows at |φr| = 180° as signed θr = −|θr| at φr = 0 (the in-plane convention of
    /// many instruments). θr = 0 stays 0.
    pub signed_theta_r: bool,
}

impl SynthData {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.value.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.value.is_empty()
    }

    /// Write `theta_i,theta_r,phi_r,L[,sigma_L][,wavelength]` (degrees; `L` is the noisy
    /// value). Every number is written in Rust's shortest round-trip form, so parsing it
    /// gives back the same f64.
    pub fn write_csv<W: Write>(&self, w: W, opts: &CsvOptions) -> std::io::Result<()> {
        let mut wtr = csv::Writer::from_writer(w);
        let mut header = vec!["theta_i", "theta_r", "phi_r", "L"];
        if opts.sigma {
            header.push("sigma_L");
        }
        if opts.wavelength {
            header.push("wavelength");
        }
        wtr.write_record(&header)?;
        let mut row: Vec<String> = Vec::with_capacity(header.len());
        for (i, a) in self.angles.iter().enumerate() {
            let (tr, pr) = if opts.signed_theta_r && a.phi_r.abs() == 180.0 && a.theta_r != 0.0 {
                (-a.theta_r, 0.0)
            } else {
                (a.theta_r, a.phi_r)
            };
            row.clear();
            row.push(num(a.theta_i));
            row.push(num(tr));
            row.push(num(pr));
            row.push(num(self.value[i]));
            if opts.sigma {
                row.push(num(self.sigma_l[i]));
            }
            if opts.wavelength {
                row.push(num(self.wavelength));
            }
            wtr.write_record(&row)?;
        }
        wtr.flush()
    }
}

/// Shortest round-trip decimal (`{:?}` switches to exponent form for tiny and huge values,
/// where `{}` would print hundreds of digits).
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// What a synthetic data set was made from, written beside it as JSON
/// (`data.truth.json` next to `data.csv`). Everything needed to regenerate the file or to
/// judge a fit of it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Model name as given to [`crate::model::by_name`].
    pub model: String,
    /// Every parameter of the model, by name.
    pub params: BTreeMap<String, f64>,
    /// Wavelength, in the unit of σ and T.
    pub wavelength: f64,
    /// That unit, when `--wavelength` named one (`nm`, `µm`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wavelength_unit: Option<String>,
    /// `radiance` or `brdf`.
    pub quantity: Quantity,
    /// KBS evaluation mode (`auto`, `series`, `smooth`, `rough`).
    pub mode: String,
    /// KBS relative tolerance.
    pub tol: f64,
    /// Patch half-sizes (X, Y), when the coherent term was included.
    pub patch: Option<(f64, f64)>,
    /// Fresnel factor on the KBS lobe (`none` when the file does not say).
    #[serde(default)]
    pub fresnel: crate::model::fresnel::Fresnel,
    /// Shadowing factor on the KBS lobe (`none` when the file does not say).
    #[serde(default)]
    pub shadowing: crate::model::shadowing::Shadowing,
    /// [`Layout::describe`] of the layout, or the layout file's path as given: either way
    /// [`Layout::parse`] reads it back.
    pub layout: String,
    /// `--samples`, when the layout was subsampled.
    pub subsample: Option<usize>,
    /// The noise added to the exact values: kind, level ε and seed.
    pub noise: Noise,
    /// Number of samples written.
    pub n: usize,
    /// Whether the CSV stores signed θr at φr = 0 for the φr = 180° rows.
    pub signed_theta_r: bool,
    /// File name of the data beside this file.
    pub data: String,
    /// goniofit version that wrote it.
    pub goniofit_version: String,
}

impl Truth {
    /// The parameters in the order of `model.params()`; an error names any parameter the
    /// truth file lacks.
    pub fn param_vector(&self, model: &dyn Model) -> Result<Vec<f64>> {
        model
            .params()
            .iter()
            .map(|s| {
                self.params
                    .iter()
                    .find(|(k, _)| k.eq_ignore_ascii_case(s.name))
                    .map(|(_, v)| *v)
                    .ok_or_else(|| Error::Param {
                        name: s.name.into(),
                        message: "missing from the truth file".into(),
                    })
            })
            .collect()
    }

    /// Name → value for every parameter of `model`.
    pub fn params_by_name(model: &dyn Model, params: &[f64]) -> BTreeMap<String, f64> {
        model
            .params()
            .iter()
            .zip(params)
            .map(|(s, v)| (s.name.to_string(), *v))
            .collect()
    }

    /// The model options the data were made with (`mode`, `tol`, `patch`).
    pub fn model_options(&self) -> Result<ModelOptions> {
        Ok(ModelOptions {
            mode: parse_eval_mode(&self.mode)?,
            tol: self.tol,
            patch: self.patch,
            fresnel: self.fresnel,
            shadowing: self.shadowing,
        })
    }

    /// The directions of the data: `layout` parsed again ([`Layout::parse`]; a layout file
    /// is looked up relative to the current folder), then subsampled as recorded.
    pub fn angles(&self) -> Result<Vec<AnglesDeg>> {
        let angles = Layout::parse(&self.layout)?.angles();
        match self.subsample {
            Some(n) => subsample(&angles, n),
            None => Ok(angles),
        }
    }

    /// Make the data set again from this truth: the same model, parameters, directions and
    /// noise, so the same values bit for bit.
    pub fn regenerate(&self) -> Result<SynthData> {
        let model = crate::model::by_name(&self.model, &self.model_options()?)?;
        let params = self.param_vector(model.as_ref())?;
        generate(
            model.as_ref(),
            &params,
            &self.angles()?,
            self.wavelength,
            self.quantity,
            &self.noise,
        )
    }

    /// Read a truth file.
    pub fn read(path: &Path) -> Result<Truth> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        serde_json::from_str(&text).map_err(|e| Error::File {
            path: path.to_path_buf(),
            message: format!("not a goniofit truth file: {e}"),
        })
    }
}

/// Lower-case name of a KBS evaluation mode, as in the truth file and `--mode`.
pub(crate) fn eval_mode_name(mode: EvalMode) -> &'static str {
    match mode {
        EvalMode::Auto => "auto",
        EvalMode::Series => "series",
        EvalMode::Smooth => "smooth",
        EvalMode::Rough => "rough",
    }
}

/// Inverse of [`eval_mode_name`] (case-insensitive).
pub(crate) fn parse_eval_mode(text: &str) -> Result<EvalMode> {
    match text.to_ascii_lowercase().as_str() {
        "auto" => Ok(EvalMode::Auto),
        "series" => Ok(EvalMode::Series),
        "smooth" => Ok(EvalMode::Smooth),
        "rough" => Ok(EvalMode::Rough),
        _ => Err(Error::Usage(format!(
            "unknown evaluation mode '{text}' (known: auto, series, smooth, rough)"
        ))),
    }
}

/// The truth file that goes beside a data file: `data.csv` → `data.truth.json`.
pub fn truth_path(data: &Path) -> std::path::PathBuf {
    let stem = data
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "data".into());
    data.with_file_name(format!("{stem}.truth.json"))
}
