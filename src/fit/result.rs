//! What a finished fit reports: parameters with their standard errors and whether the data
//! determines each, derived quantities, the verdict, goodness of fit and residuals
//! ([`FitResult`]). The conventions are in [`super::driver`]'s module doc.

use super::problem::loss::Loss;
use super::problem::{FitProblem, ParamLayout};
use super::solve::Run;
use super::stats::covariance;
use crate::model::Mode;
use goniofit_lm::Termination;
use nalgebra::DMatrix;
use std::collections::BTreeMap;

/// The problem and solver run a report describes (the first solve, or the reduced refit),
/// with its uncertainty, verdict and the notes that explain the verdict.
pub(super) struct Solved<'m> {
    pub problem: FitProblem<'m>,
    pub run: Run,
    pub unc: covariance::Uncertainty,
    pub verdict: Verdict,
    pub notes: Vec<String>,
    /// Why the point is not a usable optimum ([`super::accept::accept`]; also in `notes`).
    pub unusable: Option<String>,
}

/// One fitted parameter.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ParamResult {
    /// Parameter name as the layout spells it, with a `[channel]` suffix for per-channel
    /// parameters (`base_name` strips it).
    pub name: String,
    /// Value at the reported point, in the model's natural units (not transformed).
    pub value: f64,
    /// Standard error; None when fixed or undetermined.
    pub stderr: Option<f64>,
    /// Whether the data determines it: free, not reduced away by a rough or smooth verdict,
    /// outside the Jacobian's null space, with a finite standard error (for a
    /// log-transformed parameter one of ln p at most 1), not at a lower bound, and for a
    /// Fresnel parameter reached by some sample's local incidence angle.
    pub determined: bool,
    /// Whether the value was held fixed (`--fix`, or σ of `kbs-rough`); σ under a rough or
    /// smooth verdict, held for the reduced refit, is reported as not fixed.
    pub fixed: bool,
    /// The model's unit of the parameter (`λ unit`, `1`, `rad`); the reports use the run's unit
    /// setting instead.
    pub unit: String,
}

/// Wall seconds of each stage of one fit, in the order they run (their sum is the fit's
/// `seconds`, to the clock's resolution). Not part of the reports: the
/// timing a benchmark asks for (`GONIOFIT_STAGES`, benches/stages.sh).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageSeconds {
    /// Checks, the full problem and the start grid's candidates (the grid's model side is
    /// computed once per layout, [`super::start::grid_cache`]).
    pub grid: f64,
    /// The quick refinement of the grid's candidates on the subsample.
    pub refine: f64,
    /// Levenberg–Marquardt on the whole data (with rival valleys and probes).
    pub solve: f64,
    /// Covariance, what the data determines, and the reduced refit when it is needed.
    pub uncertainty: f64,
    /// Fitted values, goodness of fit, validity and adequacy of the report.
    pub assemble: f64,
}

/// A quantity derived from the parameters (T/σ, Beckmann's α, determined combinations).
#[derive(Debug, Clone, serde::Serialize)]
pub struct Derived {
    /// Report name (`T/sigma`, `beckmann_alpha`, `amplitude`, `reflectance_factor`, with a
    /// `[channel]` suffix where per channel).
    pub name: String,
    /// Value at the reported point.
    pub value: f64,
    /// Standard error propagated from the covariance; None when not determined or unknown.
    pub stderr: Option<f64>,
    /// Whether the data determines it (under the verdict: T/σ not for a smooth or partial
    /// verdict).
    pub determined: bool,
    /// Its meaning in one line, as the reports print it.
    pub doc: String,
}

/// What the data determines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Verdict {
    /// Every free parameter is determined.
    Full,
    /// Rough regime: only T/σ and the amplitude s·(T/σ)² are determined.
    Rough,
    /// Smooth regime: only T and the amplitude s·σ² are determined.
    Smooth,
    /// Some directions are undetermined and match no known regime.
    Partial,
    /// Not computed: the fit was stopped before the Jacobian at its best point was
    /// evaluated, so there are no standard errors, correlations or verdict.
    #[serde(rename = "not_computed")]
    NotComputed,
}

