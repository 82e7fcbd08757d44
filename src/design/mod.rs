//! Experimental design: which geometries to measure next so that the data determines what
//! it does not determine yet.
//!
//! From a model at known (fitted) parameters, the wavelength, a noise model and the
//! geometries already measured, [`design`] computes the Fisher information of the measured
//! samples and of every candidate geometry (`predict`), chooses `n` candidates that most
//! lower the predicted variance of a target — a parameter, a derived quantity such as T/σ,
//! or every parameter at once (D-optimal) — greedily and then by exchange (`choose`),
//! and reports the linearised standard errors before and after, honest about the
//! directions the information leaves undetermined. `simulate` checks the linearised
//! figures by fitting simulated measurements at the measured and proposed geometries.
//! Candidates come from a file or a grid (`candidates`); alternative wavelengths may be
//! offered, each with its own amplitudes (the per-channel parameters of a joint fit).

pub(crate) mod candidates;
pub(crate) mod choose;
mod describe;
pub(crate) mod predict;
mod quantities;
pub(crate) mod simulate;

use crate::error::{Error, Result};
use crate::fit::problem::layout::PER_CHANNEL;
use crate::geometry::layout::AnglesDeg;
use crate::geometry::{Geometry, Quantity, Sample};
use crate::model::Model;
pub use candidates::Grid;
use choose::Criterion;
pub(crate) use describe::{percent, target_label, where_};
use nalgebra::{DMatrix, DVector};
pub use predict::NoiseModel;
pub(crate) use quantities::{quantities, QuantityDef};
pub use simulate::{before_and_after, Simulation};

/// Largest relative standard error at which a design calls a quantity determined: beyond
/// it a linearised error bar is not a trustworthy description of what the data pins
/// (the simulation beside it shows by how much).
pub const DETERMINED_RELATIVE_SE: f64 = 0.25;

/// Default dynamic range of the instrument: a candidate whose predicted value is below the
/// largest predicted value (measured and candidate samples) divided by this is taken as
/// unmeasurable and never chosen.
pub const DYNAMIC_RANGE: f64 = 1e4;

/// The surface and instrument a design plans for.
pub struct Scene<'a> {
    /// The model whose Fisher information is predicted.
    pub model: &'a dyn Model,
    /// The model's parameters (in the order of `model.params()`), e.g. a fit's values.
    pub params: Vec<f64>,
    /// Wavelength, in the unit of σ and T.
    pub wavelength: f64,
    /// What the model values are: a BRDF (sr⁻¹) or a radiance.
    pub quantity: Quantity,
    /// The noise each future measurement is assumed to carry.
    pub noise: NoiseModel,
    /// The unit of the wavelength, σ and T (`nm`), for the sentence; None: unstated.
    pub unit: Option<String>,
}

/// What to choose, among what, on top of what.
#[derive(Debug, Clone)]
pub struct Request {
    /// The geometries already measured (radians; possibly none).
    pub existing: Vec<Sample>,
    /// The geometries the instrument can reach.
    pub candidates: Vec<AnglesDeg>,
    /// How many to choose.
    pub n: usize,
    /// A parameter or derived quantity name (`quantities`), or `all` (D-optimal).
    pub target: String,
    /// See [`DYNAMIC_RANGE`].
    pub dynamic_range: f64,
    /// Other wavelengths (unit of σ, T) to plan for as alternatives.
    pub wavelengths: Vec<f64>,
}

/// A quantity's value and linearised standard error (None: not determined).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Estimate {
    /// The quantity's name (`sigma`, `T`, `scale`, `T/sigma`, `amplitude_rough`, …).
    pub name: String,
    /// Its value at the scene's parameters (the point the design linearises at).
    pub value: f64,
    /// The model's unit of a parameter (`λ unit`, `1`, `rad`); empty for a derived quantity.
    pub unit: String,
    /// Linearised standard error, `relative` × |value| (None: not determined).
    pub stderr: Option<f64>,
    /// stderr / |value| (the standard error of ln value).
    pub relative: Option<f64>,
    /// Whether `relative` is at most [`DETERMINED_RELATIVE_SE`].
    pub determined: bool,
    /// A derived quantity (not one of the model's parameters).
    pub derived: bool,
}

