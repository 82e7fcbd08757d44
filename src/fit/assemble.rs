//! Assemble: the report value of a finished fit — goodness of fit, parameters with their
//! standard errors and whether each is determined, derived quantities, evaluation modes.
//! The conventions (cost, χ², covariance, AIC/BIC) are in [`super::driver`]'s module doc.

use super::accept::{lower_bound_note, termination_note};
use super::config::FitConfig;
use super::identify::{log_covariance, DETERMINED_MAX_LOG_SE};
use super::problem::edges::at_lower_bound;
use super::problem::{FitInput, FitProblem, ParamLayout, ResidualKind};
use super::result::{Derived, FitResult, ParamResult, Solved, StageSeconds, Verdict};
use super::start::Start;
use super::stats::adequacy::{self, Adequacy};
use super::stats::covariance;
use super::stats::validity;
use crate::model::{Model, ParamSpec};
use nalgebra::DMatrix;
use std::collections::BTreeMap;

/// Residuals and the goodness-of-fit figures at the reported point.
struct Goodness {
    fitted: Vec<f64>,
    residuals: Vec<f64>,
    /// The fit cost ½ Σ C²ρ(wᵢrᵢ²/C²) (½χ² for the linear loss).
    cost: f64,
    /// Samples with |√wᵢ rᵢ| > C under a robust loss.
    beyond_f_scale: Option<usize>,
    chi2: f64,
    rms: f64,
    max_abs_residual: f64,
    r2: f64,
    aic: f64,
    bic: f64,
}

/// The report of a finished fit (`seconds`: its wall time).
pub(super) fn assemble(
    model: &dyn Model,
    input: &FitInput,
    config: &FitConfig,
    solved: Solved,
    seconds: f64,
    start: Start,
) -> FitResult {
    let Solved {
        problem,
        run,
        unc,
        verdict,
        mut notes,
        unusable,
    } = solved;
    let layout = &problem.layout;
    let specs = model.params();
    let n = problem.len();
    let free = layout.free();
    let p = &run.values;
    let n_free = free.len();
    let dof = (n - n_free).max(1) as f64;
    let (gof, sample_modes, fitted_computed) =
        fitted_at_point(&problem, input, &run.lm, p, config, &mut notes);
    let params = param_results(layout, specs, p, (&unc, verdict), &input.geo, &mut notes);
    let derived = derived_quantities(layout, specs, p, &unc, verdict);
    notes.extend(termination_note(run.lm.termination));
    let result = FitResult {
        model: model.name().to_string(),
        factors: factors_label(model),
        params,
        derived,
        corr_names: free
            .iter()
            .map(|&k| layout.params[k].name.clone())
            .collect(),
        correlation: unc.correlation.clone(),
        singular_values: unc.singular_values.iter().copied().collect(),
        condition: unc.condition,
        verdict,
        notes,
        unusable,
        validity: None,
        adequacy: Adequacy::not_computed(gof.r2),
        loss: problem.loss(),
        beyond_f_scale: gof.beyond_f_scale,
        cost: gof.cost,
        chi2: gof.chi2,
        reduced_chi2: gof.chi2 / dof,
        rms: gof.rms,
        max_abs_residual: gof.max_abs_residual,
        r2: gof.r2,
        aic: gof.aic,
        bic: gof.bic,
        n,
        n_free,
        iterations: run.lm.iterations,
        evaluations: run.lm.evaluations,
        jacobian_evaluations: run.lm.jacobian_evaluations,
        termination: run.lm.termination,
        seconds,
        init_seconds: start.init_seconds,
        start_seconds: start.start_seconds,
        stage_seconds: StageSeconds::default(),
        modes: mode_counts(&sample_modes),
        g_range: g_range(layout, input, p),
        fitted_computed,
        fitted: gof.fitted,
        residuals: gof.residuals,
        // Computed after the adequacy tests (see `checked`).
        std_residuals: Vec::new(),
        sample_modes,
        layout: layout.clone(),
        values: p.clone(),
        start: start.grid_start,
        started_near: false,
    };
    checked(result, &problem, input, config)
}

/// How many samples each evaluation mode served, keyed by the mode's name.
fn mode_counts(sample_modes: &[crate::model::Mode]) -> BTreeMap<String, usize> {
    let mut counts: BTreeMap<&'static str, usize> = BTreeMap::new();
    for m in sample_modes {
        *counts.entry(m.name()).or_insert(0) += 1;
    }
    counts
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
}

/// The model's factor flags as the report prints them (empty for a model without options).
fn factors_label(model: &dyn Model) -> String {
    model
        .options()
        .map(|o| o.factors_label())
        .unwrap_or_default()
}

