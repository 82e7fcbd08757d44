//! A dataset's fit as the CLI and the Python package run it: the fit's data from a
//! [`Dataset`] (values and weights checked against double-precision overflow), every
//! candidate model (`auto` compares five by BIC, skipping fits that are not a usable
//! optimum), for a joint multi-channel fit the note on how much narrower σ and T are than
//! from one channel, and for one dataset the profile-likelihood intervals ([`intervals`]).
//!
//! This is the one path from measured samples to a finished [`Outcome`]; the reporters in
//! [`crate::report::outcome`] turn an outcome into the text report and the JSON object.

pub(crate) mod batch;
mod input;
pub(crate) mod intervals;

use super::driver::{self, FitConfig, FitInput, FitResult};
use crate::error::{Error, Result};
use crate::geometry::Quantity;
use crate::io::{self, Dataset};
use crate::model::{self, ModelOptions};
use goniofit_lm::Stop;

pub use input::check_magnitudes;
pub(crate) use input::floor_for;
pub(crate) use intervals::{profile_intervals, MAX_PROFILED};

/// The candidate of `model = "auto"` with the physically based lobe: kbs+lambert with the
/// dielectric Fresnel factor and Smith shadowing–masking (He, Torrance, Sillion & Greenberg
/// 1991). A dielectric is what a paint, a plastic or a glaze is; the conductor factor would
/// add κ, which a single channel rarely determines beside n.
pub(crate) const AUTO_EXTENDED: &str = "kbs+lambert --fresnel dielectric --shadowing smith";

/// Candidate models for `model = "auto"`, compared by BIC (model names with their factor
/// options, as reports name them).
pub const AUTO_CANDIDATES: [&str; 5] = [
    "lambert",
    "lambert-specular",
    "kbs",
    "kbs+lambert",
    AUTO_EXTENDED,
];

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
    /// and dataset. `config.lm.stop` (if any) is shared by every candidate; without one the
    /// fit makes its own from `config.lm` ([`goniofit_lm::LmConfig::new_stop`]).
    pub config: FitConfig,
    /// Standard errors from the stated uncertainties as they are (scipy's
    /// `absolute_sigma=True`), not rescaled by the residual scatter.
    pub absolute_sigma: bool,
    /// Compute the profile-likelihood intervals of the chosen fit (when it has at most
    /// `MAX_PROFILED` free parameters; they refit the data a few dozen times per quantity).
    pub intervals: bool,
}

impl DatasetFit {
    /// The candidate model names (lower case): those of `auto` ([`AUTO_CANDIDATES`]; when
    /// the caller chose factors, the four plain names, each with those factors), or the one
    /// given (checked to exist).
    pub fn candidates(&self) -> Result<Vec<String>> {
        if self.model.eq_ignore_ascii_case("auto") {
            let own_factors = self.config.model_opts.has_factors();
            Ok(AUTO_CANDIDATES
                .iter()
                .filter(|c| !(own_factors && **c == AUTO_EXTENDED))
                .map(|s| s.to_string())
                .collect())
        } else {
            model::by_name(&self.model, &ModelOptions::default()).map_err(|e| match e {
                Error::UnknownModel(name) => Error::Usage(format!(
                    "unknown model '{name}' (known: kbs, kbs-smooth, kbs-rough, kbs+lambert, lambert, lambert-specular, or auto to fit the last four and kbs+lambert --fresnel dielectric --shadowing smith and keep the lowest BIC)"
                )),
                e => e,
            })?;
            Ok(vec![self.model.to_ascii_lowercase()])
        }
    }

    /// The configuration of one candidate model on a dataset: `model` a name, optionally
    /// with factor options ([`ModelOptions::with_factors_of`]); `uncertainties`: its
    /// weights come from a stated `sigma_L`.
    pub fn config_for(&self, model: &str, uncertainties: bool) -> FitConfig {
        let (model, model_opts) = self.config.model_opts.with_factors_of(model);
        FitConfig {
            model,
            model_opts,
            weights_are_uncertainties: uncertainties,
            ..self.config.clone()
        }
    }
}

