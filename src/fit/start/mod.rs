//! Start search: where the full fit begins.
//!
//! The grid of [`grid::initial_values`] ranks starting candidates on a subsample; each
//! candidate is then refined with a quick Levenberg–Marquardt run on the same subsample,
//! and the lowest refined cost inside the models' domain (on the full data) wins. All of
//! it runs on subsamples, beside the setup of the full problem.
//!
//! The grid is [`grid`]; its linear amplitudes, solved exactly at every grid point, are
//! [`amplitudes`]; the model's side of the grid, computed once per angular layout, is
//! [`grid_cache`].

pub(crate) mod amplitudes;
pub(crate) mod grid;
pub(crate) mod grid_cache;

use super::config::FitConfig;
use super::problem::{FitInput, FitProblem, ParamLayout};
use super::solve::{factors_held, run_lm, Run};
use crate::error::Result;
use crate::model::{self, EvalMode, Model, ModelOptions};
use goniofit_lm::{LmConfig, Stop};
use rayon::prelude::*;
use std::time::Instant;

/// Accuracy of the model on the starting-value grid (it only ranks candidates).
pub(crate) const GRID_TOL: f64 = 1e-4;

/// Relative cost by which an optimum at an edge of the physical domain (T/σ → 0, kT → 0)
/// must lie below the best one inside it to count as the fit's result (and the fit then
/// ends `degenerate`): below that margin, the inside optimum explains the data as well,
/// with a lobe the surface can have. The same margin compares the full solves.
pub(crate) const EDGE_MARGIN: f64 = 1e-3;

/// Relative subsample cost within which the second-best refined candidate is solved on the
/// full data as well: the subsample (256 samples, coarse tolerances) cannot rank two
/// valleys closer than this (Cornell acryl_blue 460 nm: the wide lobe won on the
/// subsample, the narrow one is 6 % lower on the full data).
pub(crate) const RIVAL_MARGIN: f64 = 0.1;

/// Most rival valleys solved on the whole data besides the winner's (`choose_refined`).
pub(crate) const RIVALS: usize = 2;

/// Relative difference in every parameter within which two refined candidates ended at the
/// same optimum: the refinement stops at relative steps of its `xtol` (10⁻⁶), so one valley
/// reached from two starts agrees far closer than this, while distinct valleys of the grid
/// lie a factor of ~2 apart ([`grid::initial_values`]).
pub(crate) const SAME_OPTIMUM: f64 = 1e-3;

/// Relative cost difference within which two refined KBS points with the same T/σ (to
/// [`SAME_OPTIMUM`]·10) lie in one valley of the rough ridge: the refinement with the rough
/// approximation holds σ, so one valley reached from two starts ends at two σ along the
/// ridge, with the same lobe and cost.
pub(crate) const SAME_RIDGE_COST: f64 = 1e-5;

/// Whether two refined points (layout order, with their costs) are the same optimum (see
/// [`SAME_OPTIMUM`]), or, for KBS (`ridge`: layout indices of σ and T), the same valley of
/// the rough ridge ([`SAME_RIDGE_COST`]).
fn same_optimum(a: (f64, &[f64]), b: (f64, &[f64]), ridge: Option<(usize, usize)>) -> bool {
    let close = |x: f64, y: f64, tol: f64| (x - y).abs() <= tol * x.abs().max(y.abs());
    let same_point =
        a.1.iter()
            .zip(b.1)
            .all(|(&x, &y)| close(x, y, SAME_OPTIMUM));
    same_point
        || ridge.is_some_and(|(s, t)| {
            close(a.1[t] / a.1[s], b.1[t] / b.1[s], 10.0 * SAME_OPTIMUM)
                && close(a.0, b.0, SAME_RIDGE_COST)
        })
}

/// Model accuracy of the quick refinement on a subsample (it only has to land near the
/// optimum; the full fit then works at the requested accuracy).
pub(crate) const REFINE_TOL: f64 = 1e-6;