impl Verdict {
    /// The verdict in the report's words ("rough regime: only T/sigma and the amplitude
    /// are determined").
    pub fn describe(self) -> &'static str {
        match self {
            Verdict::Full => "every free parameter is determined",
            Verdict::Rough => "rough regime: only T/sigma and the amplitude are determined",
            Verdict::Smooth => {
                "smooth regime: only T and the amplitude s*sigma^2 are determined"
            }
            Verdict::Partial => "some parameter combinations are not determined",
            Verdict::NotComputed => {
                "not computed: the fit was stopped before the Jacobian at its best point was evaluated"
            }
        }
    }

    /// Lower-case name, as in JSON (`full`, `rough`, `smooth`, `partial`, `not_computed`).
    pub fn name(self) -> &'static str {
        match self {
            Verdict::Full => "full",
            Verdict::Rough => "rough",
            Verdict::Smooth => "smooth",
            Verdict::Partial => "partial",
            Verdict::NotComputed => "not_computed",
        }
    }

    /// The verdict of a [`Self::name`] (as read back from a JSON report).
    pub fn from_name(name: &str) -> Option<Verdict> {
        [
            Verdict::Full,
            Verdict::Rough,
            Verdict::Smooth,
            Verdict::Partial,
            Verdict::NotComputed,
        ]
        .into_iter()
        .find(|v| v.name() == name)
    }
}

