//! A whole fit: starting values, Levenberg–Marquardt, uncertainties, and the verdict on
//! what the data determines — with the reduced refit when it determines only combinations.
//!
//! Conventions written into every report:
//! - cost = ½ Σ wᵢ rᵢ² (the solver's), χ² = Σ wᵢ rᵢ², reduced χ² = χ²/(n − p);
//! - covariance = s² (JᵀJ)⁺ with s² = χ²/(n − p) (scaled by the residual variance, as
//!   lmfit's default and scipy's `curve_fit(absolute_sigma=False)`);
//! - AIC = n ln(χ²/n) + 2p, BIC = n ln(χ²/n) + p ln n (lmfit's definitions);
//! - a parameter is *determined* when its direction is not in the numerical null space of
//!   the Jacobian and its standard error in ln p is at most [`DETERMINED_MAX_LOG_SE`]
//!   (the data pins it within a factor e at one standard error).

pub(crate) use super::assemble::standardized_residuals;
pub(crate) use super::config::residual_floor;
pub use super::config::FitConfig;
use super::prepare::{prepare, rough_by_construction};
use super::problem::edges::at_kbs_edge;
pub use super::problem::FitInput;
use super::problem::FitProblem;
use super::problem::ParamLayout;
#[cfg(test)]
pub(crate) use super::result::Derived;
pub(crate) use super::result::{base_name, StageSeconds};
pub use super::result::{FitResult, ParamResult, Verdict};
use super::{accept, assemble, identify, reduce, solve, start};
use crate::error::{Error, Result};
use crate::model::{self, EvalMode, Model};
use goniofit_lm::Stop;
use std::time::Instant;

/// Run a fit.
pub(crate) fn fit(input: &FitInput, config: &FitConfig) -> Result<FitResult> {
    let model = model::by_name(&config.model, &config.model_opts)?;
    fit_model(model.as_ref(), input, config)
}

/// Run a fit with a built model: prepare (the layout; unfittable data refused) → start
/// search → solve → identify → reduce → accept → assemble.
pub fn fit_model(model: &dyn Model, input: &FitInput, config: &FitConfig) -> Result<FitResult> {
    let t0 = Instant::now();
    let config = &with_stop(config);
    let (layout, given) = prepare(model, input, config)?;
    let floor = residual_floor(config, &input.y);
    // The full problem is built while the starting values are searched for on subsamples.
    let (problem, start) = rayon::join(
        || {
            FitProblem::new(model, layout.clone(), input, config.residual, floor)
                .map(|p| p.with_loss(config.loss))
        },
        || start::starting_point(model, &layout, input, config, floor, &given, t0),
    );
    finish(model, input, config, (problem?, start?), t0)
}

/// A fit started at the optimum of a neighbouring dataset's fit `near` of the same model
/// (a texel beside this one): no start search, the solve on the whole data from `near`'s
/// values (every parameter by name; `--fix` values held). None when `near` does not name
/// every parameter of this fit or its point lies outside the model's domain on this data.
/// The caller judges the result against a searched fit ([`crate::fit::dataset`]'s warm
/// start): a start is only as good as the valley it lies in.
pub(crate) fn fit_near(
    input: &FitInput,
    config: &FitConfig,
    near: &FitResult,
) -> Result<Option<FitResult>> {
    let t0 = Instant::now();
    let model = model::by_name(&config.model, &config.model_opts)?;
    let model = model.as_ref();
    let config = &with_stop(config);
    let (layout, _) = prepare(model, input, config)?;
    let Some(p0) = near_point(&layout, near) else {
        return Ok(None);
    };
    if !input.in_domain(model, &layout, &p0) {
        return Ok(None);
    }
    let floor = residual_floor(config, &input.y);
    let problem =
        FitProblem::new(model, layout, input, config.residual, floor)?.with_loss(config.loss);
    let start = start::Start::given(p0, t0);
    let mut result = finish(model, input, config, (problem, start), t0)?;
    result.started_near = true;
    Ok(Some(result))
}