/// One dataset's fit: every candidate model, and the chosen one (lowest BIC among the
/// usable fits).
#[derive(Debug, Clone)]
pub struct Outcome {
    /// What the reports call the dataset (a file name, `file [group]`, a Python group).
    pub label: String,
    /// The dataset; after a one-channel fit without its samples, lines and values (the
    /// input holds them), and a wavelength column of one value kept as that value once.
    pub dataset: Dataset,
    /// The fit's data built from the dataset (values, weights, channels, geometry).
    pub input: FitInput,
    /// One result per candidate model fitted, in [`DatasetFit::candidates`] order (a stop
    /// request leaves the later ones out).
    pub candidates: Vec<FitResult>,
    /// The chosen candidate (with the joint-fit note for several channels).
    pub result: FitResult,
    /// Profile-likelihood intervals of `result` (empty when not computed).
    pub intervals: Vec<super::stats::profile::Interval>,
    /// Wall-clock seconds the intervals took (0 when not computed).
    pub interval_seconds: f64,
    /// Whether a stop (signal or time limit) cut the intervals' walks short, so that none
    /// is reported: the run did not do all it was asked (exit 3).
    pub intervals_stopped: bool,
    /// Wall-clock seconds of the whole dataset's fit: its input, every candidate's fit and
    /// the intervals.
    pub seconds: f64,
}

/// Fit one dataset with every candidate model and keep the lowest BIC among the usable
/// fits. Every candidate shares one stop request (`spec.config.lm.stop`, or one made from
/// `spec.config.lm`): once it fires, the running fit ends at its best point, and candidates
/// not yet started are skipped (named in a note). Errors: the dataset's own (no wavelength
/// for a KBS model, values that would overflow) and the fit's.
pub fn fit_dataset(spec: &DatasetFit, label: String, ds: Dataset) -> Result<Outcome> {
    fit_dataset_near(spec, label, ds, None)
}