/// Where the full fit starts, and when the search for it ended.
pub(super) struct Start {
    /// The refined starting point (layout order).
    pub p0: Vec<f64>,
    /// The grid point whose refinement won.
    pub grid_start: Vec<f64>,
    /// Seconds from the fit's start to the grid's candidates.
    pub start_seconds: f64,
    /// Seconds from the fit's start to the end of the refinement.
    pub init_seconds: f64,
    /// The other usable refined candidates, lowest cost first: where the full fit starts
    /// again when its first solve runs to an edge of the domain.
    pub alternatives: Vec<Vec<f64>>,
    /// The other usable refined candidates in valleys of their own whose subsample costs
    /// are within [`RIVAL_MARGIN`] of the winner's, lowest first (at most [`RIVALS`]):
    /// valleys the full fit also solves from, keeping the lowest cost.
    pub rivals: Vec<Vec<f64>>,
}

impl Start {
    /// A start at `p0` (layout order) without a search: no alternatives or rivals, the
    /// search's times those of the call (from the fit's start `t0`).
    pub(super) fn given(p0: Vec<f64>, t0: Instant) -> Start {
        let now = t0.elapsed().as_secs_f64();
        Start {
            grid_start: p0.clone(),
            p0,
            start_seconds: now,
            init_seconds: now,
            alternatives: Vec::new(),
            rivals: Vec::new(),
        }
    }
}

/// The models the start search evaluates, each at the accuracy its stage needs: the
/// grid's ([`GRID_TOL`]), the refinement's ([`REFINE_TOL`]) and, for KBS models, the rough
/// and smooth approximations that refine candidates in their bands (at [`REFINE_TOL`]).
struct SearchModels {
    grid: Box<dyn Model>,
    refine: Box<dyn Model>,
    rough: Option<Box<dyn Model>>,
    smooth: Option<Box<dyn Model>>,
}

impl SearchModels {
    /// The fit's `model` at the search's accuracies; `kbs`: whether it has σ (and so the
    /// rough and smooth approximations).
    fn new(model: &dyn Model, config: &FitConfig, kbs: bool) -> Result<Self> {
        let grid = loose_model(model, config, GRID_TOL, None)?;
        let refine = loose_model(model, config, REFINE_TOL, None)?;
        let limit = |mode| {
            kbs.then(|| loose_model(model, config, REFINE_TOL, Some(mode)))
                .transpose()
        };
        let (rough, smooth) = (limit(EvalMode::Rough)?, limit(EvalMode::Smooth)?);
        Ok(SearchModels {
            grid,
            refine,
            rough,
            smooth,
        })
    }
}

/// The subsample problems the candidates are refined on: the model at [`REFINE_TOL`], and
/// for KBS models its rough approximation (exact in the rough band, and it avoids the
/// O(√g) series far from the specular peak). The rough approximation depends on σ and T
/// only through T/σ, so its problem is built per candidate with σ held.
struct Refiners<'m> {
    exact: FitProblem<'m>,
    rough: Option<&'m dyn Model>,
    /// The smooth approximation (KBS models): a smooth-band candidate is refined with it
    /// at its σ, so that it stays in the smooth valley (σ → 0 at fixed sσ²), which the
    /// exact model's refinement on a subsample leaves for a rougher one the whole file
    /// may not prefer.
    smooth: Option<&'m dyn Model>,
    /// Layout index of σ (KBS models).
    sigma_k: Option<usize>,
    /// The subsample both problems are built on.
    sub: FitInput,
    /// Whether σ or T has a value the user gave (`--init`): a slide along the rough ridge
    /// would move it away from where the user asked the fit to start.
    ridge_given: bool,
}