/// `near`'s values in `layout`'s order, matched by parameter name (a held parameter keeps
/// its held value); None when a parameter of `layout` is not among `near`'s.
fn near_point(layout: &ParamLayout, near: &FitResult) -> Option<Vec<f64>> {
    layout
        .params
        .iter()
        .map(|fp| {
            fp.fixed.or_else(|| {
                let k = near.layout.params.iter().position(|q| q.name == fp.name)?;
                near.values.get(k).copied().filter(|v| v.is_finite())
            })
        })
        .collect()
}

/// The fit from its start on: solve → identify → reduce → accept → assemble.
fn finish(
    model: &dyn Model,
    input: &FitInput,
    config: &FitConfig,
    (problem, start): (FitProblem, start::Start),
    t0: Instant,
) -> Result<FitResult> {
    check_series_cost(config, input, &problem.layout, &start.p0)?;
    let run = solve_checked(&problem, input, &start, config);
    let solved_at = t0.elapsed().as_secs_f64();
    if !run.lm.cost.is_finite() {
        if let Some(why) = config.lm.stop.as_ref().and_then(Stop::requested) {
            return Err(stopped_before_first_evaluation(why, input.geo.len()));
        }
    }
    // A stop before the Jacobian at the best point was evaluated leaves no uncertainty.
    let uncomputed = !run.lm.jacobian.iter().all(|v| v.is_finite()) && config.stop_requested();
    let mut identified = identify::identify(input, &problem, &run, config.reduce);
    // The uncertainty is computed: the n × p Jacobian is not needed any more.
    let mut run = run;
    run.lm.jacobian = nalgebra::DMatrix::zeros(0, 0);
    if uncomputed {
        identified.verdict = Verdict::NotComputed;
    } else if rough_by_construction(model, config) {
        identified.verdict = Verdict::Rough;
    }
    let mut solved = reduce::reduce(model, input, config, problem, run, identified)?;
    if uncomputed {
        solved.notes.push(UNCERTAINTIES_NOT_COMPUTED.to_string());
    }
    accept::accept(&mut solved, input);
    // The report computes its residuals from the fitted values: the solver's are not held,
    // nor the vector it handed back for a next evaluation.
    solved.run.lm.residuals = nalgebra::DVector::zeros(0);
    solved.problem.forget_spare();
    let seconds = t0.elapsed().as_secs_f64();
    let stages = StageSeconds {
        grid: start.start_seconds,
        refine: start.init_seconds - start.start_seconds,
        solve: solved_at - start.init_seconds,
        uncertainty: seconds - solved_at,
        assemble: 0.0,
    };
    let mut result = assemble::assemble(model, input, config, solved, seconds, start);
    result.seconds = t0.elapsed().as_secs_f64();
    result.stage_seconds = StageSeconds {
        assemble: result.seconds - seconds,
        ..stages
    };
    Ok(result)
}

/// The error of a fit whose stop request (`why`) came before its first evaluation on the
/// whole data (`n` samples) had finished — while the starting values were searched for, or
/// in that evaluation: no point of the fit has a cost on the data, so there is nothing to
/// report (the CLI prints this message and exits 3).
fn stopped_before_first_evaluation(why: goniofit_lm::Termination, n: usize) -> Error {
    let hint = match why {
        goniofit_lm::Termination::Timeout => " (a larger --timeout lets one evaluation finish)",
        _ => "",
    };
    Error::Stopped(format!(
        "{} before the first model evaluation on the whole data ({n} samples) finished: nothing fitted{hint}",
        why.describe()
    ))
}

/// The note of a fit stopped before the Jacobian at its best point was evaluated.
pub(crate) const UNCERTAINTIES_NOT_COMPUTED: &str = "the fit was stopped before the Jacobian at its best point was evaluated: the values and the cost are those of that point, and their standard errors, correlations and what the data determines were not computed";