/// [`fit_dataset`], each candidate model first started at its optimum in `near` (the fit
/// of a neighbouring dataset, e.g. the texel before this one) and kept when that is an
/// optimum as good as a search would find (`fit_near_or_search`); otherwise searched as
/// by [`fit_dataset`].
pub fn fit_dataset_near(
    spec: &DatasetFit,
    label: String,
    mut ds: Dataset,
    near: Option<&Outcome>,
) -> Result<Outcome> {
    let t0 = std::time::Instant::now();
    let candidates = spec.candidates()?;
    let needs_wavelength = candidates.iter().any(|m| m.starts_with("kbs"));
    let one_channel = ds
        .channel
        .as_ref()
        .is_none_or(|c| c.iter().all(|l| *l == c[0]));
    let input = if one_channel {
        // The input holds the angles (as geometry) and values; what is left of the dataset
        // serves the residuals file (rows) and the report's setting (weights, wavelength).
        spec.input_taking(&mut ds, needs_wavelength)?
    } else {
        // A joint fit keeps the samples for its one-channel comparison fit.
        spec.input(&ds, needs_wavelength)?
    };
    let stop = match &spec.config.lm.stop {
        Some(stop) => stop.clone(),
        None => spec.config.lm.new_stop(),
    };
    let uncertainties = ds.sigma_l.is_some();
    let (mut results, not_fitted) =
        fit_candidates(spec, &input, (&candidates, near), uncertainties, &stop)?;
    let mut result = chosen(&mut results, &not_fitted);
    finish_result(spec, &ds, &input, &stop, &mut result)?;
    let t_intervals = std::time::Instant::now();
    let (intervals, intervals_stopped) =
        intervals_of(spec, &input, &mut result, uncertainties, &stop)?;
    let interval_seconds = t_intervals.elapsed().as_secs_f64();
    Ok(Outcome {
        label,
        dataset: ds,
        input,
        candidates: results,
        result,
        intervals,
        interval_seconds,
        intervals_stopped,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// Fit every candidate model in turn (each first from its optimum in `near`, when given),
/// sharing `stop`: the results, and the names of the candidates a stop kept from a result
/// (not started, or cut in their first evaluation; the first candidate's stop is an error:
/// there is nothing to report).
fn fit_candidates<'c>(
    spec: &DatasetFit,
    input: &FitInput,
    (candidates, near): (&'c [String], Option<&Outcome>),
    uncertainties: bool,
    stop: &Stop,
) -> Result<(Vec<FitResult>, Vec<&'c str>)> {
    let mut results: Vec<FitResult> = Vec::new();
    let mut not_fitted = Vec::new();
    for m in candidates {
        if stop.is_requested() && !results.is_empty() {
            not_fitted.push(m.as_str());
            continue;
        }
        let mut config = spec.config_for(m, uncertainties);
        config.lm.stop = Some(stop.clone());
        let search = || match seed_of(&results, &config) {
            Some(seed) => fit_seeded(input, &config, seed),
            None => fit_with_factors(input, &config),
        };
        let fitted = match near.and_then(|o| near_fit(o, &config)) {
            Some(near) => fit_near_or_search(input, &config, near, search),
            None => search(),
        };
        match fitted {
            Err(Error::Stopped(_)) if !results.is_empty() => not_fitted.push(m.as_str()),
            r => results.push(r?),
        }
    }
    Ok((results, not_fitted))
}

/// The fraction of the data's variance a fit leaves unexplained (1 − R² in the fitted
/// space), relative to the neighbour's, beyond which a fit started at the neighbour's
/// optimum is searched again (`fit_near_or_search`). The fraction does not change with
/// the texel's brightness; between neighbouring texels of the benchmark batch
/// (benches/texels.py: σ, T/σ and scale drawn anew per texel) the ratio has median 1, and
/// 99 % of pairs lie below 3.8, while a valley that is not the texel's optimum leaves a
/// misfit many times the noise.
pub(crate) const NEAR_UNEXPLAINED_RATIO: f64 = 4.0;

/// `near`'s fit of `config`'s model (with the same factors) when it converged: a start
/// worth taking for the next dataset. None for a lobe with factors, which is always
/// searched: the Fresnel index has valleys that a neighbour's optimum does not tell apart,
/// and a warm start can converge in one above the searched fit's cost, passing the
/// acceptance of [`near_kept`] (tests/trust/warm_start.rs checks `auto` against the search).
fn near_fit<'o>(near: &'o Outcome, config: &FitConfig) -> Option<&'o FitResult> {
    if config.model_opts.has_factors() {
        return None;
    }
    let factors = config.model_opts.factors_label();
    near.candidates
        .iter()
        .find(|r| r.model == config.model && r.factors == factors)
        .filter(|r| r.converged())
}

/// The fit started at `near`'s optimum ([`driver::fit_near`]), kept when [`near_kept`]
/// accepts it; otherwise the searched fit (`search`), or the near-started one where it is
/// the better ([`better_fit`]). A texel whose optimum lies in another valley than its neighbour's
/// leaves a misfit there, and is searched.
fn fit_near_or_search(
    input: &FitInput,
    config: &FitConfig,
    near: &FitResult,
    search: impl FnOnce() -> Result<FitResult>,
) -> Result<FitResult> {
    let warm = match driver::fit_near(input, config, near) {
        Ok(Some(w)) => w,
        Ok(None) | Err(Error::Stopped(_)) => return search(),
        Err(e) => return Err(e),
    };
    if near_kept(&warm, near) || config.lm.stop.as_ref().is_some_and(Stop::is_requested) {
        return Ok(warm);
    }
    let searched = search()?;
    Ok(if better_fit(&warm, &searched) {
        warm
    } else {
        searched
    })
}

/// Whether `warm`, started at `near`'s optimum, is kept without a search (see
/// [`fit_near_or_search`]): it converged, it leaves at most [`NEAR_UNEXPLAINED_RATIO`]
/// times the fraction of the data `near` left unexplained, and its residuals do not run
/// in long stretches of one sign along the scans (the adequacy's runs test: the mark of a
/// lobe of the wrong shape) unless `near`'s did too.
fn near_kept(warm: &FitResult, near: &FitResult) -> bool {
    let systematic = |r: &FitResult| r.adequacy.reasons.iter().any(|x| x.code == "runs");
    let unexplained = |r: &FitResult| Some(1.0 - r.r2).filter(|u| *u >= 0.0);
    let within = match (unexplained(warm), unexplained(near)) {
        (Some(w), Some(n)) => w <= NEAR_UNEXPLAINED_RATIO * n,
        _ => false,
    };
    warm.converged() && within && (systematic(near) || !systematic(warm))
}

/// For a candidate with factors on its lobe: the converged fit of the same model without
/// them among `done`, whose optimum seeds the candidate's second start.
fn seed_of<'r>(done: &'r [FitResult], config: &FitConfig) -> Option<&'r FitResult> {
    if !config.model_opts.has_factors() {
        return None;
    }
    done.iter()
        .find(|r| r.factors.is_empty() && r.model == config.model && r.converged())
}

