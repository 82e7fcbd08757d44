//! Starting values found from the data: a coarse grid over the nonlinear parameters
//! (σ/λ and T/λ for KBS, the lobe width w for the specular lobe), with the linear
//! parameters (scales, lobe strength) solved exactly by linear least squares at every grid
//! point (variable projection). For KBS the grid runs on a subsample spread over the whole
//! file ([`subsample`]) of at most [`GRID_SAMPLES`] samples, so its cost does not grow with
//! the dataset; models without the series run on up to [`CHEAP_MODEL_SAMPLES`].

use super::amplitudes::{self, Prepared};
use super::grid_cache;
use crate::fit::problem::{FitInput, FitProblem, ParamLayout};
use crate::geometry::median;
use goniofit_lm::Stop;
use rayon::prelude::*;

/// Largest number of samples the coarse grid is evaluated on.
pub(crate) const GRID_SAMPLES: usize = 256;

/// Median g above which a grid point is ranked with the rough approximation (below it, the
/// smooth one): the grid only ranks candidates, the refinement uses the exact model.
pub(crate) const GRID_ROUGH_G: f64 = 1.0;

/// Median g below which a KBS grid point is in the smooth band.
pub(crate) const SMOOTH_BAND_G: f64 = 0.1;

/// Median g above which a KBS grid point is in the rough band.
pub(crate) const ROUGH_BAND_G: f64 = 10.0;

/// Grid points kept as starting candidates (best first, in distinct valleys).
pub(crate) const CANDIDATES: usize = 3;

/// Samples of the quick LM refinement between the grid and the full fit (a golden-ratio
/// subsample, [`subsample`]: 256 spread over every loop of a scan start the full fit as
/// close as 512 did; with a plain stride, 256 could miss whole azimuth ranges).
pub(crate) const REFINE_SAMPLES: usize = 256;

/// Largest number of samples the start search of a model without the KBS series (Lambert,
/// Gaussian lobe: a few operations per sample) runs on, grid and refinement alike: all of
/// a gonioreflectometer file. A subsample ranks valleys wrongly where a narrow lobe is seen
/// by few samples (a Cornell paint's mirror peak: the subsample's best lobe 35 % above the
/// whole file's).
pub(crate) const CHEAP_MODEL_SAMPLES: usize = 8192;

/// Samples the start search of `model` runs on: [`REFINE_SAMPLES`] with the KBS series,
/// [`CHEAP_MODEL_SAMPLES`] without.
pub(crate) fn search_samples(model: &dyn crate::model::Model) -> usize {
    if model.params().iter().any(|s| s.name == "sigma") {
        REFINE_SAMPLES
    } else {
        CHEAP_MODEL_SAMPLES
    }
}

/// Samples nearest the mirror direction that the start search's sample always holds
/// ([`search_input`]).
pub(crate) const NEAR_SPECULAR_SAMPLES: usize = 32;

/// Parameters that enter the model linearly (solved exactly at each grid point).
pub(crate) use crate::fit::problem::LINEAR;

/// Grid values for a nonlinear parameter, in the unit of the reference wavelength `lambda`.
fn grid_for(name: &str, lambda: f64) -> Vec<f64> {
    let logspace = |lo: f64, hi: f64, n: usize| -> Vec<f64> {
        (0..n)
            .map(|k| lo * (hi / lo).powf(k as f64 / (n - 1) as f64))
            .collect()
    };
    match name {
        "sigma" => logspace(0.002, 4.0, 12)
            .into_iter()
            .map(|v| v * lambda)
            .collect(),
        "T" => logspace(0.02, 400.0, 14)
            .into_iter()
            .map(|v| v * lambda)
            .collect(),
        "w" => logspace(0.003, 1.2, 30),
        // The Fresnel factor's index: a paint's or glass's n = 1.5 (its candidates are
        // picked as every parameter's), then indices that give other grazing rises
        // F(90°) = 1/R(0) = 1/r₀², r₀ = (n − 1)/(n + 1) = 0.03, 0.1, 0.35, 0.8 (rises of
        // 1100, 100, 8 and 1.6; n = 1.06, 1.22, 2.08, 9), each the start of one more
        // candidate where the grid fits it better than n = 1.5 ([`other_indices`]): a
        // single start falls into whichever valley of n is nearest (n → 1, a high index, or
        // the plain lobe's at n → ∞, where F = 1). A metal's extinction order.
        "n" => std::iter::once(PRIMARY_INDEX)
            .chain([0.03, 0.1, 0.35, 0.8].map(|r0: f64| (1.0 + r0) / (1.0 - r0)))
            .collect(),
        "kappa" => vec![1.0],
        _ => vec![1.0],
    }
}

