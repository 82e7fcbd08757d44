//! Profile-likelihood intervals of a dataset's chosen fit ([`crate::fit::stats::profile`]): every
//! free parameter, the parameters the reduced fit held, and T/σ, Beckmann's α, the
//! amplitudes and the reflectance factors.

use super::DatasetFit;
use crate::error::Result;
use crate::fit::driver::{self, FitInput, FitResult};
use crate::fit::problem::FitProblem;
use crate::fit::stats::profile::{Interval, Profiler, Target};
use goniofit_lm::Stop;

/// Fits with more free parameters than this get no profile intervals (each needs two
/// walks of refits per quantity).
pub(crate) const MAX_PROFILED: usize = 8;

/// Profile-likelihood intervals of every free parameter, of the parameters the reduced
/// fit held, and of T/σ, Beckmann's α, the amplitudes and the reflectance factors, on the
/// full problem at the reported optimum `r` (`uncertainties`: the weights come from a
/// stated `sigma_L`). A quantity whose profile cannot be walked is left out. Every refit
/// shares the fit's `stop` (its time limit and signals): once it fires the walks end, and
/// the caller discards what they found (a walk cut short ends at a wrong likelihood).
///
/// `r`'s fitted values, residuals and standardized residuals are not held while the refits
/// run (on a big fit they and the refits' residuals are the peak of its memory): they are
/// computed again afterwards at `r`'s parameters, on the intervals' problem (the same
/// model, residual kind, floor, weights and loss: the same numbers).
pub(crate) fn profile_intervals(
    spec: &DatasetFit,
    input: &FitInput,
    r: &mut FitResult,
    uncertainties: bool,
    stop: &Stop,
) -> Result<Vec<Interval>> {
    if stop.is_requested() {
        return Ok(Vec::new());
    }
    let again = !r.fitted.is_empty() && !r.residuals.is_empty();
    if again {
        r.fitted = Vec::new();
        r.residuals = Vec::new();
        r.std_residuals = Vec::new();
    }
    let n_free = r.n_free;
    let result: &FitResult = r;
    let (intervals, residuals) = on_problem(
        spec,
        input,
        result,
        uncertainties,
        stop,
        |problem, config| {
            let intervals = intervals_on(problem, result, spec.absolute_sigma, config);
            problem.forget_spare();
            let residuals = again.then(|| {
                let (fitted, _) = problem.values_modes_until(&result.values, None)?;
                let raw = problem.raw_residuals(&fitted);
                let unc = config.weights_are_uncertainties;
                let std = driver::standardized_residuals(problem, &raw, n_free, unc);
                Some((fitted, raw, std))
            });
            (intervals, residuals)
        },
    )?;
    if let Some(Some((fitted, raw, std))) = residuals {
        r.fitted = fitted;
        r.residuals = raw;
        r.std_residuals = std;
    }
    Ok(intervals)
}

/// `f` on the full problem at `r`'s model (the parameters held by the reduced fit free
/// again) with the fit's configuration, sharing `stop`.
fn on_problem<T>(
    spec: &DatasetFit,
    input: &FitInput,
    r: &FitResult,
    uncertainties: bool,
    stop: &Stop,
    f: impl FnOnce(&FitProblem, &driver::FitConfig) -> T,
) -> Result<T> {
    let mut config = spec.config_for(&r.full_model(), uncertainties);
    config.lm.stop = Some(stop.clone());
    let model = crate::model::by_name(&config.model, &config.model_opts)?;
    let mut layout = r.layout.clone();
    // Parameters held by the reduction (reported as not fixed) are profiled too.
    for (fp, p) in layout.params.iter_mut().zip(&r.params) {
        if !p.fixed {
            fp.fixed = None;
        }
    }
    let floor = driver::residual_floor(&config, &input.y);
    let problem = FitProblem::new(model.as_ref(), layout, input, config.residual, floor)?
        .with_loss(config.loss);
    Ok(f(&problem, &config))
}

/// The intervals of every quantity of `r` on `problem`, its full problem.
fn intervals_on(
    problem: &FitProblem,
    r: &FitResult,
    absolute_sigma: bool,
    config: &driver::FitConfig,
) -> Vec<Interval> {
    let stop = config.lm.stop.as_ref().expect("the intervals' stop");
    let prof = Profiler::new(problem, &r.values, absolute_sigma, &config.lm);
    let layout = &problem.layout;
    let mut out = Vec::new();
    for k in layout.free() {
        if stop.is_requested() {
            break;
        }
        if let Some(iv) = prof.interval(&layout.params[k].name, &Target::Param(k)) {
            out.push(iv);
        }
    }
    let first = |n: &str| layout.find(n).first().copied();
    if let (Some(ks), Some(kt)) = (first("sigma"), first("T")) {
        let ratio = Target::Product {
            coef: vec![(kt, 1.0), (ks, -1.0)],
            eliminate: ks,
        };
        if let Some(iv) = prof.interval("T/sigma", &ratio) {
            out.push(iv.mapped("beckmann_alpha", 2.0, true));
            out.push(iv);
        }
        for d in &r.derived {
            if !d.name.starts_with("amplitude") {
                continue;
            }
            let scale = d.name.replacen("amplitude", "scale", 1);
            let Some(ka) = layout.params.iter().position(|p| p.name == scale) else {
                continue;
            };
            let coef = match r.verdict {
                driver::Verdict::Smooth => vec![(ka, 1.0), (ks, 2.0)],
                _ => vec![(ka, 1.0), (kt, 2.0), (ks, -2.0)],
            };
            let target = Target::Product {
                coef,
                eliminate: ks,
            };
            if let Some(iv) = prof.interval(&d.name, &target) {
                out.push(iv);
            }
        }
    }
    for d in &r.derived {
        if let Some(term) = d.doc.strip_prefix("π·").and_then(|t| t.split(',').next()) {
            let src = d.name.replacen("reflectance_factor", term, 1);
            if let Some(iv) = out.iter().find(|i| i.name == src) {
                let m = iv.mapped(&d.name, std::f64::consts::PI, false);
                out.push(m);
            }
        }
    }
    out
}
