//! The fit report as one typed document: what `fit --json` writes, what the Python
//! package's `FitResult.report` holds and what `goniofit plot` reads back. Numbers that are
//! not finite are written as `null` (JSON has no NaN); fields that are numbers or null are
//! `Option<f64>` here.

use super::RunInfo;
use crate::fit::driver::{FitResult, Verdict};
use crate::fit::problem::loss::LossKind;
use crate::fit::stats::adequacy::Adequacy;
use crate::fit::stats::profile::LEVELS;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// A fit's report. Keys as in the JSON object, which lists them in this order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitReport {
    /// The model's name (`kbs+lambert`, …).
    pub model: String,
    /// Its factor options as command-line text (`--fresnel dielectric`), empty without.
    pub factors: String,
    /// What the data determines (`full`, `rough`, `smooth`, `partial`, `not_computed`).
    pub verdict: Verdict,
    /// Whether the fit is at a usable optimum.
    pub converged: bool,
    /// The solver's termination (`ftol`, `degenerate`, …; [`termination_name`]).
    pub termination: String,
    /// The fitted parameters by name.
    pub params: BTreeMap<String, ParamEntry>,
    /// The derived quantities (T/σ, Beckmann's α, reflectances, …) by name.
    pub derived: BTreeMap<String, DerivedEntry>,
    /// The report's notes, in words.
    pub notes: Vec<String>,
    pub cost: Option<f64>,
    pub loss: LossEntry,
    pub chi2: Option<f64>,
    pub reduced_chi2: Option<f64>,
    pub rms: Option<f64>,
    pub max_abs_residual: Option<f64>,
    pub r2: Option<f64>,
    pub aic: Option<f64>,
    pub bic: Option<f64>,
    /// Samples fitted.
    pub n: usize,
    /// Free parameters.
    pub n_free: usize,
    /// Whether the model describes the data, with its tests.
    pub adequacy: AdequacyEntry,
    /// The checks of the paper's assumptions at the fitted surface (KBS models), by name.
    pub validity: Option<BTreeMap<String, ValidityEntry>>,
    pub correlation: Correlation,
    pub singular_values: Vec<Option<f64>>,
    pub condition: Option<f64>,
    /// The starting point by parameter name, and whether it came from the start search
    /// (`search`) or a neighbouring dataset's optimum (`neighbour`).
    pub start: BTreeMap<String, Option<f64>>,
    pub start_from: String,
    pub iterations: u64,
    pub evaluations: u64,
    pub jacobian_evaluations: u64,
    /// Wall-clock seconds of the fit, of its profile intervals, of the start search with
    /// its refinement, and of the grid alone.
    pub seconds: f64,
    pub interval_seconds: f64,
    pub init_seconds: f64,
    pub start_seconds: f64,
    /// Samples per evaluation mode of the KBS series (`series`, `rough`, …).
    pub modes: BTreeMap<String, usize>,
    /// Whether fitted values exist for every sample at the reported point.
    pub fitted_computed: bool,
    /// The range of g over the samples (KBS models).
    pub g_range: Option<[Option<f64>; 2]>,
    /// The input as named on the command line, the fit's setting, the command line and
    /// the version of goniofit.
    pub input: String,
    pub setting: super::Setting,
    pub command: String,
    pub version: String,
    /// What `goniofit plot` needs to redraw the fit (reports of a dataset's outcome).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub replay: Option<Replay>,
    /// The candidates of a model comparison (`--model auto`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub comparison: Option<Vec<ComparisonRow>>,
}

/// An estimate: its value, standard error (null when unknown), whether the data determine
/// it, and its profile-likelihood intervals at 68.27 % and 95 % (`[lo, hi]`, null for an
/// open side) when computed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    pub value: Option<f64>,
    pub stderr: Option<f64>,
    pub determined: bool,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interval68: Option<[Option<f64>; 2]>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interval95: Option<[Option<f64>; 2]>,
}

/// A fitted parameter: its estimate, whether it was held fixed, and its unit in the run's
/// unit setting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamEntry {
    #[serde(flatten)]
    pub estimate: Estimate,
    pub fixed: bool,
    pub unit: String,
}

/// A derived quantity: its estimate, its meaning in one line, and its unit (which depends
/// on whether the verdict is a smooth surface).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DerivedEntry {
    #[serde(flatten)]
    pub estimate: Estimate,
    pub doc: String,
    pub unit: String,
}

/// The robust loss: its kind, its scale C and how many samples lie beyond it (null for
/// the linear loss).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LossEntry {
    pub kind: LossKind,
    pub f_scale: Option<f64>,
    pub beyond_f_scale: Option<usize>,
}

/// The adequacy verdict with its headline in words.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdequacyEntry {
    #[serde(flatten)]
    pub adequacy: Adequacy,
    pub headline: String,
}