impl Estimate {
    /// The estimate of quantity `d` whose relative standard error is `relative` (None,
    /// or not finite: not determined).
    pub fn of_relative(d: &QuantityDef, relative: Option<f64>) -> Estimate {
        let relative = relative.filter(|r| r.is_finite());
        Estimate {
            name: d.name.clone(),
            value: d.value,
            unit: d.unit.clone(),
            stderr: relative.map(|r| r * d.value.abs()),
            relative,
            determined: relative.is_some_and(|r| r <= DETERMINED_RELATIVE_SE),
            derived: d.derived,
        }
    }
}

/// A candidate geometry, what the model predicts there and what it would add.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Candidate {
    /// The candidate's direction in degrees: (θi, θr, φr).
    pub angles: [f64; 3],
    /// The model's value (the measured quantity).
    pub value: f64,
    /// Within the instrument's dynamic range and carrying information.
    pub reachable: bool,
    /// What the candidate alone would add (`choose::single_gains`).
    pub gain: f64,
    /// Whether the design chose it.
    pub chosen: bool,
}

/// The design at another wavelength (its own amplitudes).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Alternative {
    /// The alternative wavelength, in the unit of σ and T.
    pub wavelength: f64,
    /// The geometries chosen at that wavelength (degrees: θi, θr, φr), in the order chosen.
    pub chosen: Vec<[f64; 3]>,
    /// The target's relative standard error after the design there (None: not determined;
    /// for `all`, the largest over the parameters).
    pub target_after: Option<f64>,
}

/// A finished design.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Design {
    /// The target as requested: a quantity's name or `all`.
    pub target: String,
    /// `c-optimal` (one quantity) or `D-optimal` (`all`).
    pub criterion: String,
    /// Number of geometries already measured.
    pub n_existing: usize,
    /// The chosen geometries (degrees: θi, θr, φr), in the order chosen.
    pub chosen: Vec<[f64; 3]>,
    /// Every candidate with its predicted value, reachability and single gain, in the request's
    /// order.
    pub candidates: Vec<Candidate>,
    /// Every parameter and derived quantity with the measured samples alone, and with the
    /// chosen ones added.
    pub before: Vec<Estimate>,
    /// The same with the chosen geometries added to the measured ones.
    pub after: Vec<Estimate>,
    /// The target's relative standard error before and after (None: not determined; for
    /// `all` the largest over the parameters).
    pub target_before: Option<f64>,
    /// The target's relative standard error with the chosen geometries added.
    pub target_after: Option<f64>,
    /// The design at each of the request's other wavelengths, in their order.
    pub alternatives: Vec<Alternative>,
    /// What to do, in one sentence.
    pub sentence: String,
}

