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
    /// The minimised cost ½ Σ C²ρ(wᵢrᵢ²/C²) (½χ² for the linear loss) at the reported point.
    pub cost: Option<f64>,
    /// The loss the fit minimised.
    pub loss: LossEntry,
    /// χ² = Σ wᵢrᵢ² at the reported point (null under a robust loss when the fitted values were
    /// not computed).
    pub chi2: Option<f64>,
    /// χ²/(n − p), p the free parameters.
    pub reduced_chi2: Option<f64>,
    /// Root mean square of the unweighted residuals, in the residual kind's space (null when
    /// the fitted values were not computed).
    pub rms: Option<f64>,
    /// Largest |rᵢ| of the unweighted residuals (null when not computed).
    pub max_abs_residual: Option<f64>,
    /// Weighted R² in the residuals' space (null when the data has no spread or the fitted
    /// values were not computed).
    pub r2: Option<f64>,
    /// Akaike's criterion n·ln(χ²/n) + 2p (2·cost for χ² under a robust loss).
    pub aic: Option<f64>,
    /// Bayesian criterion n·ln(χ²/n) + p·ln n (2·cost for χ² under a robust loss).
    pub bic: Option<f64>,
    /// Samples fitted.
    pub n: usize,
    /// Free parameters.
    pub n_free: usize,
    /// Whether the model describes the data, with its tests.
    pub adequacy: AdequacyEntry,
    /// The checks of the paper's assumptions at the fitted surface (KBS models), by name.
    pub validity: Option<BTreeMap<String, ValidityEntry>>,
    /// The free parameters' correlation matrix and its largest entries.
    pub correlation: Correlation,
    /// Singular values of the weighted Jacobian with unit-norm columns, descending (null for a
    /// non-finite one).
    pub singular_values: Vec<Option<f64>>,
    /// Condition number σ_max/σ_min of that Jacobian (null when infinite: singular).
    pub condition: Option<f64>,
    /// The starting point by parameter name, and whether it came from the start search
    /// (`search`) or a neighbouring dataset's optimum (`neighbour`).
    pub start: BTreeMap<String, Option<f64>>,
    /// `search` or `neighbour` (see `start`).
    pub start_from: String,
    /// Levenberg–Marquardt iterations of the fit (a refit's added).
    pub iterations: u64,
    /// Residual evaluations of the solver (a refit's added).
    pub evaluations: u64,
    /// Jacobian evaluations of the solver (a refit's added).
    pub jacobian_evaluations: u64,
    /// Wall-clock seconds of the fit, of its profile intervals, of the start search with
    /// its refinement, and of the grid alone.
    pub seconds: f64,
    /// Seconds of the profile intervals (0 when none were computed).
    pub interval_seconds: f64,
    /// Seconds up to the end of the starting-value refinement (included in `seconds`).
    pub init_seconds: f64,
    /// Seconds up to the grid's candidates (included in `init_seconds`).
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
    /// The fit's setting: input path and checksum, wavelength and units, quantity, residual,
    /// floor, weights, loss.
    pub setting: super::Setting,
    /// The full command line of the run.
    pub command: String,
    /// goniofit's version that wrote the report.
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
    /// The value at the reported point (null if not finite).
    pub value: Option<f64>,
    /// Its standard error; null when not determined, fixed or not finite.
    pub stderr: Option<f64>,
    /// Whether the data determines it (see [`crate::fit::driver::Verdict`]).
    pub determined: bool,
    /// The 68.27 % profile-likelihood interval `[lo, hi]` (a side null when open); absent when
    /// not computed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interval68: Option<[Option<f64>; 2]>,
    /// The 95 % profile-likelihood interval `[lo, hi]` (a side null when open); absent when not
    /// computed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interval95: Option<[Option<f64>; 2]>,
}

/// A fitted parameter: its estimate, whether it was held fixed, and its unit in the run's
/// unit setting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParamEntry {
    /// Value, standard error, determination and intervals (flattened into the entry).
    #[serde(flatten)]
    pub estimate: Estimate,
    /// Whether it was held fixed (`--fix`, or σ of `kbs-rough`) rather than fitted.
    pub fixed: bool,
    /// Its unit in the run's unit setting (`nm`, `unit of λ`, `sr⁻¹`, `1`, `rad`, …).
    pub unit: String,
}