/// `result` with its validity checks, adequacy tests and standardized residuals filled in,
/// and a note when a
/// reported number is not finite (the result is then not a usable optimum).
fn checked(
    mut result: FitResult,
    problem: &FitProblem,
    input: &FitInput,
    config: &FitConfig,
) -> FitResult {
    result.validity = validity_of(&result, input);
    result.adequacy = adequacy_of(&result, problem, input, config);
    // After the tests, whose temporaries are the peak of a big fit's memory.
    result.std_residuals = standardized_residuals(
        problem,
        &result.residuals,
        result.n_free,
        config.weights_are_uncertainties,
    );
    if !result.is_finite() {
        result.notes.push(
            "not a usable optimum: the cost, a parameter, a standard error or a correlation is not a finite number (the values overflow double precision; rescale L or the weights)".into(),
        );
    }
    result
}

/// The fitted values, goodness of fit and per-sample evaluation modes at the reported point
/// `p` (`lm`: the solve that reached it), and whether they were computed: a stop request
/// cuts them between blocks of samples when the solver's evaluations were slow
/// ([`quick`]); cut, the figures the solver's cost gives stand ([`from_cost`]), without
/// fitted values, residuals or modes, and `notes` says what was not computed.
fn fitted_at_point(
    problem: &FitProblem,
    input: &FitInput,
    lm: &goniofit_lm::LmReport,
    p: &[f64],
    config: &FitConfig,
    notes: &mut Vec<String>,
) -> (Goodness, Vec<crate::model::Mode>, bool) {
    let stop = config.lm.stop.as_ref().filter(|_| !quick(lm));
    let n_free = problem.layout.free().len();
    match problem.values_modes_until(p, stop) {
        Some((fitted, modes)) => (goodness(problem, input, fitted, n_free), modes, true),
        None => {
            notes.push(FITTED_NOT_COMPUTED.to_string());
            (from_cost(problem, lm.cost, n_free), Vec::new(), false)
        }
    }
}

/// The note of a fit whose stop request cut the evaluation of its fitted values at the
/// reported point (after the solve; a fit whose evaluations are slower than
/// [`QUICK_EVALUATION_SECONDS`] checks the stop between blocks of samples there).
pub(super) const FITTED_NOT_COMPUTED: &str = "the fit was stopped before its fitted values at the reported point were evaluated on the whole data: the cost is the solver's at that point, and the rms and max |residual|, R² (and χ² under a robust loss) were not computed, nor the residuals file and pictures";

/// The mean seconds of one of the solver's evaluations at most which the fitted values and
/// modes at the reported point are evaluated to the end after a stop request too (they cost
/// about one evaluation: a quick fit stopped keeps its residuals file and pictures).
pub(super) const QUICK_EVALUATION_SECONDS: f64 = 0.25;

/// Whether the solver's evaluations took at most [`QUICK_EVALUATION_SECONDS`] each.
fn quick(lm: &goniofit_lm::LmReport) -> bool {
    lm.seconds <= QUICK_EVALUATION_SECONDS * lm.evaluations.max(1) as f64
}

/// The figures that the solver's cost at the reported point gives without the fitted
/// values (see [`FITTED_NOT_COMPUTED`]): χ² = 2·cost under the linear loss, AIC and BIC
/// from the objective 2·cost; rms, max |residual| and R² NaN (never printed as numbers).
fn from_cost(problem: &FitProblem, cost: f64, n_free: usize) -> Goodness {
    let (aic, bic) = information_criteria(2.0 * cost, problem.len() as f64, n_free);
    let linear = problem.loss().is_linear();
    Goodness {
        fitted: Vec::new(),
        residuals: Vec::new(),
        cost,
        beyond_f_scale: None,
        chi2: if linear { 2.0 * cost } else { f64::NAN },
        rms: f64::NAN,
        max_abs_residual: f64::NAN,
        r2: f64::NAN,
        aic,
        bic,
    }
}

/// (AIC, BIC) of a fit with `n_free` parameters on `nf` samples from its objective (χ², or
/// 2·cost under a robust loss; floored at the smallest positive number so that a perfect
/// fit gives finite values).
fn information_criteria(objective: f64, nf: f64, n_free: usize) -> (f64, f64) {
    let log_mean = (objective.max(f64::MIN_POSITIVE) / nf).ln();
    (
        nf * log_mean + 2.0 * n_free as f64,
        nf * log_mean + n_free as f64 * nf.ln(),
    )
}