/// A fit of `config`'s model; for a KBS lobe with factors and no plain fit of it at hand,
/// the plain model (the factors and their parameters' `--init`/`--fix` left out) is fitted
/// first and seeds the second start of [`fit_seeded`]. Without a converged plain fit (or
/// once a stop is requested) the model's own fit alone.
fn fit_with_factors(input: &FitInput, config: &FitConfig) -> Result<FitResult> {
    if !(config.model_opts.has_factors() && config.model.starts_with("kbs")) {
        return driver::fit(input, config);
    }
    let mut plain = config.clone();
    plain.model_opts.fresnel = crate::model::fresnel::Fresnel::None;
    plain.model_opts.shadowing = crate::model::shadowing::Shadowing::None;
    let factor_param = |(k, _): &(String, f64)| k == "n" || k == "kappa";
    plain.init.retain(|p| !factor_param(p));
    plain.fix.retain(|p| !factor_param(p));
    plain.lm.progress = false;
    match driver::fit(input, &plain) {
        Ok(seed)
            if seed.converged() && !config.lm.stop.as_ref().is_some_and(Stop::is_requested) =>
        {
            fit_seeded(input, config, &seed)
        }
        _ => driver::fit(input, config),
    }
}

/// A candidate with factors fitted twice: from its own start search, and from the plain
/// model's optimum `plain` (its σ, T, scales and amplitudes, the factor's parameters at
/// their starting values; the user's `--init` and `--fix` kept). The lower cost among the
/// converged fits is kept (both counted in its work). The factors do not nest the plain lobe
/// (F → 1 only as n → ∞, G → 1 only as T/σ → ∞), so no bound by the plain cost holds; the
/// second start keeps the extended fit from ending in a valley far from the plain lobe's
/// when a better one lies beside it.
fn fit_seeded(input: &FitInput, config: &FitConfig, plain: &FitResult) -> Result<FitResult> {
    let own = driver::fit(input, config)?;
    if config.lm.stop.as_ref().is_some_and(Stop::is_requested) {
        return Ok(own);
    }
    let mut seeded = config.clone();
    let given = |name: &str| {
        config
            .init
            .iter()
            .chain(&config.fix)
            .any(|(k, _)| k == name)
    };
    for (p, &v) in plain.layout.params.iter().zip(&plain.values) {
        if !given(&p.name) {
            seeded.init.push((p.name.clone(), v));
        }
    }
    let other = match driver::fit(input, &seeded) {
        Ok(r) => r,
        Err(Error::Stopped(_)) => return Ok(own),
        Err(e) => return Err(e),
    };
    Ok(if better_fit(&other, &own) { other } else { own })
}