/// Solve from the start, and from each of the start search's rival valleys
/// (the lower cost inside the domain wins); when the first run ends at an edge of the physical domain
/// ([`at_kbs_edge`]), solve again from each other usable refined candidate, and
/// keep the lowest-cost run inside the domain unless the edge run is lower by more than
/// [`start::EDGE_MARGIN`] (then the edge run: the fit ends `degenerate` and says why).
/// A fit that may reduce starts and stays below the rough ridge's [`solve::RIDGE_G`]
/// ([`solve::SigmaRange`]). Each solve of a fit with free Fresnel parameters settles the
/// lobe with them held first ([`solve::run_lm_settled`]).
fn solve_checked(
    problem: &FitProblem,
    input: &FitInput,
    start: &start::Start,
    config: &FitConfig,
) -> solve::Run {
    let range = config
        .reduce
        .then(|| solve::SigmaRange::rough_ridge(problem, input))
        .flatten();
    let trail = solve::Trail::default();
    let solve = |p0: &[f64]| match &range {
        Some(r) => solve::run_lm_settled(
            problem,
            input,
            &r.project(p0),
            &config.lm,
            Some(r),
            Some(&trail),
        ),
        None => solve::run_lm_settled(problem, input, p0, &config.lm, None, Some(&trail)),
    };
    let first = solve(&start.p0);
    let layout = &problem.layout;
    if !at_kbs_edge(layout, input, &first.values) {
        let inside = |p: &[f64]| !at_kbs_edge(layout, input, p);
        let best = best_of_rivals(first, &start.rivals, &solve, &inside, config);
        return leave_small_basins(problem, best, &solve, &inside, config);
    }
    let mut runs = vec![first];
    let mut cut = false;
    for p0 in &start.alternatives {
        if config.stop_requested() {
            cut = true;
            break;
        }
        runs.push(solve(p0));
        cut |= was_stopped(&runs[runs.len() - 1]);
    }
    let lowest = |edge: bool| {
        (0..runs.len())
            .filter(|&i| !runs[i].joined)
            .filter(|&i| at_kbs_edge(layout, input, &runs[i].values) == edge)
            .min_by(|&a, &b| runs[a].lm.cost.total_cmp(&runs[b].lm.cost))
    };
    let edge = lowest(true).unwrap_or(0);
    let pick = match lowest(false) {
        Some(i) if runs[i].lm.cost <= runs[edge].lm.cost * (1.0 + start::EDGE_MARGIN) => i,
        _ => edge,
    };
    // The report counts the work of every run.
    let mut chosen = runs.swap_remove(pick);
    for other in &runs {
        chosen.add_counts(&other.lm);
    }
    if cut {
        chosen.mark_cut(&config.lm);
    }
    chosen
}

/// The lowest-cost run `inside` the domain of `first` and the solves from each of `rivals`
/// (`first` when none is lower). A stop request cuts the rivals short: the run kept then
/// ends with the stop's termination, as the search over valleys is not complete.
fn best_of_rivals(
    first: solve::Run,
    rivals: &[Vec<f64>],
    solve: &dyn Fn(&[f64]) -> solve::Run,
    inside: &dyn Fn(&[f64]) -> bool,
    config: &FitConfig,
) -> solve::Run {
    let mut kept = first;
    let mut cut = false;
    for p0 in rivals {
        if config.stop_requested() {
            cut = true;
            break;
        }
        let rival = solve(p0);
        cut |= was_stopped(&rival);
        let other;
        (kept, other) = if !rival.joined && inside(&rival.values) && rival.lm.cost < kept.lm.cost {
            (rival, kept)
        } else {
            (kept, rival)
        };
        kept.add_counts(&other.lm);
    }
    if cut {
        kept.mark_cut(&config.lm);
    }
    kept
}

/// Relative steps of each nonlinear parameter at which `leave_small_basins` probes a
/// converged log-residual fit (each way).
pub(crate) const PROBE_STEPS: [f64; 2] = [0.01, 0.04];

/// Most solves `leave_small_basins` starts from probes.
pub(crate) const PROBE_ROUNDS: usize = 4;

/// Relative cost by which a probe must lie below the converged point to be solved from.
pub(crate) const PROBE_GAIN: f64 = 1e-7;