/// Residuals, cost, χ², rms, R², AIC and BIC of the model values `fitted`. Under a robust loss
/// AIC/BIC (and the standardized residuals, [`standardized_residuals`]) use the robust objective 2·cost = Σ C²ρ in place of
/// χ² (the quantity the fit minimised, and the s² of its covariance), so that a few outliers
/// neither inflate s nor decide a model comparison.
fn goodness(problem: &FitProblem, input: &FitInput, fitted: Vec<f64>, n_free: usize) -> Goodness {
    let n = problem.len();
    let residuals = problem.raw_residuals(&fitted);
    let sw = problem.sqrt_weight();
    let chi2: f64 = residuals
        .iter()
        .zip(sw.iter())
        .map(|(r, s)| (r * s).powi(2))
        .sum();
    let linear = problem.loss().is_linear();
    let cost = if linear {
        0.5 * chi2
    } else {
        problem.cost_of(&residuals)
    };
    // The objective in place of χ²: χ² itself for the linear loss.
    let objective = if linear { chi2 } else { 2.0 * cost };
    let c = problem.loss().f_scale;
    let beyond_f_scale = (!linear).then(|| {
        residuals
            .iter()
            .zip(sw.iter())
            .filter(|(r, s)| (*r * *s).abs() > c)
            .count()
    });
    let rms = (residuals.iter().map(|r| r * r).sum::<f64>() / n as f64).sqrt();
    let max_abs_residual = residuals.iter().fold(0.0f64, |m, r| m.max(r.abs()));
    let r2 = r_squared(problem, input, &fitted);
    let (aic, bic) = information_criteria(objective, n as f64, n_free);
    Goodness {
        fitted,
        residuals,
        cost,
        beyond_f_scale,
        chi2,
        rms,
        max_abs_residual,
        r2,
        aic,
        bic,
    }
}

/// Weighted R² in the space the residuals live in: the data itself, or ln y for log
/// residuals. NaN when the data has no spread.
fn r_squared(problem: &FitProblem, input: &FitInput, fitted: &[f64]) -> f64 {
    use adequacy::distributions::r_squared;
    let sw = |i: usize| problem.sqrt_weight()[i];
    let n = fitted.len();
    match problem.kind() {
        ResidualKind::Log => {
            let ln = |v: &f64| v.max(problem.floor).ln();
            let t: Vec<f64> = input.y.iter().map(ln).collect();
            let f: Vec<f64> = fitted.iter().map(ln).collect();
            r_squared(n, |i| t[i], |i| f[i], sw)
        }
        _ => r_squared(n, |i| input.y[i], |i| fitted[i], sw),
    }
}

/// The adequacy tests on the residuals at the reported point (not computed when a stop
/// cut them).
fn adequacy_of(
    r: &FitResult,
    problem: &FitProblem,
    input: &FitInput,
    config: &FitConfig,
) -> Adequacy {
    if !r.fitted_computed {
        return Adequacy::not_computed(r.r2);
    }
    adequacy::assess(&adequacy::FitResiduals {
        residuals: &r.residuals,
        sqrt_weight: problem.sqrt_weight(),
        fitted: &r.fitted,
        geo: &input.geo,
        channel: &input.channel,
        kind: problem.kind(),
        absolute_weights: config.weights_are_uncertainties,
        linear_loss: problem.loss().is_linear(),
        has_diffuse: r.model.contains("lambert"),
        n_free: r.n_free,
        chi2: r.chi2,
        r2: r.r2,
    })
}

/// Local incidence angle (degrees) below which every sample of a fit lies for its Fresnel
/// parameters to count as not determined: there a dielectric's R(θ_loc)/R(0) stays within
/// a factor ~2 of 1, so the index is read from the curvature of a nearly flat factor and
/// trades against the lobe's shape.
const FRESNEL_MIN_LOCAL_DEG: f64 = 60.0;

/// Marks the Fresnel parameters (`n`, `kappa`) not determined, with a note, when no sample
/// reaches θ_loc = [`FRESNEL_MIN_LOCAL_DEG`] (cos θ_loc = √((1 + ŝ·k̂₂)/2)).
fn fresnel_reach(
    params: &mut [ParamResult],
    geo: &crate::geometry::Geometry,
    notes: &mut Vec<String>,
) {
    let largest = (0..geo.len())
        .map(|i| crate::geometry::cos_local(geo.h(i)).acos().to_degrees())
        .fold(0.0f64, f64::max);
    if largest >= FRESNEL_MIN_LOCAL_DEG {
        return;
    }
    for p in params
        .iter_mut()
        .filter(|p| (p.name == "n" || p.name == "kappa") && p.determined)
    {
        p.determined = false;
        p.stderr = None;
        notes.push(format!(
            "{} is not determined: no sample beyond θ_loc = {FRESNEL_MIN_LOCAL_DEG:.0}° (the largest local incidence angle is {largest:.1}°), where the Fresnel factor depends on the index",
            p.name
        ));
    }
}