/// Plan the next `request.n` samples for `scene` (see the module doc). Errors: a usage
/// error for an unknown target, n = 0, no candidates, a dynamic range ≤ 1 or a wavelength
/// that is not positive; geometry outside the valid domain.
pub fn design(scene: &Scene, request: &Request) -> Result<Design> {
    check(scene, request)?;
    let defs = quantities(scene.model, &scene.params);
    let crit = criterion(&defs, &request.target)?;
    let q = scene.params.len();
    let map: Vec<usize> = (0..q).collect();
    let existing = rows_at(scene, &request.existing, scene.wavelength, &map, q)?;
    let samples: Vec<Sample> = request.candidates.iter().map(AnglesDeg::sample).collect();
    let cand = rows_at(scene, &samples, scene.wavelength, &map, q)?;
    let reachable = reachable(&existing.value, &cand, request.dynamic_range);
    let f0 = predict::information(&existing.rows);
    let chosen = choose::choose(&f0, &cand.rows, request.n, &crit, &reachable);
    let f1 = with_rows(&f0, &cand.rows, &chosen);
    let (before, after) = (estimates(&defs, &f0), estimates(&defs, &f1));
    let gains = choose::single_gains(&f0, &cand.rows, &crit);
    let candidates = (0..samples.len())
        .map(|i| Candidate {
            angles: deg(&request.candidates[i]),
            value: finite_or_zero(cand.value[i]),
            reachable: reachable[i],
            gain: finite_or_zero(gains[i]),
            chosen: chosen.contains(&i),
        })
        .collect();
    let chosen_deg: Vec<[f64; 3]> = chosen
        .iter()
        .map(|&i| deg(&request.candidates[i]))
        .collect();
    let alternatives = request
        .wavelengths
        .iter()
        .map(|&l| alternative(scene, request, &defs, &crit, &existing.rows, l))
        .collect::<Result<Vec<_>>>()?;
    let mut d = Design {
        target: request.target.clone(),
        criterion: match crit {
            Criterion::LogDet => "D-optimal".into(),
            Criterion::Variance(_) => "c-optimal".into(),
        },
        n_existing: request.existing.len(),
        target_before: target_se(&request.target, &before),
        target_after: target_se(&request.target, &after),
        chosen: chosen_deg,
        candidates,
        before,
        after,
        alternatives,
        sentence: String::new(),
    };
    d.sentence = describe::sentence(&d, scene, request.n);
    Ok(d)
}

fn check(scene: &Scene, request: &Request) -> Result<()> {
    crate::model::check_param_count(scene.model, &scene.params)?;
    let usage = |m: String| Err(Error::Usage(m));
    if request.n == 0 {
        return usage("--n 0: choose at least one geometry".into());
    }
    if request.candidates.is_empty() {
        return usage("no candidate geometries to choose from".into());
    }
    if !(request.dynamic_range.is_finite() && request.dynamic_range > 1.0) {
        return usage(format!(
            "--dynamic-range {}: must be a finite number above 1",
            request.dynamic_range
        ));
    }
    for &l in std::iter::once(&scene.wavelength).chain(&request.wavelengths) {
        if !(l.is_finite() && l > 0.0) {
            return usage(format!("wavelength {l} must be finite and positive"));
        }
    }
    Ok(())
}

/// The criterion of a target name: `all` is D-optimal, a quantity's name c-optimal on it.
fn criterion(defs: &[QuantityDef], target: &str) -> Result<Criterion> {
    if target.eq_ignore_ascii_case("all") {
        return Ok(Criterion::LogDet);
    }
    defs.iter()
        .find(|d| d.name.eq_ignore_ascii_case(target))
        .map(|d| Criterion::Variance(d.coef.clone()))
        .ok_or_else(|| {
            Error::Usage(format!(
                "--target '{target}': not a parameter or derived quantity of this model (choose one of: {}, all)",
                defs.iter().map(|d| d.name.as_str()).collect::<Vec<_>>().join(", ")
            ))
        })
}

/// The information rows of `samples` measured at wavelength `lambda`.
fn rows_at(
    scene: &Scene,
    samples: &[Sample],
    lambda: f64,
    map: &[usize],
    q: usize,
) -> Result<predict::Rows> {
    if samples.is_empty() {
        return Ok(predict::Rows {
            value: Vec::new(),
            rows: DMatrix::zeros(0, q),
        });
    }
    let geo = Geometry::new(samples, &[lambda], scene.quantity)?;
    Ok(predict::information_rows(
        scene.model,
        &scene.params,
        &geo,
        scene.noise,
        map,
        q,
    ))
}