/// Whether a layout parameter is linear.
pub(crate) fn is_linear(
    layout: &ParamLayout,
    k: usize,
    model_specs: &[crate::model::ParamSpec],
) -> bool {
    LINEAR.contains(&model_specs[layout.params[k].spec].name)
}

/// Starting values for every layout parameter, from the grid over `input` (which `problem`
/// was built on; the fit passes its refinement subsample). `given[k]` holds a user's
/// `--init` or `--fix` value (used as is, and not searched over). Returns the candidates,
/// best first: (grid cost, full parameter values).
///
/// `grid_model` is the model the grid is evaluated with: the fit's model at a loose
/// tolerance (the grid only ranks candidates; LM then works at the requested one). For KBS
/// models, grid points whose median g is far into a limit use that limit's approximation
/// (the grid's corners, σ ≫ λ or T ≫ λ, would otherwise dominate its cost).
///
/// Once `stop` is requested no further grid point is started: the candidates are the best
/// of the points completed by then (every cost is that of a whole point), or the fallback
/// start (all ones, infinite cost) when the grid's model side was not complete.
pub(crate) fn initial_values(
    problem: &FitProblem,
    grid_model: &dyn crate::model::Model,
    input: &FitInput,
    given: &[Option<f64>],
    stop: Option<&Stop>,
) -> Vec<(f64, Vec<f64>)> {
    let stopped = || stop.is_some_and(Stop::is_requested);
    let layout = &problem.layout;
    // Where a search without any usable grid point starts: 1, amplitudes at their unit
    // (the data's scale).
    let ones: Vec<f64> = (0..layout.len())
        .map(|k| given[k].unwrap_or(layout.params[k].transform.unit()))
        .collect();
    let fallback = || vec![(f64::INFINITY, ones.clone())];
    let specs = problem.model.params();
    // Evenly spaced subsample.
    let is_kbs = specs.iter().any(|s| s.name == "sigma");
    let grid_samples = if is_kbs {
        GRID_SAMPLES
    } else {
        CHEAP_MODEL_SAMPLES
    };
    let sub_input = input.subset(&subsample(problem.len(), grid_samples));
    let sub = on_subsample(grid_model, problem, &sub_input);
    let grid = Grid::new(layout, specs, given, input, &sub_input);
    // The model side of every grid point depends only on the layout (angles, model, axes),
    // not on the data: computed once per layout and shared by every fit of it.
    let mut key = grid_cache::Key::new(
        grid_model.name(),
        &sub_input.geo,
        &sub_input.channel,
        &grid.axes,
    );
    key.push(given.iter().map(|g| g.map_or(u64::MAX, f64::to_bits)));
    key.push(grid.linear.iter().chain(&grid.nonlinear).map(|&k| k as u64));
    key.push([layout.len() as u64, problem.layout.index.len() as u64]);
    key.push(options_bits(grid_model));
    let basis = grid_cache::basis(key, || {
        model_side(&grid, grid_model, problem, &sub, &sub_input, is_kbs, stop)
    });
    let Some(basis) = basis else {
        return fallback();
    };
    // The data side of the amplitude solves, once for every grid point.
    let prep = Prepared::new(&sub);
    // (cost, parameters, regime band of the point's median g), grid points in parallel.
    let scored: Vec<(f64, Vec<f64>, usize)> = (0..grid.total)
        .into_par_iter()
        .filter_map(|flat| {
            if stopped() {
                return None;
            }
            let (mut p, g) = grid.point(flat);
            let b = basis.points[flat].as_ref()?;
            amplitudes::solve(&sub, b, &prep, &mut p, &grid.linear).map(|c| (c, p, band_of(g)))
        })
        .collect();
    let kbs = grid.sigma_k.zip(layout.find("T").first().copied());
    // The Fresnel index, when searched: candidates at n = 1.5 as for any parameter, then
    // one per other index where the grid fits better.
    let index = layout
        .find("n")
        .first()
        .copied()
        .filter(|&k| given[k].is_none());
    let (primary, others): (Vec<_>, Vec<_>) = match index {
        Some(k) => scored.into_iter().partition(|s| s.1[k] == PRIMARY_INDEX),
        None => (scored, Vec::new()),
    };
    let mut picked = pick_distinct(primary, kbs.filter(|_| is_kbs), &grid.nonlinear);
    if let (Some(k), Some(best)) = (index, picked.first().map(|p| p.0)) {
        picked.extend(other_indices(others, k, best));
    }
    if picked.is_empty() {
        return fallback();
    }
    picked
}

