//! A dataset's fit as the CLI and the Python package run it: the fit's data from a
//! [`Dataset`], every candidate model (`auto` compares four by BIC), and for a joint
//! multi-channel fit the note on how much narrower σ and T are than from one channel.
//!
//! This is the one path from measured samples to a finished [`Outcome`]; the reporters in
//! [`crate::report::outcome`] turn an outcome into the text report and the JSON object.

use super::driver::{self, FitConfig, FitInput, FitResult};
use super::problem::ResidualKind;
use super::weights::residual_weights;
use crate::error::{Error, Result};
use crate::geometry::{Geometry, Quantity};
use crate::io::Dataset;
use crate::model::{self, ModelOptions};
use crate::report;

/// Candidate models for `model = "auto"`, compared by BIC.
pub const AUTO_CANDIDATES: [&str; 4] = ["lambert", "lambert-specular", "kbs", "kbs+lambert"];

/// Everything a dataset's fit needs beside the data.
#[derive(Debug, Clone)]
pub struct DatasetFit {
    /// A model name (see [`model::by_name`]) or `auto`.
    pub model: String,
    /// Whether the measured value is a radiance (eq. 28) or a BRDF.
    pub quantity: Quantity,
    /// Wavelength (the unit of σ and T); overrides the dataset's own.
    pub wavelength: Option<f64>,
    /// The fit's settings; `model` and `weights_are_uncertainties` are set per candidate
    /// and dataset.
    pub config: FitConfig,
    /// Standard errors from the stated uncertainties as they are (scipy's
    /// `absolute_sigma=True`), not rescaled by the residual scatter.
    pub absolute_sigma: bool,
}

impl DatasetFit {
    /// The candidate model names (lower case): the four of `auto`, or the one given
    /// (checked to exist).
    pub fn candidates(&self) -> Result<Vec<String>> {
        if self.model.eq_ignore_ascii_case("auto") {
            Ok(AUTO_CANDIDATES.iter().map(|s| s.to_string()).collect())
        } else {
            model::by_name(&self.model, &ModelOptions::default()).map_err(|e| match e {
                Error::UnknownModel(name) => Error::Usage(format!(
                    "unknown model '{name}' (known: kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert, lambert-specular, or auto to fit the last four and keep the lowest BIC)"
                )),
                e => e,
            })?;
            Ok(vec![self.model.to_ascii_lowercase()])
        }
    }

    /// The configuration of one candidate model on a dataset (`uncertainties`: its weights
    /// come from a stated `sigma_L`).
    pub fn config_for(&self, model: &str, uncertainties: bool) -> FitConfig {
        FitConfig {
            model: model.to_string(),
            weights_are_uncertainties: uncertainties,
            ..self.config.clone()
        }
    }

    /// The fit input of a dataset with this fit's quantity, wavelength, residual and floor.
    pub fn input(&self, ds: &Dataset, needs_wavelength: bool) -> Result<FitInput> {
        fit_input(
            ds,
            self.quantity,
            self.wavelength,
            needs_wavelength,
            self.config.residual,
            self.config.floor,
        )
    }
}

/// One dataset's fit: every candidate model, and the chosen one (lowest BIC).
#[derive(Debug, Clone)]
pub struct Outcome {
    /// What the reports call the dataset (a file name, `file [group]`, a Python group).
    pub label: String,
    pub dataset: Dataset,
    pub input: FitInput,
    /// One result per candidate model, in [`DatasetFit::candidates`] order.
    pub candidates: Vec<FitResult>,
    /// The lowest-BIC candidate (with the joint-fit note for several channels).
    pub result: FitResult,
}

/// The fit's data from a dataset: geometry (λ from `wavelength`, else the dataset's own,
/// else 1 unless `needs_wavelength`), values, the weights transformed for the residual kind
/// ([`super::weights`]), and the channel index of every sample with the channel names in
/// first-appearance order.
pub fn fit_input(
    ds: &Dataset,
    quantity: Quantity,
    wavelength: Option<f64>,
    needs_wavelength: bool,
    residual: ResidualKind,
    floor: Option<f64>,
) -> Result<FitInput> {
    let n = ds.samples.len();
    let lambda: Vec<f64> = match (&ds.wavelength, wavelength) {
        (_, Some(l)) => vec![l],
        (Some(w), None) => w.clone(),
        (None, None) if needs_wavelength => {
            return Err(Error::Usage(format!(
                "{}: KBS models need a wavelength: give --wavelength, a wavelength column, or an ASTM channel such as 550nm",
                ds.path.display()
            )))
        }
        (None, None) => vec![1.0],
    };
    let geo = Geometry::new(&ds.samples, &lambda, quantity)?;
    let y = ds.value.clone().ok_or_else(|| Error::File {
        path: ds.path.clone(),
        message: "no measured value column (L)".into(),
    })?;
    let floor = floor_for(floor, &y);
    let (weight, _) = residual_weights(
        ds.weight.as_deref().filter(|_| ds.sigma_l.is_none()),
        ds.sigma_l.as_deref(),
        &y,
        residual,
        floor,
    );
    let (channel, channel_names) = match &ds.channel {
        Some(labels) => {
            let mut names: Vec<String> = Vec::new();
            let idx = labels
                .iter()
                .map(|l| match names.iter().position(|x| x == l) {
                    Some(i) => i,
                    None => {
                        names.push(l.clone());
                        names.len() - 1
                    }
                })
                .collect();
            (idx, names)
        }
        None => (vec![0; n], vec![String::new()]),
    };
    Ok(FitInput {
        geo,
        y,
        weight,
        channel,
        channel_names,
    })
}