/// Every layout parameter with its standard error (delta method through the transform)
/// and whether the data determines it: free, not reduced away by the verdict, outside the
/// Jacobian's null space, a log standard error at most [`DETERMINED_MAX_LOG_SE`], not at a
/// lower bound, and for the Fresnel index one sample at least reaching the local incidence
/// angle where it matters ([`fresnel_reach`]). A note is added for each parameter at its
/// lower bound or out of reach.
fn param_results(
    layout: &ParamLayout,
    specs: &[ParamSpec],
    p: &[f64],
    (unc, verdict): (&covariance::Uncertainty, Verdict),
    geo: &crate::geometry::Geometry,
    notes: &mut Vec<String>,
) -> Vec<ParamResult> {
    let free = layout.free();
    let log_se = |k: usize| -> Option<f64> {
        let i = free.iter().position(|&f| f == k)?;
        let v = unc.covariance[(i, i)];
        (v.is_finite() && v >= 0.0).then(|| v.sqrt())
    };
    let in_null = |k: usize| -> bool {
        free.iter()
            .position(|&f| f == k)
            .is_some_and(|i| unc.undetermined.iter().any(|v| v[i].abs() > 0.1 * v.norm()))
    };
    let sigma_held = verdict != Verdict::Full && verdict != Verdict::Partial;
    let mut params = Vec::new();
    for (k, fp) in layout.params.iter().enumerate() {
        let spec = &specs[fp.spec];
        let reduced_away = sigma_held
            && (spec.name == "sigma"
                || spec.name == "scale"
                || (verdict == Verdict::Rough && spec.name == "T"));
        let se = log_se(k).map(|s| s * fp.transform.dp_dx(fp.transform.to_x(p[k])).abs());
        // The relative standard error (that of ln p: x's for the log transform).
        let loose = se.is_some_and(|s| fp.transform.is_log() && s / p[k] > DETERMINED_MAX_LOG_SE);
        let at_bound = at_lower_bound(fp, p[k], se);
        if at_bound {
            notes.push(lower_bound_note(fp));
        }
        let determined = fp.fixed.is_none()
            && !reduced_away
            && !in_null(k)
            && !loose
            && !at_bound
            && se.is_some();
        params.push(ParamResult {
            name: fp.name.clone(),
            value: p[k],
            stderr: if determined { se } else { None },
            determined,
            fixed: fp.fixed.is_some() && !(sigma_held && spec.name == "sigma"),
            unit: spec.unit.to_string(),
        });
    }
    fresnel_reach(&mut params, geo, notes);
    params
}

/// Value and standard error of Π p_k^{c_k} over (layout index k, exponent c_k), from the
/// log-space covariance of the free parameters: var ln value = cᵀ Σ c (fixed parameters
/// contribute no variance). The error is None when that variance is not finite.
fn log_combination(
    free: &[usize],
    log_cov: &DMatrix<f64>,
    p: &[f64],
    coef: &[(usize, f64)],
) -> (f64, Option<f64>) {
    let value = coef.iter().map(|&(k, c)| p[k].powf(c)).product::<f64>();
    let mut var = 0.0;
    for &(k1, c1) in coef {
        for &(k2, c2) in coef {
            let (Some(i1), Some(i2)) = (
                free.iter().position(|&f| f == k1),
                free.iter().position(|&f| f == k2),
            ) else {
                continue;
            };
            var += c1 * c2 * log_cov[(i1, i2)];
        }
    }
    let se = (var.is_finite() && var >= 0.0).then(|| var.sqrt() * value);
    (value, se)
}