/// The Fresnel index the grid's candidates are picked at (a paint's or glass's).
const PRIMARY_INDEX: f64 = 1.5;

/// Of the grid points at the other indices (`scored`: cost, values, band; the index at
/// layout index `k`), the lowest-cost one of each index whose cost is below `best`, the
/// best candidate's at [`PRIMARY_INDEX`]; lowest cost first.
fn other_indices(scored: Vec<(f64, Vec<f64>, usize)>, k: usize, best: f64) -> Vec<(f64, Vec<f64>)> {
    let mut lowest: Vec<(f64, Vec<f64>)> = Vec::new();
    for (cost, p, _) in scored {
        if cost.is_nan() || cost >= best {
            continue;
        }
        match lowest.iter_mut().find(|(_, q)| q[k] == p[k]) {
            Some(l) if cost < l.0 => *l = (cost, p),
            Some(_) => {}
            None => lowest.push((cost, p)),
        }
    }
    lowest.sort_by(|a, b| a.0.total_cmp(&b.0));
    lowest
}

/// `problem`'s layout, residual kind and floor on `input` (a subsample of its data) with
/// model `m`.
fn on_subsample<'m>(
    m: &'m dyn crate::model::Model,
    problem: &FitProblem,
    input: &FitInput,
) -> FitProblem<'m> {
    FitProblem::new(
        m,
        problem.layout.clone(),
        input,
        problem.kind(),
        problem.floor,
    )
    .expect("subsample is consistent")
}

/// The model side of every point of `grid` on the subsample (`sub` with the grid's model;
/// for KBS, points far into a limit use that limit's approximation), or None when `stop`
/// was requested before every point was computed (an incomplete grid is neither cached nor
/// ranked).
fn model_side(
    grid: &Grid,
    grid_model: &dyn crate::model::Model,
    problem: &FitProblem,
    sub: &FitProblem,
    sub_input: &FitInput,
    is_kbs: bool,
    stop: Option<&Stop>,
) -> Option<grid_cache::GridBasis> {
    use crate::model::{by_name, EvalMode, ModelOptions};
    let stopped = || stop.is_some_and(Stop::is_requested);
    let limit = |mode: EvalMode| {
        let base = grid_model.options().unwrap_or_default();
        let opts = ModelOptions {
            mode,
            fresnel: base.fresnel,
            shadowing: base.shadowing,
            ..ModelOptions::default()
        };
        is_kbs
            .then(|| by_name(grid_model.name(), &opts).ok())
            .flatten()
    };
    let (rough_model, smooth_model) = (limit(EvalMode::Rough), limit(EvalMode::Smooth));
    let sub_rough = rough_model
        .as_deref()
        .map(|m| on_subsample(m, problem, sub_input));
    let sub_smooth = smooth_model
        .as_deref()
        .map(|m| on_subsample(m, problem, sub_input));
    let points = (0..grid.total)
        .into_par_iter()
        .map(|flat| {
            if stopped() {
                return None;
            }
            let (p, g) = grid.point(flat);
            let grid_problem = match (g, &sub_rough, &sub_smooth) {
                (Some(g), Some(r), _) if g > GRID_ROUGH_G => r,
                (Some(g), _, Some(s)) if g <= GRID_ROUGH_G => s,
                _ => sub,
            };
            grid_cache::point_basis(grid_problem, &p, &grid.linear)
        })
        .collect();
    (!stopped()).then_some(grid_cache::GridBasis { points })
}