impl<'m> Refiners<'m> {
    /// The refiners of `models` on the start search's subsample of `input` (its size set by
    /// the fit's `model`), with the fit's residual `floor`; `given[k]` holds a user's
    /// `--init` or `--fix` value.
    fn new(
        models: &'m SearchModels,
        model: &dyn Model,
        layout: &ParamLayout,
        input: &FitInput,
        config: &FitConfig,
        floor: f64,
        given: &[Option<f64>],
    ) -> Result<Self> {
        let sigma_k = layout.find("sigma").first().copied();
        // Layout indices of σ and T (KBS models).
        let ridge = sigma_k.zip(layout.find("T").first().copied());
        let sub = grid::search_input(input, grid::search_samples(model));
        let exact = FitProblem::new(
            models.refine.as_ref(),
            layout.clone(),
            &sub,
            config.residual,
            floor,
        )?;
        Ok(Refiners {
            exact,
            rough: models.rough.as_deref(),
            smooth: models.smooth.as_deref(),
            sigma_k,
            sub,
            ridge_given: ridge.is_some_and(|(ks, kt)| given[ks].is_some() || given[kt].is_some()),
        })
    }

    /// The rough approximation's problem on the subsample with σ held at `start`'s value (the
    /// approximation has no gradient along the rough ridge, so a free σ would wander along it,
    /// to σ → 0 as readily as anywhere); None without a rough approximation.
    fn rough_problem(&self, start: &[f64]) -> Option<FitProblem<'m>> {
        self.held_sigma_problem(self.rough?, start)
    }

    /// The KBS regime band of point `p` by its median g on the subsample: smooth 0 (below
    /// [`grid::SMOOTH_BAND_G`]), between 1, rough 2 (above [`grid::ROUGH_BAND_G`]); None
    /// without σ.
    fn band(&self, p: &[f64]) -> Option<u8> {
        self.sigma_k.map(|k| match self.sub.geo.median_g(p[k]) {
            g if g < grid::SMOOTH_BAND_G => 0,
            g if g > grid::ROUGH_BAND_G => 2,
            _ => 1,
        })
    }

    /// Append a copy of the best smooth-band candidate when the grid ranks it within
    /// [`RIVAL_MARGIN`] of its best, to be refined once more with the smooth approximation
    /// at its σ; its index, or None.
    fn add_smooth_held(&self, candidates: &mut Vec<(f64, Vec<f64>)>) -> Option<usize> {
        let grid_best = candidates.first().map_or(f64::INFINITY, |c| c.0);
        let smooth = candidates
            .iter()
            .find(|(_, c)| self.band(c) == Some(0))
            .filter(|(cost, _)| *cost <= grid_best * (1.0 + RIVAL_MARGIN))
            .cloned()?;
        candidates.push(smooth);
        Some(candidates.len() - 1)
    }

    /// The smooth approximation's problem on the subsample with σ held at `start`'s value
    /// (in the smooth limit only sσ² is determined); None without one.
    fn smooth_problem(&self, start: &[f64]) -> Option<FitProblem<'m>> {
        self.held_sigma_problem(self.smooth?, start)
    }

    /// A quick LM run of `problem` (on the subsample) from `start`, first with the Fresnel
    /// factor's free parameters (`n`, `kappa`) held at their start, then with them free
    /// from where the lobe settled. From a grid point the lobe's σ and T are off by up to
    /// the grid's step, and a free index then absorbs that misfit: it runs to n → ∞
    /// (where the factor is 1 and the plain lobe's valley lies, a local minimum at
    /// infinity) while its profile at the settled lobe falls towards the truth. Returns the
    /// run and, when the free index left the held one by more than a factor
    /// [`FACTOR_RUNAWAY`] (in the factor's shape), the settled point: the subsample cannot tell whether the index
    /// ran to another valley of the whole data or only past one the subsample does not
    /// resolve, so the full fit solves from both ([`settled_rival`]).
    fn run_settled(
        &self,
        problem: &FitProblem,
        start: &[f64],
        coarse: &LmConfig,
    ) -> (Run, Option<Vec<f64>>) {
        let specs = problem.model.params();
        match factors_held(problem, &self.sub, start) {
            Some((lobe, held)) if !stopped(coarse.stop.as_ref()) => {
                let settled = run_lm(&lobe, start, coarse);
                let run = run_lm(problem, &settled.values, coarse);
                let ran_away = held.iter().any(|&k| {
                    let shape = |v: f64| match specs[problem.layout.params[k].spec].name {
                        "n" => ((v - 1.0) / (v + 1.0)).abs(),
                        _ => v.abs(),
                    };
                    let ratio = shape(run.values[k]) / shape(settled.values[k]);
                    let moved = ratio.ln().abs();
                    moved.is_nan() || moved > FACTOR_RUNAWAY.ln()
                });
                (run, ran_away.then_some(settled.values))
            }
            _ => (run_lm(problem, start, coarse), None),
        }
    }

    /// `model`'s problem on the subsample with σ held at `start`'s value.
    fn held_sigma_problem(&self, model: &'m dyn Model, start: &[f64]) -> Option<FitProblem<'m>> {
        let k = self.sigma_k?;
        let mut layout = self.exact.layout.clone();
        layout.params[k].fixed = Some(start[k]);
        let (kind, floor) = (self.exact.kind(), self.exact.floor);
        FitProblem::new(model, layout, &self.sub, kind, floor).ok()
    }
}