/// One validity check.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValidityEntry {
    /// Whether the fitted surface satisfies it; null when the data does not determine it.
    pub satisfied: Option<bool>,
    pub value: Option<f64>,
    pub limit: f64,
    pub text: String,
}

/// The correlation matrix of the free parameters, with the most correlated pairs (those
/// the text report lists).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Correlation {
    pub names: Vec<String>,
    pub matrix: Vec<Vec<Option<f64>>>,
    pub largest: Vec<Pair>,
}

/// Two correlated parameters and their correlation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pair {
    pub a: String,
    pub b: String,
    pub rho: Option<f64>,
}

/// What `goniofit plot` needs to redraw a fit: the fit's command-line arguments, the model
/// with its factor options (those of an `auto` choice are not among the arguments), and
/// the value of every parameter in layout order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Replay {
    pub args: Vec<String>,
    pub model: String,
    pub factors: String,
    pub names: Vec<String>,
    pub values: Vec<f64>,
    pub n_free: usize,
}

/// One candidate of a model comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ComparisonRow {
    /// The model with its factor options.
    pub model: String,
    pub bic: Option<f64>,
    pub aic: Option<f64>,
    pub cost: Option<f64>,
    pub converged: bool,
    pub termination: String,
    /// Its BIC minus the chosen fit's.
    pub delta_bic: Option<f64>,
    pub chosen: bool,
    /// A usable fit within ΔBIC < 2 of the chosen one.
    pub tie: bool,
}

/// The solver's termination as the report spells it (`ftol`, `degenerate`, …).
pub fn termination_name(t: crate::lm::Termination) -> String {
    format!("{t:?}").to_lowercase()
}