/// The search grid of a layout: the nonlinear parameters' candidate values (a given value
/// alone), the linear parameters solved at each point, and how a flat index maps to a point.
struct Grid {
    /// Candidate values of each searched (nonlinear) parameter.
    axes: Vec<Vec<f64>>,
    /// Layout indices of the nonlinear parameters, in the order of `axes`.
    nonlinear: Vec<usize>,
    /// Layout indices of the free linear parameters (amplitudes).
    linear: Vec<usize>,
    /// Every parameter at its given value, else 1.
    base: Vec<f64>,
    /// Layout index of σ (KBS) and the median of (c/λ)² over the subsample: g ≈ (2πσ)²
    /// times that.
    sigma_k: Option<usize>,
    c2_lambda: f64,
    /// Number of grid points.
    total: usize,
}

impl Grid {
    fn new(
        layout: &ParamLayout,
        specs: &[crate::model::ParamSpec],
        given: &[Option<f64>],
        input: &FitInput,
        sub_input: &FitInput,
    ) -> Self {
        let lambda = input.geo.wavelength.median();
        let c2_lambda = median(
            &(0..sub_input.geo.len())
                .map(|i| (sub_input.geo.c[i] / sub_input.geo.wavelength[i]).powi(2))
                .collect::<Vec<_>>(),
        );
        let nonlinear: Vec<usize> = (0..layout.len())
            .filter(|&k| !is_linear(layout, k, specs))
            .collect();
        let axes: Vec<Vec<f64>> = nonlinear
            .iter()
            .map(|&k| match given[k] {
                Some(v) => vec![v],
                None => grid_for(specs[layout.params[k].spec].name, lambda),
            })
            .collect();
        let linear = (0..layout.len())
            .filter(|&k| is_linear(layout, k, specs) && given[k].is_none())
            .collect();
        Grid {
            total: axes.iter().map(Vec::len).product(),
            axes,
            nonlinear,
            linear,
            base: (0..layout.len())
                .map(|k| given[k].unwrap_or(layout.params[k].transform.unit()))
                .collect(),
            sigma_k: layout
                .params
                .iter()
                .position(|fp| specs[fp.spec].name == "sigma"),
            c2_lambda,
        }
    }

    /// The grid point of a flat index, and its median g (KBS).
    fn point(&self, flat: usize) -> (Vec<f64>, Option<f64>) {
        let mut p = self.base.clone();
        let mut rem = flat;
        for (axis, &k) in self.axes.iter().zip(&self.nonlinear) {
            p[k] = axis[rem % axis.len()];
            rem /= axis.len();
        }
        let g = self
            .sigma_k
            .map(|k| (2.0 * std::f64::consts::PI * p[k]).powi(2) * self.c2_lambda);
        (p, g)
    }
}

/// The regime band of a grid point's median g: 0 smooth (or no g), 1 intermediate, 2 rough.
fn band_of(g: Option<f64>) -> usize {
    match g {
        Some(g) if g < SMOOTH_BAND_G => 0,
        Some(g) if g <= ROUGH_BAND_G => 1,
        Some(_) => 2,
        None => 0,
    }
}