/// A converged fit with log residuals, probed: each free nonlinear parameter (σ, T, w) is
/// moved by ±[`PROBE_STEPS`] (the smaller first) with the others held, and where a probe
/// inside the domain has a lower cost (by [`PROBE_GAIN`]), the fit is solved again from the
/// lowest probe of that step (at most
/// [`PROBE_ROUNDS`] times; the lower converged run is kept). Samples at the floor make the
/// log-residual cost of a real file rugged on the scale of a per cent: a Cornell paint's
/// kbs-rough fit converged in a dip 0.2 % wide at T = 5225 nm with the cost falling by 0.4 %
/// to T = 4480 nm. The other residual kinds are smooth and left as they are.
fn leave_small_basins(
    problem: &FitProblem,
    run: solve::Run,
    solve: &dyn Fn(&[f64]) -> solve::Run,
    inside: &dyn Fn(&[f64]) -> bool,
    config: &FitConfig,
) -> solve::Run {
    if problem.kind() != super::problem::ResidualKind::Log || !run.lm.termination.converged() {
        return run;
    }
    let specs = problem.model.params();
    let layout = &problem.layout;
    let nonlinear: Vec<usize> = layout
        .free()
        .into_iter()
        .filter(|&k| !super::problem::layout::LINEAR.contains(&specs[layout.params[k].spec].name))
        .collect();
    let cost = |q: &[f64]| {
        let (f, _) = problem.model_values(q, false);
        problem.cost_of(&problem.raw_residuals(&f))
    };
    let mut run = run;
    for _ in 0..PROBE_ROUNDS {
        if config.stop_requested() {
            break;
        }
        // The smallest step with a probe lower than the point, and its lowest probe.
        let lower = PROBE_STEPS.iter().find_map(|d| {
            nonlinear
                .iter()
                .flat_map(|&k| [1.0 - d, 1.0 + d].map(|f| (k, f)))
                .map(|(k, f)| {
                    let mut q = run.values.clone();
                    q[k] *= f;
                    q
                })
                .filter(|q| inside(q))
                .map(|q| (cost(&q), q))
                .filter(|(c, _)| c.is_finite() && *c < run.lm.cost * (1.0 - PROBE_GAIN))
                .min_by(|a, b| a.0.total_cmp(&b.0))
        });
        let Some((_, q)) = lower else { break };
        let mut next = solve(&q);
        let better = !next.joined
            && next.lm.termination.converged()
            && next.lm.cost < run.lm.cost
            && inside(&next.values);
        if !better {
            run.add_counts(&next.lm);
            break;
        }
        next.add_counts(&run.lm);
        run = next;
    }
    run
}

/// Whether a run ended on a stop request (time limit or interrupt).
fn was_stopped(run: &solve::Run) -> bool {
    matches!(
        run.lm.termination,
        goniofit_lm::Termination::Timeout | goniofit_lm::Termination::Interrupted
    )
}

/// Largest g a forced `--mode series` fit accepts at its start: the series sums O(√g) terms
/// per sample (at g ~ 1e6 about 0.5 ms per sample, against 2 µs with `auto`), so beyond this
/// one evaluation of a large file would take minutes.
pub(crate) const SERIES_G_MAX: f64 = 1e5;

/// Refuse a forced series evaluation on data so rough that one evaluation would take
/// minutes (see [`SERIES_G_MAX`]), with a hint to use `auto`.
fn check_series_cost(
    config: &FitConfig,
    input: &FitInput,
    layout: &ParamLayout,
    p0: &[f64],
) -> Result<()> {
    let Some(&k) = layout.find("sigma").first() else {
        return Ok(());
    };
    if config.model_opts.mode != EvalMode::Series {
        return Ok(());
    }
    let g_max = (0..input.geo.len())
        .map(|i| input.geo.g(i, p0[k]))
        .fold(0.0f64, f64::max);
    if g_max <= SERIES_G_MAX {
        return Ok(());
    }
    Err(Error::Usage(format!(
        "--mode series sums O(√g) terms per sample, and at the starting point (sigma = {:.3e}) g reaches {g_max:.3e} (above {SERIES_G_MAX:.0e}): one evaluation of these {} samples would cost of the order of √g = {:.0} terms each; use --mode auto, which meets the same --tol with the rough-limit asymptotics",
        p0[k],
        input.geo.len(),
        g_max.sqrt()
    )))
}

/// `config` with one stop request for every stage of the fit: the caller's
/// (`config.lm.stop`, e.g. one for a whole command), or a new one from `config.lm.timeout`,
/// `config.lm.interrupt` and the signals from now on.
fn with_stop(config: &FitConfig) -> FitConfig {
    let mut config = config.clone();
    if config.lm.stop.is_none() {
        config.lm.stop = Some(config.lm.new_stop());
    }
    config
}