/// Factor by which a Fresnel parameter freed after the lobe settled must move for the
/// settled point to be solved on the whole data as well (`Refiners::run_settled`), the
/// index n measured by the factor's shape r₀ = |n − 1|/(n + 1) (the grazing rise is
/// 1/r₀²), κ as it is: the grid's index steps by about 2 in r₀, so a smaller move stays
/// in the valley the grid point was in.
pub(crate) const FACTOR_RUNAWAY: f64 = 2.0;

/// The quick refinement's solver settings: loose tolerances, at most 100 iterations.
fn coarse_config(config: &FitConfig) -> LmConfig {
    LmConfig {
        ftol: 1e-6,
        xtol: 1e-6,
        max_iters: 100,
        progress: false,
        predicted_stop: true,
        ..config.lm.clone()
    }
}

/// The fit's model at a looser tolerance (and optionally in a forced evaluation mode).
fn loose_model(
    model: &dyn Model,
    config: &FitConfig,
    tol: f64,
    mode: Option<EvalMode>,
) -> Result<Box<dyn Model>> {
    model::by_name(
        model.name(),
        &ModelOptions {
            tol: tol.max(config.model_opts.tol),
            mode: mode.unwrap_or(config.model_opts.mode),
            ..config.model_opts
        },
    )
}

/// The starting point: the grid's candidates, each refined on a subsample, the lowest
/// refined cost inside the domain winning (see the module doc). `given[k]` holds a user's
/// `--init` or `--fix` value.
pub(super) fn starting_point(
    model: &dyn Model,
    layout: &ParamLayout,
    input: &FitInput,
    config: &FitConfig,
    floor: f64,
    given: &[Option<f64>],
    t0: Instant,
) -> Result<Start> {
    let kbs = !layout.find("sigma").is_empty();
    let models = SearchModels::new(model, config, kbs)?;
    let bar = search_bar(config.lm.progress);
    let refiners = Refiners::new(&models, model, layout, input, config, floor, given)?;
    // The grid runs on (for KBS, at most GRID_SAMPLES of) the refinement's subsample.
    let stop = config.lm.stop.as_ref();
    let mut candidates = grid::initial_values(
        &refiners.exact,
        models.grid.as_ref(),
        &refiners.sub,
        given,
        stop,
    );
    let held = refiners.add_smooth_held(&mut candidates);
    let start_seconds = t0.elapsed().as_secs_f64();
    // A start must lie inside the models' domain on every sample, not only on the
    // subsample: a rough-valley candidate can drift to a σ where a sample outside the
    // subsample has g beyond the fit's limit. Without any refined start inside, the first
    // grid candidate inside is taken.
    let inside = |p: &[f64]| input.in_domain(model, layout, p);
    let first_grid = candidates.iter().position(|(_, c)| inside(c)).unwrap_or(0);
    let mut grid_start = candidates[first_grid].1.clone();
    let mut p0 = grid_start.clone();
    let coarse = coarse_config(config);
    let mut alternatives = Vec::new();
    let mut rivals = Vec::new();
    // After a stop request nothing is refined (the fit's first evaluation on the whole data
    // is then cut too, and the fit ends with nothing fitted).
    if refiners.sub.y.len() > layout.free().len() && !stopped(stop) {
        let at_edge = |p: &[f64]| super::problem::edges::at_kbs_edge(layout, input, p);
        let chosen = refine_and_choose(
            &refiners,
            &candidates,
            held,
            (&inside, &at_edge),
            &coarse,
            &bar,
        );
        if let Some((values, start)) = chosen.start {
            p0 = values;
            grid_start = start;
        }
        alternatives = chosen.alternatives;
        rivals = chosen.rivals;
    }
    bar.finish_and_clear();
    Ok(Start {
        p0,
        grid_start,
        start_seconds,
        init_seconds: t0.elapsed().as_secs_f64(),
        alternatives,
        rivals,
    })
}