/// A finished fit (converged or not).
#[derive(Debug, Clone)]
pub struct FitResult {
    /// The model's name (`kbs`, `kbs+lambert`, `lambert`, …) without factor options.
    pub model: String,
    /// The model's factor options as command-line text (` --fresnel dielectric`), empty
    /// without factors ([`crate::model::ModelOptions::factors_label`]).
    pub factors: String,
    /// Every parameter of the layout, fixed ones included, in layout order.
    pub params: Vec<ParamResult>,
    /// The quantities derived from the parameters (T/σ, Beckmann's α, amplitudes, reflectance
    /// factors).
    pub derived: Vec<Derived>,
    /// Names and correlation matrix of the free parameters of the reported fit.
    pub corr_names: Vec<String>,
    /// Correlation matrix of the free parameters, in the order of `corr_names` (NaN where a
    /// standard error is 0).
    pub correlation: DMatrix<f64>,
    /// Singular values of the weighted Jacobian with unit-norm columns, descending (one per
    /// free parameter).
    pub singular_values: Vec<f64>,
    /// Condition number σ_max/σ_min of that column-scaled Jacobian (∞ when singular).
    pub condition: f64,
    /// What the data determines, from the Jacobian's null space at the reported point.
    pub verdict: Verdict,
    /// Notes of the fit in words (bounds reached, reduced refits, termination, …) that the
    /// reports print.
    pub notes: Vec<String>,
    /// Why the fit's point is not a usable optimum when it is degenerate (an edge of the
    /// domain, a lobe the sampling does not resolve, a lost rank; also among `notes`).
    pub unusable: Option<String>,
    /// Whether the fitted surface satisfies the paper's assumptions (KBS models; a warning,
    /// not a failure): `super::stats::validity`.
    pub validity: Option<super::stats::validity::Validity>,
    /// Whether the model describes the data and the weights match the noise, from the
    /// residuals (`super::stats::adequacy`; a verdict, not a failure).
    pub adequacy: super::stats::adequacy::Adequacy,
    /// The robust loss the fit minimised (linear: plain least squares).
    pub loss: Loss,
    /// Under a robust loss, how many samples have a weighted residual beyond `f_scale`
    /// (|√w r| > C: treated as outliers); None for linear.
    pub beyond_f_scale: Option<usize>,
    /// The minimised cost ½ Σ C²ρ(wᵢrᵢ²/C²) (½ Σ wᵢrᵢ² = ½χ² for the linear loss).
    pub cost: f64,
    /// χ² = Σ wᵢ rᵢ² over the samples at the reported point (2 × cost for the linear loss); NaN
    /// under a robust loss when a stop cut the fitted values.
    pub chi2: f64,
    /// χ²/(n − p), p the free parameters (n − p floored at 1); near 1 when the weights are the
    /// inverse noise variances and the model fits.
    pub reduced_chi2: f64,
    /// Root mean square of the unweighted residuals rᵢ, in the residual kind's space (data
    /// units, relative, or ln units); NaN when the fitted values were not computed.
    pub rms: f64,
    /// Largest |rᵢ| of the unweighted residuals; NaN when the fitted values were not computed.
    pub max_abs_residual: f64,
    /// Weighted R² in the residuals' space (of ln y for log residuals); NaN when the data has
    /// no spread or the fitted values were not computed.
    pub r2: f64,
    /// Akaike's criterion n·ln(χ²/n) + 2p (2·cost in place of χ² under a robust loss); only
    /// differences between fits of the same data mean something.
    pub aic: f64,
    /// Bayesian criterion n·ln(χ²/n) + p·ln n (2·cost in place of χ² under a robust loss); the
    /// model comparison ranks candidates by it.
    pub bic: f64,
    /// Number of samples fitted.
    pub n: usize,
    /// Number of free (not fixed) parameters p.
    pub n_free: usize,
    /// Levenberg–Marquardt iterations, those of an earlier solve added for a refit.
    pub iterations: u64,
    /// Residual evaluations of the solver, those of an earlier solve added for a refit.
    pub evaluations: u64,
    /// Jacobian evaluations of the solver, those of an earlier solve added for a refit.
    pub jacobian_evaluations: u64,
    /// Why the solver stopped.
    pub termination: Termination,
    /// Wall time of the whole fit: starting values, refinement, LM, uncertainty and verdict,
    /// the fitted values and the adequacy tests (not the profile intervals, which
    /// `crate::fit::dataset` times apart).
    pub seconds: f64,
    /// Of which: up to the end of the starting-value refinement.
    pub init_seconds: f64,
    /// Of which: up to the grid's candidates (the automatic starting values, before any
    /// LM iteration).
    pub start_seconds: f64,
    /// The wall time of each stage of the fit (`StageSeconds`).
    pub stage_seconds: StageSeconds,
    /// Number of samples per evaluation mode of the model (`series`, `rough`, …), keyed by the
    /// mode's name; empty when the fitted values were not computed.
    pub modes: BTreeMap<String, usize>,
    /// Range of g = (2πσ/λ)²(cos θi + cos θr)² over the samples (KBS models).
    pub g_range: Option<(f64, f64)>,
    /// Whether the fitted values, residuals and evaluation modes of every sample were
    /// computed at the reported point: false when a stop request cut their evaluation after
    /// the solve (then those vectors and `modes` are empty, rms, max |residual| and R² are
    /// NaN, a note says so, and the command exits 3 without a residuals file or pictures).
    pub fitted_computed: bool,
    /// Model value fᵢ of every sample at the reported point (empty when not computed).
    pub fitted: Vec<f64>,
    /// Unweighted residual rᵢ of every sample by the residual kind: f − y, (f − y)/max(|y|,
    /// floor) or ln max(f, floor) − ln max(y, floor) (empty when not computed).
    pub residuals: Vec<f64>,
    /// Standardized residual √wᵢ rᵢ of every sample, divided by s = √(χ²/(n − p)) unless the
    /// weights are uncertainties (by the robust s under a robust loss).
    pub std_residuals: Vec<f64>,
    /// The evaluation mode of the model at every sample (empty when not computed).
    pub sample_modes: Vec<Mode>,
    /// The parameter layout of the reported fit: names, transforms, channels and fixed values
    /// (for plotting per channel).
    pub layout: ParamLayout,
    /// The value of every parameter in layout order, fixed ones included: the reported point.
    pub values: Vec<f64>,
    /// The grid point (layout order) whose quick refinement won, before any LM iteration;
    /// for a fit started at a neighbour's optimum, that optimum.
    pub start: Vec<f64>,
    /// Whether the fit started at a neighbouring dataset's optimum (`--warm-start`) instead
    /// of the start search, and was kept as the fit (see `crate::fit::dataset`).
    pub started_near: bool,
}

/// A fit's per-sample vectors, moved out of a [`FitResult`] and back.
pub struct SampleVectors {
    fitted: Vec<f64>,
    residuals: Vec<f64>,
    std_residuals: Vec<f64>,
    sample_modes: Vec<Mode>,
}

/// A parameter's name without its `[channel]` suffix.
pub(crate) fn base_name(name: &str) -> &str {
    name.split('[').next().unwrap_or(name)
}