/// A derived quantity: its estimate, its meaning in one line, and its unit (which depends
/// on whether the verdict is a smooth surface).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DerivedEntry {
    /// Value, standard error, determination and intervals (flattened into the entry).
    #[serde(flatten)]
    pub estimate: Estimate,
    /// What the quantity is, in one line.
    pub doc: String,
    /// Its unit in the run's unit setting (the smooth amplitude's carries a length²).
    pub unit: String,
}

/// The robust loss: its kind, its scale C and how many samples lie beyond it (null for
/// the linear loss).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LossEntry {
    /// The loss function ρ (`linear`, `soft_l1`, `huber`, `cauchy`, `arctan`).
    pub kind: LossKind,
    /// The loss scale C in units of the weighted residual √w·r (null for the linear loss).
    pub f_scale: Option<f64>,
    /// Samples with |√wᵢ rᵢ| > C, treated as outliers (null for the linear loss).
    pub beyond_f_scale: Option<usize>,
}

/// The adequacy verdict with its headline in words.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AdequacyEntry {
    /// The verdict, its reasons and the test statistics (flattened into the entry).
    #[serde(flatten)]
    pub adequacy: Adequacy,
    /// The verdict in one sentence, as the text report gives it.
    pub headline: String,
}

/// One validity check.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ValidityEntry {
    /// Whether the fitted surface satisfies it; null when the data does not determine it.
    pub satisfied: Option<bool>,
    /// The checked quantity: R/λ (curvature) or the shadowed fraction 1 − S (shadowing); null
    /// when not finite.
    pub value: Option<f64>,
    /// The limit the value is compared with: a lower bound for the curvature, an upper one for
    /// the shadowing.
    pub limit: f64,
    /// The check in words, with its numbers.
    pub text: String,
}

/// The correlation matrix of the free parameters, with the most correlated pairs (those
/// the text report lists).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Correlation {
    /// Names of the free parameters, in the matrix's order.
    pub names: Vec<String>,
    /// The correlations ρᵢⱼ, row by row (null where a standard error is 0).
    pub matrix: Vec<Vec<Option<f64>>>,
    /// The pairs with the largest |ρ|, largest first (at most ten, finite ones only).
    pub largest: Vec<Pair>,
}

/// Two correlated parameters and their correlation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Pair {
    /// One parameter's name.
    pub a: String,
    /// The other parameter's name.
    pub b: String,
    /// Their correlation ρ ∈ [−1, 1].
    pub rho: Option<f64>,
}

/// What `goniofit plot` and `goniofit design --from` need to rebuild a fit: the fit's
/// settings, the model with its factor options (those of an `auto` choice are not among
/// the settings), and the value of every parameter in layout order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Replay {
    /// What the fit was asked to do (how its file is read, the model, the residual, …).
    pub settings: crate::settings::Settings,
    /// The model's name of the fit (the chosen one for `--model auto`).
    pub model: String,
    /// Its factor options as command-line text, empty without.
    pub factors: String,
    /// Every parameter name in layout order.
    pub names: Vec<String>,
    /// Every parameter value (fixed ones included) in layout order.
    pub values: Vec<f64>,
    /// Number of free parameters of the fit.
    pub n_free: usize,
}

/// One candidate of a model comparison.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ComparisonRow {
    /// The model with its factor options.
    pub model: String,
    /// Bayesian information criterion of the candidate's fit.
    pub bic: Option<f64>,
    /// Akaike's information criterion of the candidate's fit.
    pub aic: Option<f64>,
    /// The candidate's minimised cost.
    pub cost: Option<f64>,
    /// Whether the candidate's fit is a usable optimum.
    pub converged: bool,
    /// The solver's termination of the candidate's fit.
    pub termination: String,
    /// Its BIC minus the chosen fit's.
    pub delta_bic: Option<f64>,
    /// Whether this candidate is the one reported.
    pub chosen: bool,
    /// A usable fit within ΔBIC < 2 of the chosen one.
    pub tie: bool,
}

/// The solver's termination as the report spells it (`ftol`, `degenerate`, …).
pub fn termination_name(t: goniofit_lm::Termination) -> String {
    format!("{t:?}").to_lowercase()
}

/// A finite number, or None.
pub(crate) fn num(v: f64) -> Option<f64> {
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