/// A test of a point in parameter space (layout order), shareable across threads.
type PointTest<'a> = &'a (dyn Fn(&[f64]) -> bool + Sync);

/// Refine every candidate (`held`: the one refined with the smooth approximation) and
/// choose among them ([`choose_refined`]); `domain`: whether a point is inside the
/// models' domain on the whole data, and whether it lies at an edge of it.
fn refine_and_choose(
    refiners: &Refiners,
    candidates: &[(f64, Vec<f64>)],
    held: Option<usize>,
    domain: (PointTest, PointTest),
    coarse: &LmConfig,
    bar: &indicatif::ProgressBar,
) -> Chosen {
    let (inside, at_edge) = domain;
    show_refining(bar, candidates.len(), refiners.sub.y.len());
    let refined = refine_candidates(refiners, candidates, held, coarse, inside, bar);
    let band = |p: &[f64]| refiners.band(p);
    let band_only = held.map(|i| refined[i].values.clone());
    let ridge = refiners
        .sigma_k
        .zip(refiners.exact.layout.find("T").first().copied());
    let points: Vec<(f64, Vec<f64>)> = refined.iter().map(|r| (r.cost, r.values.clone())).collect();
    let mut chosen = choose_refined(
        &points,
        candidates,
        at_edge,
        coarse.ftol,
        Valleys {
            ridge,
            band: &band,
            band_only: band_only.as_deref(),
        },
    );
    let settled = chosen
        .start
        .as_ref()
        .and_then(|(winner, _)| settled_rival(&refined, winner, ridge));
    chosen.rivals.extend(settled);
    chosen
}

/// Refine each candidate with a quick LM on the subsample (in parallel): the grid's best
/// point can be a factor of a few off, or sit in the valley of the rough asymptote
/// (σ → ∞ at fixed T/σ) while the truth is elsewhere. A candidate in the rough band
/// (median g > [`grid::ROUGH_BAND_G`]) is refined with the rough approximation and its
/// refined cost then taken with the exact model; candidate `smooth_held` is refined with the
/// smooth approximation at its σ, and its cost taken the same way.
/// Returns each candidate's [`Refined`]; the cost is infinite for a refined point that is not finite or not inside the domain,
/// or for a candidate whose refinement was not started before a stop request (the fit's
/// `coarse.stop`; a refinement under way ends at its last complete point).
fn refine_candidates(
    refiners: &Refiners,
    candidates: &[(f64, Vec<f64>)],
    smooth_held: Option<usize>,
    coarse: &LmConfig,
    inside: &(dyn Fn(&[f64]) -> bool + Sync),
    bar: &indicatif::ProgressBar,
) -> Vec<Refined> {
    candidates
        .par_iter()
        .enumerate()
        .map(|(i, (_, start))| {
            let _done = Done(bar);
            if stopped(coarse.stop.as_ref()) {
                return Refined {
                    cost: f64::INFINITY,
                    values: start.clone(),
                    settled: None,
                };
            }
            let rough_band = refiners.band(start) == Some(2);
            let smooth_band = smooth_held == Some(i);
            let exact_cost = |q: &[f64]| 0.5 * refiners.exact.weighted_residuals(q).norm_squared();
            let ((cost, values), settled) = match (refiners.rough_problem(start), rough_band) {
                (Some(rough), true) => {
                    let (run, settled) = refiners.run_settled(&rough, start, coarse);
                    let stop = coarse.stop.as_ref();
                    (
                        slide_rough_ridge(refiners, run.values, inside, stop),
                        settled,
                    )
                }
                _ if smooth_band && refiners.smooth_problem(start).is_some() => {
                    let smooth = refiners.smooth_problem(start).expect("checked");
                    let (run, settled) = refiners.run_settled(&smooth, start, coarse);
                    ((exact_cost(&run.values), run.values), settled)
                }
                _ => {
                    let (run, settled) = refiners.run_settled(&refiners.exact, start, coarse);
                    ((run.lm.cost, run.values), settled)
                }
            };
            // A refined start outside the domain (on the full data) does not count.
            let usable = |c: f64, v: &[f64]| {
                if c.is_finite() && inside(v) {
                    c
                } else {
                    f64::INFINITY
                }
            };
            let settled = settled.map(|v| (usable(exact_cost(&v), &v), v));
            Refined {
                cost: usable(cost, &values),
                values,
                settled,
            }
        })
        .collect()
}