/// The candidates from the scored grid points (cost, values, band): the grid ranks with
/// the limits' approximations, which can favour a wrong regime (the rough asymptote σ → ∞
/// at fixed T/σ is a valley of its own), so for KBS (`kbs`: layout indices of σ and T) the
/// best points of each regime band (smooth, intermediate, rough) are kept: the band's best
/// and its best of a lobe at least [`SHAPE_APART`] wider or narrower ([`lobe_shape`]: two
/// lobes of one paint, Cornell acryl_blue 460 nm, a wide one the subsample favours and a
/// narrow near-mirror one 6 % lower on the whole data). Otherwise the best points at least
/// a factor e^{0.7} ≈ 2 apart in some nonlinear parameter. At most [`CANDIDATES`] (KBS:
/// [`KBS_CANDIDATES`]), best first.
fn pick_distinct(
    mut scored: Vec<(f64, Vec<f64>, usize)>,
    kbs: Option<(usize, usize)>,
    nonlinear: &[usize],
) -> Vec<(f64, Vec<f64>)> {
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut picked: Vec<(f64, Vec<f64>, usize)> = Vec::new();
    let most = if kbs.is_some() {
        KBS_CANDIDATES
    } else {
        CANDIDATES
    };
    let best = scored.first().map_or(f64::INFINITY, |s| s.0);
    for (cost, p, band) in scored {
        let distinct = match kbs {
            Some(ks) => {
                let same_band: Vec<_> = picked.iter().filter(|q| q.2 == band).collect();
                let shape = lobe_shape(&p, ks, band);
                let apart = |q: &&(f64, Vec<f64>, usize)| {
                    let other = lobe_shape(&q.1, ks, band);
                    (0..2).any(|d| (shape[d] - other[d]).abs() > SHAPE_APART.ln())
                };
                (same_band.is_empty() || cost <= best * (1.0 + SECOND_MARGIN))
                    && same_band.len() < PER_BAND
                    && same_band.iter().all(apart)
            }
            None => picked.iter().all(|(_, q, _)| {
                nonlinear.iter().any(|&k| {
                    (p[k].abs().max(1e-300).ln() - q[k].abs().max(1e-300).ln()).abs() > 0.7
                })
            }),
        };
        if distinct {
            picked.push((cost, p, band));
            if picked.len() == most {
                break;
            }
        }
    }
    picked.into_iter().map(|(c, p, _)| (c, p)).collect()
}

/// Grid candidates kept per regime band for KBS models (see `pick_distinct`).
pub(crate) const PER_BAND: usize = 2;

/// Relative grid cost above the grid's best within which a band's second lobe is kept: a
/// lobe the grid ranks far worse than the best point is no rival on the whole data either
/// (the second lobes that win on the whole data for Cornell acryl_blue, tests/trust/corpus.rs, are
/// kept at this margin; it keeps the texel batch's throughput, benches/texels.sh).
pub(crate) const SECOND_MARGIN: f64 = 0.25;

/// Most KBS candidates: [`PER_BAND`] in each of the three regime bands.
pub(crate) const KBS_CANDIDATES: usize = 3 * PER_BAND;

/// Factor by which the lobe shape of two candidates of one band must differ to count as
/// two valleys: the grid's T axis steps by ≈ 2.1, so neighbours of one valley are closer.
pub(crate) const SHAPE_APART: f64 = 3.0;

/// The logarithms of what sets a KBS lobe's shape in a regime band (σ, T at layout indices
/// `ks`): T/σ in the rough band (the rough limit depends on σ and T only through it), T in
/// the smooth band (its limit's lobe width), both σ and T in between (unused entries 0).
fn lobe_shape(p: &[f64], (s, t): (usize, usize), band: usize) -> [f64; 2] {
    let (ls, lt) = (p[s].abs().max(1e-300).ln(), p[t].abs().max(1e-300).ln());
    match band {
        2 => [lt - ls, 0.0],
        0 => [lt, 0.0],
        _ => [ls, lt],
    }
}

/// The bits of a model's evaluation options (mode, tolerance, patch), for cache keys.
fn options_bits(model: &dyn crate::model::Model) -> Vec<u64> {
    match model.options() {
        None => vec![0],
        Some(o) => {
            let (x, y) = o.patch.unwrap_or((0.0, 0.0));
            vec![1, o.mode as u64, o.tol.to_bits(), x.to_bits(), y.to_bits()]
        }
    }
}