/// Whether fit `a` is the better of two fits of one model from different starts. A fit that
/// ended at an optimum (converged, or `degenerate`: at an edge of the domain or where the
/// data does not determine a parameter) beats one that did not (stopped, out of
/// iterations). Between two that did, the lower cost wins, but a converged fit keeps its
/// place against a degenerate one unless the degenerate cost is lower by more than
/// [`EDGE_MARGIN`](super::start::EDGE_MARGIN): the same rule as the start search's, under
/// which the data's best fit is the edge only when it is clearly better than the best
/// usable optimum.
fn better_fit(a: &FitResult, b: &FitResult) -> bool {
    use goniofit_lm::Termination;
    let ended = |r: &FitResult| {
        r.is_finite() && (r.converged() || r.termination == Termination::Degenerate)
    };
    match (ended(a), ended(b)) {
        (true, false) => true,
        (false, true) => false,
        (false, false) => a.cost < b.cost,
        (true, true) => match (a.converged(), b.converged()) {
            (true, false) => b.cost >= a.cost * (1.0 - super::start::EDGE_MARGIN),
            (false, true) => a.cost < b.cost * (1.0 - super::start::EDGE_MARGIN),
            _ => a.cost < b.cost,
        },
    }
}

/// The candidate with the lowest BIC among the usable ones ([`lowest_bic_usable`]), with
/// the notes on the candidates skipped or not fitted. The chosen fit keeps its per-sample
/// vectors; the candidates (the comparison) keep their summaries only, so a big fit's
/// vectors exist once.
fn chosen(results: &mut [FitResult], not_fitted: &[&str]) -> FitResult {
    let (best, skipped) = lowest_bic_usable(results);
    let samples = results[best].take_samples();
    let mut result = results[best].clone();
    result.put_samples(samples);
    for r in results.iter_mut() {
        r.take_samples();
    }
    result.notes.extend(skipped);
    result.notes.extend(tie_note(results, best));
    if !not_fitted.is_empty() {
        result.notes.push(format!(
            "the fit was stopped before the candidates {} were fitted",
            not_fitted.join(", ")
        ));
    }
    result
}

/// The profile-likelihood intervals of `result` when asked for and the fit is a usable
/// optimum (a note on `result` says why not otherwise), and whether a stop cut their
/// walks short (then none is returned: a walk cut short ends at a wrong likelihood).
fn intervals_of(
    spec: &DatasetFit,
    input: &FitInput,
    result: &mut FitResult,
    uncertainties: bool,
    stop: &Stop,
) -> Result<(Vec<super::stats::profile::Interval>, bool)> {
    let wanted = spec.intervals && result.n_free <= MAX_PROFILED;
    if !wanted {
        return Ok((Vec::new(), false));
    }
    if !result.converged() {
        // A profile around a point that is not a usable optimum (degenerate, stopped)
        // would bound nothing the data says.
        result
            .notes
            .push("no profile intervals: the fit did not converge to a usable optimum".into());
        return Ok((Vec::new(), false));
    }
    let intervals = profile_intervals(spec, input, result, uncertainties, stop)?;
    if !stop.is_requested() {
        return Ok((intervals, false));
    }
    result.notes.push(
        "profile-likelihood intervals not computed: the fit was stopped while they were \
         walked (only the standard errors are shown)"
            .into(),
    );
    Ok((Vec::new(), true))
}

/// The chosen fit as reported: absolute-sigma standard errors if asked, the reflectance
/// factors of a BRDF, and for a joint fit (not stopped) the narrowing note.
fn finish_result(
    spec: &DatasetFit,
    ds: &Dataset,
    input: &FitInput,
    stop: &Stop,
    result: &mut FitResult,
) -> Result<()> {
    if spec.absolute_sigma {
        result.use_absolute_sigma();
    }
    result.add_reflectance_factors(spec.quantity);
    if input.channel_names.len() > 1 && !stop.is_requested() {
        if let Some(note) = joint_narrowing(spec, ds, result, stop)? {
            result.notes.push(note);
        }
    }
    Ok(())
}