/// A candidate after its refinement on the subsample: the refined point with its exact
/// cost there (infinite when not usable), and the lobe's settled point when the Fresnel
/// index ran away from it ([`Refiners::run_settled`]), with its exact cost.
struct Refined {
    cost: f64,
    values: Vec<f64>,
    settled: Option<(f64, Vec<f64>)>,
}

/// The settled point of the refinement that won, when the free index ran away from it and
/// its subsample cost is within [`RIVAL_MARGIN`] of the winner's: a valley the whole data
/// may prefer (a lobe with an index the subsample's profile falls away from), solved as a
/// rival.
fn settled_rival(
    refined: &[Refined],
    winner: &[f64],
    ridge: Option<(usize, usize)>,
) -> Option<Vec<f64>> {
    let won = refined.iter().find(|r| r.values == winner)?;
    let (cost, values) = won.settled.as_ref()?;
    let close = *cost <= won.cost * (1.0 + RIVAL_MARGIN);
    (close && !same_optimum((*cost, values), (won.cost, winner), ridge)).then(|| values.clone())
}

/// The start search's line on standard error while it runs (`show`: the fit's progress
/// display, on a terminal and without `--quiet`): the grid, then the candidates refined of
/// how many. Hidden otherwise (and indicatif draws nothing when standard error is not a
/// terminal).
fn search_bar(show: bool) -> indicatif::ProgressBar {
    if !show {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} start search {elapsed} {msg}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    bar.set_message("grid of starting values");
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    bar
}

/// Turn the search bar into a count of the `n` candidates refined on `samples` samples.
fn show_refining(bar: &indicatif::ProgressBar, n: usize, samples: usize) {
    bar.set_length(n as u64);
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{spinner} start search {elapsed} {msg}: {pos}/{len} done",
    ) {
        bar.set_style(style);
    }
    bar.set_message(format!("refining {n} candidates on {samples} samples"));
}

/// Counts one refined candidate on the start search's line when dropped (also when the
/// refinement returns early).
struct Done<'b>(&'b indicatif::ProgressBar);

impl Drop for Done<'_> {
    fn drop(&mut self) {
        self.0.inc(1);
    }
}

/// What the refined candidates give the full fit: its start (refined values, the grid
/// point they came from), the other starts in the order to try them, and rival valleys.
struct Chosen {
    start: Option<(Vec<f64>, Vec<f64>)>,
    alternatives: Vec<Vec<f64>>,
    rivals: Vec<Vec<f64>>,
}

/// How [`choose_refined`] tells valleys apart: `ridge` (layout indices of σ and T, KBS),
/// `band` (a point's KBS regime band) and `band_only` (a refined point that may be a rival
/// only as its band's extra one).
struct Valleys<'a> {
    ridge: Option<(usize, usize)>,
    band: &'a dyn Fn(&[f64]) -> Option<u8>,
    band_only: Option<&'a [f64]>,
}

