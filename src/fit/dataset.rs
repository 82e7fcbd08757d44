//! A dataset's fit as the CLI and the Python package run it: the fit's data from a
//! [`Dataset`], every candidate model (`auto` compares four by BIC), and for a joint
//! multi-channel fit the note on how much narrower σ and T are than from one channel.
//!
//! This is the one path from measured samples to a finished [`Outcome`]; the reporters in
//! [`crate::report::outcome`] turn an outcome into the text report and the JSON object.

use super::driver::{self, FitConfig, FitInput, FitResult};
use crate::error::{Error, Result};
use crate::geometry::{Geometry, Quantity};
use crate::io::Dataset;
use crate::model::{self, ModelOptions};

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
}

impl DatasetFit {
    /// The candidate model names (lower case): the four of `auto`, or the one given
    /// (checked to exist).
    pub fn candidates(&self) -> Result<Vec<String>> {
        if self.model.eq_ignore_ascii_case("auto") {
            Ok(AUTO_CANDIDATES.iter().map(|s| s.to_string()).collect())
        } else {
            model::by_name(&self.model, &ModelOptions::default())?;
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
/// else 1 unless `needs_wavelength`), values, weights (1 without a weight column), and the
/// channel index of every sample with the channel names in first-appearance order.
pub fn fit_input(
    ds: &Dataset,
    quantity: Quantity,
    wavelength: Option<f64>,
    needs_wavelength: bool,
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
    let weight = ds.weight.clone().unwrap_or_else(|| vec![1.0; n]);
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

/// Fit one dataset with every candidate model and keep the lowest BIC. Errors: the
/// dataset's own (no wavelength for a KBS model, bad values) and the fit's.
pub fn fit_dataset(spec: &DatasetFit, label: String, ds: Dataset) -> Result<Outcome> {
    let candidates = spec.candidates()?;
    let needs_wavelength = candidates.iter().any(|m| m.starts_with("kbs"));
    let input = fit_input(&ds, spec.quantity, spec.wavelength, needs_wavelength)?;
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

/// For a joint fit: how much narrower σ and T are than from the middle channel alone.
fn joint_narrowing(spec: &DatasetFit, ds: &Dataset, joint: &FitResult) -> Result<Option<String>> {
    let Some(labels) = &ds.channel else {
        return Ok(None);
    };
    let names = &joint.layout.channel_names;
    let mid = &names[names.len() / 2];
    let idx: Vec<usize> = (0..labels.len()).filter(|&i| &labels[i] == mid).collect();
    let mut single = ds.subset(&idx);
    single.channel = None;
    let input = fit_input(&single, spec.quantity, spec.wavelength, true)?;
    let mut config = spec.config_for(&joint.model, ds.sigma_l.is_some());
    config.lm.progress = false;
    let alone = driver::fit(&input, &config)?;
    let mut parts = Vec::new();
    for name in ["sigma", "T"] {
        let se = |r: &FitResult| {
            r.params
                .iter()
                .find(|p| p.name == name)
                .and_then(|p| p.stderr)
        };
        match (se(joint), se(&alone)) {
            (Some(j), Some(a)) => parts.push(format!(
                "{name}: ±{j:.3e} joint vs ±{a:.3e} from {mid} alone ({:.1}× narrower)",
                a / j
            )),
            (Some(j), None) => parts.push(format!(
                "{name}: ±{j:.3e} joint, not determined from {mid} alone"
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