/// A finite number, or None.
pub fn num(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

impl FitReport {
    /// The report of fit `r` run as `info` says, with its profile intervals (no replay
    /// block and no comparison: [`super::outcome::report`] adds those).
    pub fn of(r: &FitResult, info: &RunInfo) -> FitReport {
        let mut params = params_of(r, info);
        let mut derived = derived_of(r, info);
        attach_intervals(info, &mut params, &mut derived);
        FitReport {
            model: r.model.clone(),
            factors: r.factors.trim().to_string(),
            verdict: r.verdict,
            converged: r.converged(),
            termination: termination_name(r.termination),
            params,
            derived,
            notes: r.notes.clone(),
            cost: num(r.cost),
            loss: LossEntry {
                kind: r.loss.kind,
                f_scale: num(r.loss.f_scale),
                beyond_f_scale: r.beyond_f_scale,
            },
            chi2: num(r.chi2),
            reduced_chi2: num(r.reduced_chi2),
            rms: num(r.rms),
            max_abs_residual: num(r.max_abs_residual),
            r2: num(r.r2),
            aic: num(r.aic),
            bic: num(r.bic),
            n: r.n,
            n_free: r.n_free,
            adequacy: AdequacyEntry {
                adequacy: r.adequacy.clone(),
                headline: r.adequacy.headline(),
            },
            validity: validity_of(r),
            correlation: correlation_of(r),
            singular_values: r.singular_values.iter().map(|v| num(*v)).collect(),
            condition: num(r.condition),
            start: start_of(r),
            start_from: if r.started_near {
                "neighbour"
            } else {
                "search"
            }
            .into(),
            iterations: r.iterations,
            evaluations: r.evaluations,
            jacobian_evaluations: r.jacobian_evaluations,
            seconds: r.seconds,
            interval_seconds: info.interval_seconds,
            init_seconds: r.init_seconds,
            start_seconds: r.start_seconds,
            modes: r.modes.clone(),
            fitted_computed: r.fitted_computed,
            g_range: r.g_range.map(|(a, b)| [num(a), num(b)]),
            input: info.input.clone(),
            setting: info.setting.clone(),
            command: info.command.clone(),
            version: info.version.clone(),
            replay: None,
            comparison: None,
        }
    }

    /// The report as a JSON value (keys of objects sorted).
    pub fn to_value(&self) -> serde_json::Value {
        serde_json::to_value(self).unwrap_or(serde_json::Value::Null)
    }

    /// The pictures' second title line (so that `goniofit plot` says what `fit --plot`
    /// says): T/σ with its standard error, the verdict when it leaves something
    /// undetermined, the parameters the data does not determine, and whether the fit
    /// converged (or why not).
    pub fn status_line(&self) -> String {
        use crate::error::fmt_num;
        let mut parts = Vec::new();
        let t_over_sigma = self.derived.get("T/sigma").map(|d| &d.estimate);
        if let Some((value, d)) = t_over_sigma.and_then(|d| Some((d.value?, d))) {
            parts.push(match d.stderr {
                Some(e) => format!("T/σ = {} ± {}", fmt_num(value), fmt_num(e)),
                None => format!("T/σ = {}", fmt_num(value)),
            });
        }
        let mut undetermined: Vec<String> = self
            .undetermined()
            .iter()
            .map(|k| k.replace("sigma", "σ"))
            .collect();
        // σ and T first, as in the report.
        undetermined.sort_by_key(|k| (k != "σ", k != "T", k.clone()));
        if self.verdict != Verdict::Full {
            parts.push(self.verdict.describe().replace("sigma", "σ"));
        }
        if !undetermined.is_empty() {
            parts.push(format!("not determined: {}", undetermined.join(", ")));
        }
        let termination = &self.termination;
        parts.push(if self.converged {
            format!("converged ({termination})")
        } else if termination == "degenerate" {
            "degenerate: not a usable optimum (see the report's notes)".to_string()
        } else {
            format!("not converged ({termination}): the best point so far")
        });
        parts.join("; ")
    }

    /// The free parameters the data does not determine, in the report's order.
    pub fn undetermined(&self) -> Vec<String> {
        self.params
            .iter()
            .filter(|(_, p)| !p.estimate.determined && !p.fixed)
            .map(|(k, _)| k.clone())
            .collect()
    }
}

impl Estimate {
    /// A value with its standard error, without intervals (non-finite numbers as None).
    fn of(value: f64, stderr: Option<f64>, determined: bool) -> Estimate {
        Estimate {
            value: num(value),
            stderr: stderr.and_then(num),
            determined,
            interval68: None,
            interval95: None,
        }
    }
}

/// The parameter table in the run's unit setting.
fn params_of(r: &FitResult, info: &RunInfo) -> BTreeMap<String, ParamEntry> {
    let units = &info.setting.units;
    r.params
        .iter()
        .map(|p| {
            let entry = ParamEntry {
                estimate: Estimate::of(p.value, p.stderr, p.determined),
                fixed: p.fixed,
                unit: units.of_param(&p.name),
            };
            (p.name.clone(), entry)
        })
        .collect()
}

/// The derived quantities, their units depending on whether the verdict is a smooth
/// surface.
fn derived_of(r: &FitResult, info: &RunInfo) -> BTreeMap<String, DerivedEntry> {
    let units = &info.setting.units;
    let smooth = r.verdict == Verdict::Smooth;
    r.derived
        .iter()
        .map(|d| {
            let entry = DerivedEntry {
                estimate: Estimate::of(d.value, d.stderr, d.determined),
                doc: d.doc.clone(),
                unit: units.of_derived(&d.name, smooth),
            };
            (d.name.clone(), entry)
        })
        .collect()
}

/// Adds the profile intervals to the entries they belong to (a parameter's name first, else
/// a derived quantity's). An interval whose name matches neither table, or whose level was
/// not computed, adds nothing.
fn attach_intervals(
    info: &RunInfo,
    params: &mut BTreeMap<String, ParamEntry>,
    derived: &mut BTreeMap<String, DerivedEntry>,
) {
    for iv in &info.intervals {
        let level = |prob: f64| {
            iv.at(prob)
                .map(|l| [l.lo.value().and_then(num), l.hi.value().and_then(num)])
        };
        let estimate = match params.get_mut(&iv.name) {
            Some(p) => Some(&mut p.estimate),
            None => derived.get_mut(&iv.name).map(|d| &mut d.estimate),
        };
        if let Some(e) = estimate {
            (e.interval68, e.interval95) = (level(LEVELS[0]), level(LEVELS[1]));
        }
    }
}

/// The start point of the fit, parameter name → starting value.
fn start_of(r: &FitResult) -> BTreeMap<String, Option<f64>> {
    r.layout
        .params
        .iter()
        .zip(&r.start)
        .map(|(p, v)| (p.name.clone(), num(*v)))
        .collect()
}

/// The correlation matrix with its names and the most correlated pairs.
fn correlation_of(r: &FitResult) -> Correlation {
    let k = r.corr_names.len();
    Correlation {
        names: r.corr_names.clone(),
        matrix: (0..k)
            .map(|i| (0..k).map(|j| num(r.correlation[(i, j)])).collect())
            .collect(),
        largest: super::text::top_pairs(r, super::text::TOP_PAIRS)
            .into_iter()
            .map(|(a, b, rho)| Pair {
                a,
                b,
                rho: num(rho),
            })
            .collect(),
    }
}

/// The validity checks keyed by name, or None when the fit ran none.
fn validity_of(r: &FitResult) -> Option<BTreeMap<String, ValidityEntry>> {
    r.validity.as_ref().map(|v| {
        v.checks
            .iter()
            .map(|c| {
                let entry = ValidityEntry {
                    satisfied: c.satisfied,
                    value: num(c.value),
                    limit: c.limit,
                    text: c.text.clone(),
                };
                (c.name.to_string(), entry)
            })
            .collect()
    })
}