/// Choose among the refined candidates (`refined[i]` from `candidates[i]`). A refined start
/// at an edge of the physical domain (T/σ → 0, T → 0: `at_edge`) is no optimum worth
/// starting from while another candidate's valley is about as low; when the edge is lower
/// by more than [`EDGE_MARGIN`], the data's best fit is the edge, and the full fit starts
/// there (to end `degenerate`, saying why), the others as alternatives. Otherwise the
/// lowest usable one starts (ties within `ftol` to the better-ranked grid point), and the
/// next usable ones in valleys of their own ([`same_optimum`], `ridge`: layout indices of σ
/// and T) are rivals when their costs are within [`RIVAL_MARGIN`] (at most [`RIVALS`], and
/// one more from a KBS regime band, `band`: smooth 0, between 1, rough 2, that none of them
/// is in; the smooth approximation's refinement, `band_only`, is a rival only as that one).
fn choose_refined(
    refined: &[(f64, Vec<f64>)],
    candidates: &[(f64, Vec<f64>)],
    at_edge: &dyn Fn(&[f64]) -> bool,
    ftol: f64,
    valleys: Valleys,
) -> Chosen {
    let Valleys {
        ridge,
        band,
        band_only,
    } = valleys;
    let (edge, usable): (Vec<_>, Vec<_>) = refined
        .iter()
        .cloned()
        .zip(candidates)
        .partition(|((_, v), _)| at_edge(v));
    let (usable, usable_grid): (Vec<_>, Vec<_>) =
        usable.into_iter().map(|(r, c)| (r, c.clone())).unzip();
    let others = other_usable(&usable, &usable_grid, ftol);
    let best_usable = usable.iter().map(|r| r.0).fold(f64::INFINITY, f64::min);
    let lowest_edge = edge
        .iter()
        .filter(|((c, _), _)| c.is_finite())
        .min_by(|a, b| a.0 .0.total_cmp(&b.0 .0));
    let mut chosen = Chosen {
        start: None,
        alternatives: Vec::new(),
        rivals: Vec::new(),
    };
    match (lowest_refined(usable, &usable_grid, ftol), lowest_edge) {
        (winner, Some(((cost, values), grid)))
            if winner.is_none() || *cost < best_usable * (1.0 - EDGE_MARGIN) =>
        {
            if let Some((w, _)) = winner {
                chosen.alternatives.push(w);
            }
            chosen.start = Some((values.clone(), grid.1.clone()));
        }
        (Some(winner), _) => {
            // Other valleys about as low on the subsample are solved too. A candidate whose
            // refinement ended at an optimum already kept is no other valley: solving from
            // it again would only find that optimum once more, to the solver's tolerance,
            // and in a flat valley let rounding pick between the two ends.
            let mut kept: Vec<(f64, &[f64])> = vec![(best_usable, &winner.0)];
            for (c, v) in others.iter() {
                let new = kept.iter().all(|&k| !same_optimum((*c, v), k, ridge));
                let regular = band_only != Some(v.as_slice());
                if *c <= best_usable * (1.0 + RIVAL_MARGIN)
                    && new
                    && regular
                    && kept.len() <= RIVALS
                {
                    kept.push((*c, v));
                    chosen.rivals.push(v.clone());
                }
            }
            // A KBS regime band none of them is in (the smooth valley below rougher ones
            // as low on the subsample) gets one more solve: its lowest valley within the
            // margin.
            let seen: Vec<Option<u8>> = kept.iter().map(|k| band(k.1)).collect();
            let extra = others.iter().find(|(c, v)| {
                let b = band(v);
                b.is_some()
                    && !seen.contains(&b)
                    && *c <= best_usable * (1.0 + RIVAL_MARGIN)
                    && kept.iter().all(|&k| !same_optimum((*c, v), k, ridge))
            });
            if let Some((_, v)) = extra {
                chosen.rivals.push(v.clone());
            }
            chosen.start = Some(winner);
        }
        _ => {}
    }
    chosen
        .alternatives
        .extend(others.into_iter().map(|(_, v)| v));
    chosen
}

/// Whether `stop` was requested (the fit's stop request; none: never).
fn stopped(stop: Option<&Stop>) -> bool {
    stop.is_some_and(Stop::is_requested)
}