impl FitResult {
    /// For a BRDF (`quantity`), the reflectance factor π·s of every Lambertian term
    /// (`scale` of `lambert` and `lambert-specular`, `scale_d` of `kbs+lambert`, per
    /// channel), added to the derived quantities with the standard error scaled alike. A
    /// radiance has no reflectance factor without the irradiance, so nothing is added then.
    pub fn add_reflectance_factors(&mut self, quantity: crate::geometry::Quantity) {
        if quantity != crate::geometry::Quantity::Brdf {
            return;
        }
        let lambert_term = match self.model.as_str() {
            "lambert" | "lambert-specular" => "scale",
            "kbs+lambert" => "scale_d",
            _ => return,
        };
        let pi = std::f64::consts::PI;
        let added: Vec<Derived> = self
            .params
            .iter()
            .filter(|p| base_name(&p.name) == lambert_term)
            .map(|p| Derived {
                name: p.name.replacen(lambert_term, "reflectance_factor", 1),
                value: pi * p.value,
                stderr: p.stderr.map(|s| pi * s),
                determined: p.determined || p.fixed,
                doc: format!("π·{lambert_term}, the Lambertian term as a reflectance factor"),
            })
            .collect();
        self.derived.extend(added);
    }

    /// Standard errors from the stated uncertainties as they are (scipy's
    /// `curve_fit(absolute_sigma=True)`): the fit's covariance s²(JᵀJ)⁺ with
    /// s² = 2·cost/(n − p) (the reduced χ² for the linear loss) becomes (JᵀJ)⁺, so every
    /// standard error is divided by s. Correlations do not change.
    pub fn use_absolute_sigma(&mut self) {
        let dof = self.n.saturating_sub(self.n_free).max(1) as f64;
        let s = (2.0 * self.cost / dof).sqrt();
        if !(s.is_finite() && s > 0.0) {
            return;
        }
        for p in &mut self.params {
            p.stderr = p.stderr.map(|e| e / s);
        }
        for d in &mut self.derived {
            d.stderr = d.stderr.map(|e| e / s);
        }
    }

    /// The model's name with its factor options (`kbs+lambert --fresnel dielectric
    /// --shadowing smith`): what tells two candidates of one model apart.
    pub fn full_model(&self) -> String {
        format!("{}{}", self.model, self.factors)
    }

    /// Moves out the per-sample vectors (fitted values, residuals, standardised residuals,
    /// modes), leaving them empty: a candidate of a model comparison keeps only its summary,
    /// and a copy of the summary costs nothing per sample.
    pub fn take_samples(&mut self) -> SampleVectors {
        SampleVectors {
            fitted: std::mem::take(&mut self.fitted),
            residuals: std::mem::take(&mut self.residuals),
            std_residuals: std::mem::take(&mut self.std_residuals),
            sample_modes: std::mem::take(&mut self.sample_modes),
        }
    }

    /// Puts back what [`Self::take_samples`] moved out.
    pub fn put_samples(&mut self, s: SampleVectors) {
        self.fitted = s.fitted;
        self.residuals = s.residuals;
        self.std_residuals = s.std_residuals;
        self.sample_modes = s.sample_modes;
    }

    /// Whether the fit is a usable optimum: the solver met a convergence criterion and the
    /// cost, every parameter, standard error and correlation is a finite number (R² may be
    /// undefined, NaN, only for data without spread).
    pub fn converged(&self) -> bool {
        self.termination.converged() && self.is_finite()
    }

    /// Whether the cost, parameters, standard errors and correlations are finite numbers (a
    /// correlation is NaN by design where a standard error is 0: an exact fit).
    pub fn is_finite(&self) -> bool {
        self.cost.is_finite()
            && !self.r2.is_infinite()
            && self.values.iter().all(|v| v.is_finite())
            && self
                .params
                .iter()
                .all(|p| p.value.is_finite() && p.stderr.is_none_or(f64::is_finite))
            && self.correlation.iter().all(|c| !c.is_infinite())
    }

    /// Value of a parameter by (base) name, first channel.
    pub fn value(&self, name: &str) -> Option<f64> {
        self.layout.find(name).first().map(|&k| self.values[k])
    }
}