/// The derived quantities of KBS fits: T/σ and Beckmann's α = 2σ/T (determined unless the
/// verdict is smooth or partial), and per channel the amplitude the regime determines.
fn derived_quantities(
    layout: &ParamLayout,
    specs: &[ParamSpec],
    p: &[f64],
    unc: &covariance::Uncertainty,
    verdict: Verdict,
) -> Vec<Derived> {
    let free = layout.free();
    let log_cov = log_covariance(layout, unc, p);
    let combo = |coef: &[(usize, f64)]| log_combination(&free, &log_cov, p, coef);
    let first = |name: &str| layout.find(name).first().copied();
    let mut derived = Vec::new();
    let (Some(ks), Some(kt)) = (first("sigma"), first("T")) else {
        return derived;
    };
    let (ratio, ratio_se) = combo(&[(kt, 1.0), (ks, -1.0)]);
    let ratio_ok = verdict != Verdict::Smooth && verdict != Verdict::Partial;
    derived.push(Derived {
        name: "T/sigma".into(),
        value: ratio,
        stderr: ratio_ok.then_some(ratio_se).flatten(),
        determined: ratio_ok,
        doc: "correlation length over rms height".into(),
    });
    let (slope, slope_se) = combo(&[(ks, 1.0), (kt, -1.0)]);
    derived.push(Derived {
        name: "beckmann_alpha".into(),
        value: 2.0 * slope,
        stderr: ratio_ok.then_some(slope_se.map(|s| 2.0 * s)).flatten(),
        determined: ratio_ok,
        doc: "Beckmann's α = 2σ/T, the surface's rms slope".into(),
    });
    let scale_spec = specs.iter().position(|s| s.name == "scale").unwrap_or(0);
    for (c, ch) in layout.index.iter().enumerate() {
        let ka = ch[scale_spec];
        let suffix = if layout.channel_names.len() > 1 {
            format!("[{}]", layout.channel_names[c])
        } else {
            String::new()
        };
        let (coef, doc) = match verdict {
            Verdict::Rough => (
                [(ka, 1.0), (kt, 2.0), (ks, -2.0)].to_vec(),
                "s·(T/σ)², the rough-regime lobe amplitude",
            ),
            Verdict::Smooth => (
                [(ka, 1.0), (ks, 2.0)].to_vec(),
                "s·σ², the smooth-regime lobe amplitude (σ in the unit of λ)",
            ),
            _ => continue,
        };
        let (value, stderr) = combo(&coef);
        derived.push(Derived {
            name: format!("amplitude{suffix}"),
            value,
            stderr,
            determined: true,
            doc: doc.into(),
        });
    }
    derived
}

/// The validity checks of a KBS fit at its σ and T (None for other models).
fn validity_of(r: &FitResult, input: &FitInput) -> Option<validity::Validity> {
    let param = |name: &str| r.params.iter().find(|p| p.name == name);
    let (sigma, corr) = (param("sigma")?, param("T")?);
    let ratio = r.derived.iter().find(|d| d.name == "T/sigma")?;
    let surface = validity::Surface {
        sigma: sigma.value,
        corr_len: corr.value,
        ratio_determined: ratio.determined,
        both_determined: (sigma.determined || sigma.fixed) && (corr.determined || corr.fixed),
        wavelength: input.geo.wavelength.median(),
        shadowing_modelled: r.factors.contains("--shadowing"),
    };
    Some(validity::check(
        &surface,
        &input.geo.theta_i,
        &input.geo.theta_r,
    ))
}

/// Range of g over the samples at the fitted σ (KBS models).
fn g_range(layout: &ParamLayout, input: &FitInput, p: &[f64]) -> Option<(f64, f64)> {
    let ks = layout.find("sigma").first().copied()?;
    Some(
        (0..input.geo.len())
            .map(|i| input.geo.g(i, p[ks]))
            .fold((f64::INFINITY, 0.0f64), |(lo, hi), g| {
                (lo.min(g), hi.max(g))
            }),
    )
}

/// Standardized residuals √wᵢ rᵢ / s of `problem`'s raw `residuals` at a fit with `n_free`
/// free parameters: s² = χ²/(n − p), under a robust loss the robust objective 2·cost/(n − p)
/// (the s² of the covariance, so that a few outliers do not shrink every other residual);
/// √wᵢ rᵢ when the weights are inverse variances from stated uncertainties (or s = 0).
pub(crate) fn standardized_residuals(
    problem: &FitProblem,
    residuals: &[f64],
    n_free: usize,
    weights_are_uncertainties: bool,
) -> Vec<f64> {
    let sqrt_w = problem.sqrt_weight();
    let objective = if problem.loss().is_linear() {
        residuals
            .iter()
            .zip(sqrt_w.iter())
            .map(|(r, s)| (r * s).powi(2))
            .sum()
    } else {
        2.0 * problem.cost_of(residuals)
    };
    let dof = residuals.len().saturating_sub(n_free).max(1) as f64;
    let s_hat = (objective / dof).sqrt();
    let scale = if weights_are_uncertainties || s_hat == 0.0 {
        1.0
    } else {
        1.0 / s_hat
    };
    residuals
        .iter()
        .zip(sqrt_w.iter())
        .map(|(r, s)| r * s * scale)
        .collect()
}