/// The start search's sample of `input` (at most `max` samples): the
/// [`NEAR_SPECULAR_SAMPLES`] samples nearest the mirror direction (smallest v_xy²/v_z², the
/// facet slope that reflects into them) and a [`subsample`] spread over the file. A narrow
/// lobe lives on a few samples near the mirror direction only, which a spread subsample can
/// miss altogether (Cornell acryl_blue 460 nm: a near-mirror lobe of rms slope 0.008 is 6 %
/// lower on the whole data than the wide lobe the spread sample sees). The sample is
/// stratified so that its cost stays an estimate of the whole data's (up to a constant
/// factor): each near-mirror sample stands for itself, each spread one for its share of the
/// rest, so the near-mirror ones carry weight m/(n − k) (k of them, m spread samples among
/// the other n − k). Depends on the angles only, so every fit of one angular layout draws
/// the same samples.
pub(crate) fn search_input(input: &FitInput, max: usize) -> FitInput {
    let geo = &input.geo;
    let n = geo.len();
    let near = NEAR_SPECULAR_SAMPLES.min(max / 4);
    if n <= max || near == 0 {
        return input.subset(&subsample(n, max));
    }
    let slope2 = |i: usize| geo.vxy2[i] / (geo.c[i] * geo.c[i]).max(f64::MIN_POSITIVE);
    let mut order: Vec<usize> = (0..n).collect();
    order.select_nth_unstable_by(near - 1, |&a, &b| slope2(a).total_cmp(&slope2(b)));
    let mut is_near = vec![false; n];
    order[..near].iter().for_each(|&i| is_near[i] = true);
    let spread = subsample(n, max - near);
    let m = spread.iter().filter(|&&i| !is_near[i]).count();
    let mut idx: Vec<usize> = order[..near].to_vec();
    idx.extend(spread);
    idx.sort_unstable();
    idx.dedup();
    let mut sub = input.subset(&idx);
    let share = m as f64 / (n - near) as f64;
    let weight = &sub.weight;
    sub.weight = (0..idx.len())
        .map(|j| weight[j] * if is_near[idx[j]] { share } else { 1.0 })
        .collect();
    sub
}

/// At most `max` of `n` sample indices, spread over the whole file: the multiples of a
/// step near n(√5 − 1)/2 that is coprime to n, modulo n, sorted. A scan stored in nested
/// loops (θi × θr × φr) is then covered in every loop; a plain stride aliases with the
/// inner loops (a stride of 20 through 40 azimuths picks only two of them).
pub(crate) fn subsample(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        return (0..n).collect();
    }
    fn gcd(a: usize, b: usize) -> usize {
        if b == 0 {
            a
        } else {
            gcd(b, a % b)
        }
    }
    let mut step = ((n as f64) * 0.618_033_988_749_894_9).round() as usize;
    while gcd(step, n) != 1 {
        step += 1;
    }
    let mut idx: Vec<usize> = (0..max)
        .map(|k| ((k as u128 * step as u128) % n as u128) as usize)
        .collect();
    idx.sort_unstable();
    idx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subsample_covers_every_loop_of_a_scan() {
        assert_eq!(subsample(3, 10), vec![0, 1, 2]);
        // A 10 θi × 25 θr × 40 φr scan stored φ fastest: 512 of its 10 000 samples.
        let idx = subsample(10_000, 512);
        assert_eq!(idx.len(), 512);
        assert!(idx.windows(2).all(|w| w[0] < w[1]), "sorted and distinct");
        let covered = |f: &dyn Fn(usize) -> usize, k: usize| {
            let mut seen = vec![false; k];
            for &i in &idx {
                seen[f(i)] = true;
            }
            seen.iter().all(|&s| s)
        };
        assert!(covered(&|i| i % 40, 40), "every azimuth");
        assert!(covered(&|i| (i / 40) % 25, 25), "every θr");
        assert!(covered(&|i| i / 1000, 10), "every θi");
    }
}