/// The candidate with the lowest BIC among the converged fits (among all when none
/// converged), and a note for each candidate with a lower BIC that was skipped because its
/// fit is not a usable optimum (degenerate, or stopped without converging), quoting why:
/// the degeneracy itself ([`FitResult::unusable`]: one reason, whatever other notes the
/// point also earns), else the fit's last note. `results` is not empty.
fn lowest_bic_usable(results: &[FitResult]) -> (usize, Vec<String>) {
    let any_converged = results.iter().any(|r| r.converged());
    let best = results
        .iter()
        .enumerate()
        .filter(|(_, r)| r.converged() || !any_converged)
        .min_by(|a, b| a.1.bic.total_cmp(&b.1.bic))
        .map_or(0, |(i, _)| i);
    let skipped = results
        .iter()
        .filter(|r| !r.converged() && any_converged && r.bic < results[best].bic)
        .map(|r| {
            format!(
                "auto: skipped {} (lower BIC {:.4}) because its fit is not usable: {}",
                r.full_model(),
                r.bic,
                r.unusable
                    .as_deref()
                    .or(r.notes.last().map(String::as_str))
                    .unwrap_or(r.termination.describe())
            )
        })
        .collect();
    (best, skipped)
}

/// ΔBIC below which two models' fits are a tie: the data do not prefer one (Kass &
/// Raftery's "not worth more than a bare mention").
pub(crate) const BIC_TIE: f64 = 2.0;

/// The usable candidates (converged, other than `best`) whose BIC lies within
/// [`BIC_TIE`] of the chosen one's, with their ΔBIC, lowest first; empty when the chosen
/// fit is not usable itself.
pub(crate) fn tied_with(results: &[FitResult], best: usize) -> Vec<(&FitResult, f64)> {
    if !results[best].converged() {
        return Vec::new();
    }
    let mut tied: Vec<(&FitResult, f64)> = results
        .iter()
        .enumerate()
        .filter(|&(i, r)| i != best && r.converged())
        .map(|(_, r)| (r, r.bic - results[best].bic))
        .filter(|&(_, d)| d < BIC_TIE)
        .collect();
    tied.sort_by(|a, b| a.1.total_cmp(&b.1));
    tied
}

/// The note naming a tie of the chosen fit with other usable candidates ([`tied_with`]),
/// e.g. "tie: lambert-specular and kbs+lambert differ by ΔBIC = 0.5 < 2; the data do not
/// prefer one".
fn tie_note(results: &[FitResult], best: usize) -> Option<String> {
    let tied = tied_with(results, best);
    let chosen = &results[best].full_model();
    match tied.as_slice() {
        [] => None,
        [(other, d)] => Some(format!(
            "tie: {chosen} and {} differ by ΔBIC = {d:.2} < {BIC_TIE}; the data do not prefer one",
            other.full_model()
        )),
        more => {
            let list: Vec<String> = more
                .iter()
                .map(|(r, d)| format!("{} (ΔBIC = {d:.2})", r.full_model()))
                .collect();
            Some(format!(
                "tie: {chosen} and {} lie within ΔBIC < {BIC_TIE} of each other; the data do not prefer one",
                list.join(", ")
            ))
        }
    }
}

/// For a joint fit: how much narrower σ, T and T/σ are than from the middle channel alone,
/// or that the data determines them neither way.
fn joint_narrowing(
    spec: &DatasetFit,
    ds: &Dataset,
    joint: &FitResult,
    stop: &Stop,
) -> Result<Option<String>> {
    let Some(labels) = &ds.channel else {
        return Ok(None);
    };
    let names = &joint.layout.channel_names;
    let mid = &names[names.len() / 2];
    let idx: Vec<usize> = (0..labels.len())
        .filter(|&i| io::shown_text(&labels[i]) == mid.as_str())
        .collect();
    let mut single = ds.subset(&idx);
    single.channel = None;
    let input = spec.input(&single, true)?;
    let mut config = spec.config_for(&joint.full_model(), ds.sigma_l.is_some());
    config.lm.progress = false;
    config.lm.stop = Some(stop.clone());
    let alone = match driver::fit(&input, &config) {
        Err(Error::Stopped(_)) => return Ok(None),
        r => r?,
    };
    if stop.is_requested() {
        // The single-channel fit was cut short: its errors say nothing.
        return Ok(None);
    }
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