/// Which candidates can be measured: a finite value within the dynamic range of the
/// largest value (measured or candidate) and a row with information.
fn reachable(existing: &[f64], cand: &predict::Rows, range: f64) -> Vec<bool> {
    let peak = existing
        .iter()
        .chain(&cand.value)
        .filter(|v| v.is_finite())
        .fold(0.0f64, |m, v| m.max(v.abs()));
    (0..cand.value.len())
        .map(|i| {
            let v = cand.value[i];
            v.is_finite() && v.abs() >= peak / range && cand.rows.row(i).iter().any(|x| *x != 0.0)
        })
        .collect()
}

/// `f` plus the information of the given rows of `rows`.
fn with_rows(f: &DMatrix<f64>, rows: &DMatrix<f64>, which: &[usize]) -> DMatrix<f64> {
    let mut m = f.clone();
    for &i in which {
        let g = rows.row(i).transpose();
        m += &g * g.transpose();
    }
    m
}

/// Every quantity's linearised estimate under information `f` (the first rows of `f`
/// belong to the model's parameters; extra variables are other channels' amplitudes).
fn estimates(defs: &[QuantityDef], f: &DMatrix<f64>) -> Vec<Estimate> {
    let cov = predict::covariance(f);
    defs.iter()
        .map(|d| {
            let mut c = DVector::zeros(f.nrows());
            c.rows_mut(0, d.coef.len()).copy_from(&d.coef);
            let se = cov.se(&c);
            let relative = if d.log {
                se
            } else {
                se.map(|s| s / d.value.abs())
            };
            Estimate::of_relative(d, relative)
        })
        .collect()
}

/// The target's relative standard error: the named quantity's, or for `all` the largest
/// over the parameters (None when any is not determined).
fn target_se(target: &str, est: &[Estimate]) -> Option<f64> {
    if target.eq_ignore_ascii_case("all") {
        return est
            .iter()
            .filter(|e| !e.derived)
            .map(|e| e.relative)
            .try_fold(0.0f64, |m, r| r.map(|r| m.max(r)));
    }
    est.iter()
        .find(|e| e.name.eq_ignore_ascii_case(target))
        .and_then(|e| e.relative)
}

/// The design at wavelength `lambda`: the candidates measured there, with their own copies
/// of the per-channel amplitudes (a new channel of a joint fit), on top of the measured
/// samples at the scene's wavelength.
fn alternative(
    scene: &Scene,
    request: &Request,
    defs: &[QuantityDef],
    crit: &Criterion,
    existing: &DMatrix<f64>,
    lambda: f64,
) -> Result<Alternative> {
    let specs = scene.model.params();
    let q0 = specs.len();
    let mut map: Vec<usize> = (0..q0).collect();
    let mut q = q0;
    for (j, s) in specs.iter().enumerate() {
        if PER_CHANNEL.contains(&s.name) && lambda != scene.wavelength {
            map[j] = q;
            q += 1;
        }
    }
    let samples: Vec<Sample> = request.candidates.iter().map(AnglesDeg::sample).collect();
    let cand = rows_at(scene, &samples, lambda, &map, q)?;
    let mut base = DMatrix::zeros(q, q);
    base.view_mut((0, 0), (q0, q0))
        .copy_from(&predict::information(existing));
    let reach = reachable(&[], &cand, request.dynamic_range);
    let crit = match crit {
        Criterion::Variance(c) => Criterion::Variance(c.clone().resize_vertically(q, 0.0)),
        Criterion::LogDet => Criterion::LogDet,
    };
    let chosen = choose::choose(&base, &cand.rows, request.n, &crit, &reach);
    let after = estimates(defs, &with_rows(&base, &cand.rows, &chosen));
    Ok(Alternative {
        wavelength: lambda,
        chosen: chosen
            .iter()
            .map(|&i| deg(&request.candidates[i]))
            .collect(),
        target_after: target_se(&request.target, &after),
    })
}

fn deg(a: &AnglesDeg) -> [f64; 3] {
    [a.theta_i, a.theta_r, a.phi_r]
}

fn finite_or_zero(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        0.0
    }
}