/// Factor by which `slide_rough_ridge` scales σ and T per step.
pub(crate) const RIDGE_STEP: f64 = 2.0;

/// Most steps of `slide_rough_ridge` (σ up to 2¹² ≈ 4000 times the refined one; the
/// domain's g limit usually ends the slide first).
pub(crate) const RIDGE_STEPS: usize = 12;

/// Slide a point refined with the rough approximation along the rough ridge to where the
/// exact model fits the subsample best, and return (exact cost, point). The ridge scales σ
/// and T together and holds T/σ and the scales: the rough approximation is the same all
/// along it, so its refinement cannot move σ there, yet at a σ of a few λ the exact model
/// is still far from its rough limit wherever the lobe is faint (its low-order series terms
/// are wider than the Gaussian limit), and weights that follow the values (relative noise,
/// 1/σ_L² with σ_L ∝ L) count those samples as much as the peak. The grid's σ axis ends at
/// 4λ, so a lobe of σ ≈ 8λ would otherwise be judged at a σ where the exact cost is 10⁵
/// times the truth's, and lose to a smooth-looking optimum (as in `goniofit recover`). The slide
/// steps by [`RIDGE_STEP`] while the exact cost falls, the point stays `inside` the domain
/// and at most [`RIDGE_STEPS`] times, and no step is started after a stop request. A σ or
/// T the user gave (`--init`) or held (`--fix`) is not slid.
fn slide_rough_ridge(
    refiners: &Refiners,
    mut p: Vec<f64>,
    inside: &(dyn Fn(&[f64]) -> bool + Sync),
    stop: Option<&Stop>,
) -> (f64, Vec<f64>) {
    let exact_cost = |q: &[f64]| 0.5 * refiners.exact.weighted_residuals(q).norm_squared();
    let mut cost = exact_cost(&p);
    let (Some(ks), Some(&kt)) = (refiners.sigma_k, refiners.exact.layout.find("T").first()) else {
        return (cost, p);
    };
    // A held σ (--fix) or T is not moved: the ridge is then not free to slide along.
    let held = |k: usize| refiners.exact.layout.params[k].fixed.is_some();
    if held(ks) || held(kt) || refiners.ridge_given {
        return (cost, p);
    }
    for _ in 0..RIDGE_STEPS {
        if stopped(stop) {
            break;
        }
        let mut q = p.clone();
        q[ks] *= RIDGE_STEP;
        q[kt] *= RIDGE_STEP;
        if !inside(&q) {
            break;
        }
        let c = exact_cost(&q);
        // NaN (a failed evaluation) ends the slide too.
        if c.partial_cmp(&cost) != Some(std::cmp::Ordering::Less) {
            break;
        }
        (cost, p) = (c, q);
    }
    (cost, p)
}

/// The refined point with the lowest cost, and the grid point it came from. Costs within
/// the refinement's `ftol` count as a tie, won by the better-ranked grid point.
fn lowest_refined(
    refined: Vec<(f64, Vec<f64>)>,
    candidates: &[(f64, Vec<f64>)],
    ftol: f64,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let lowest = refined.iter().map(|r| r.0).fold(f64::INFINITY, f64::min);
    refined
        .into_iter()
        .zip(candidates)
        .find(|(r, _)| r.0.is_finite() && r.0 <= lowest * (1.0 + ftol))
        .map(|((_, values), (_, start))| (values, start.clone()))
}

/// The usable refined points other than the winner of [`lowest_refined`] with their refined
/// costs, lowest cost first.
fn other_usable(
    refined: &[(f64, Vec<f64>)],
    candidates: &[(f64, Vec<f64>)],
    ftol: f64,
) -> Vec<(f64, Vec<f64>)> {
    let winner = lowest_refined(refined.to_vec(), candidates, ftol).map(|w| w.0);
    let mut rest: Vec<&(f64, Vec<f64>)> = refined
        .iter()
        .filter(|r| r.0.is_finite() && Some(&r.1) != winner.as_ref())
        .collect();
    rest.sort_by(|a, b| a.0.total_cmp(&b.0));
    rest.into_iter().cloned().collect()
}