/// The residual floor: `floor`, or 1e-6 × max |y| (as the fit computes it).
pub fn floor_for(floor: Option<f64>, y: &[f64]) -> f64 {
    driver::residual_floor(
        &FitConfig {
            floor,
            ..FitConfig::default()
        },
        y,
    )
}

/// Fit one dataset with every candidate model and keep the lowest BIC. Errors: the
/// dataset's own (no wavelength for a KBS model, bad values) and the fit's.
pub fn fit_dataset(spec: &DatasetFit, label: String, ds: Dataset) -> Result<Outcome> {
    let candidates = spec.candidates()?;
    let needs_wavelength = candidates.iter().any(|m| m.starts_with("kbs"));
    let input = spec.input(&ds, needs_wavelength)?;
    let uncertainties = ds.sigma_l.is_some();
    let results = candidates
        .iter()
        .map(|m| driver::fit(&input, &spec.config_for(m, uncertainties)))
        .collect::<Result<Vec<FitResult>>>()?;
    let best = results
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.bic.total_cmp(&b.1.bic))
        .map_or(0, |(i, _)| i);
    let mut result = results[best].clone();
    if spec.absolute_sigma {
        report::use_absolute_sigma(&mut result);
    }
    report::add_reflectance_factors(
        &mut result,
        &report::Units {
            quantity: spec.quantity,
            ..Default::default()
        },
    );
    if input.channel_names.len() > 1 {
        if let Some(note) = joint_narrowing(spec, &ds, &result)? {
            result.notes.push(note);
        }
    }
    Ok(Outcome {
        label,
        dataset: ds,
        input,
        candidates: results,
        result,
    })
}

/// For a joint fit: how much narrower σ, T and T/σ are than from the middle channel alone,
/// or that the data determines them neither way.
fn joint_narrowing(spec: &DatasetFit, ds: &Dataset, joint: &FitResult) -> Result<Option<String>> {
    let Some(labels) = &ds.channel else {
        return Ok(None);
    };
    let names = &joint.layout.channel_names;
    let mid = &names[names.len() / 2];
    let idx: Vec<usize> = (0..labels.len()).filter(|&i| &labels[i] == mid).collect();
    let mut single = ds.subset(&idx);
    single.channel = None;
    let input = spec.input(&single, true)?;
    let mut config = spec.config_for(&joint.model, ds.sigma_l.is_some());
    config.lm.progress = false;
    let alone = driver::fit(&input, &config)?;
    let mut parts = Vec::new();
    for name in ["sigma", "T", "T/sigma"] {
        let se = |r: &FitResult| -> Option<Option<f64>> {
            let p = r.params.iter().find(|p| p.name == name);
            let d = r.derived.iter().find(|d| d.name == name);
            match (p, d) {
                (Some(p), _) => Some(p.stderr),
                (None, Some(d)) => Some(d.stderr),
                _ => None,
            }
        };
        match (se(joint), se(&alone)) {
            (Some(Some(j)), Some(Some(a))) => parts.push(format!(
                "{name}: ±{j:.3e} joint vs ±{a:.3e} from {mid} alone ({:.1}× narrower)",
                a / j
            )),
            (Some(Some(j)), Some(None)) => parts.push(format!(
                "{name}: ±{j:.3e} joint, not determined from {mid} alone"
            )),
            (Some(None), Some(Some(a))) => parts.push(format!(
                "{name}: not determined jointly, ±{a:.3e} from {mid} alone"
            )),
            (Some(None), Some(None)) => parts.push(format!(
                "{name}: not determined by the data, jointly or from {mid} alone"
            )),
            _ => {}
        }
    }
    Ok((!parts.is_empty()).then(|| {
        format!(
            "joint fit over {} channels: {}",
            names.len(),
            parts.join("; ")
        )
    }))
}
