//! Profile-likelihood confidence intervals, as lmfit's `conf_interval`.
//!
//! For a scalar ψ of the parameters (one parameter, or a product Π p_j^{c_j} such as T/σ or
//! the lobe amplitude s(T/σ)²), ψ is held at a trial value t and every other free parameter
//! is refitted; the profile χ²(t) is the best χ² at that t. The interval at probability P
//! is where χ²(t) − χ²_min stays below
//! - s² · t²_{(1+P)/2, n−p} (s² = χ²_min/(n − p): the F-test lmfit uses, F(1, n−p) = t²),
//!   which for a model linear in ψ gives exactly ψ̂ ± t·(standard error); or
//! - z²_{(1+P)/2} when the weights are true inverse variances (`absolute`: scipy's
//!   `absolute_sigma=True`).
//!
//! The search, per side: the first refit is where the linearisation's quadratic profile
//! s²(Δt/se)² reaches the 68 % threshold; each next one where √Δχ², taken as linear in t
//! through the last two points, reaches the next threshold (at most 4× as far per step),
//! so that where the profile is nearly quadratic the walk points are the crossings
//! already. A crossing not yet met to [`CROSS_TOL`] is found in its bracket by inverse
//! quadratic interpolation on √Δχ², bisecting where that stalls. Every refit is
//! warm-started where the points so far predict the other parameters (linear through the
//! two nearest points; along the covariance's conditional direction Cg/gᵀCg for the first).
//! The sides run on two threads when there are two.
//!
//! Where the profile stays below a threshold out to the search limit (a factor
//! [`LOG_RANGE`] for positive parameters), or to where the refits reach the model's
//! domain edge (g or a past half the fit's limit, where Δχ² rises because the model can go
//! no further), that side is *open*: the data bounds ψ on one side only ("σ > 180 nm at
//! 95 %"). For an amplitude whose profile stays low down to 0, the bound is the domain
//! edge 0.
//!
//! Accuracy: each end meets |√Δχ² − √threshold| ≤ [`CROSS_TOL`]·√threshold, which for a
//! profile quadratic near the end puts it within 0.1 % of its distance from the estimate;
//! each refit runs to a relative cost change that keeps the error of Δχ² a tenth of that.

use super::restricted::{dlnp_dx, Restricted};
use crate::fit::problem::{FitProblem, Transform};
use goniofit_lm as lm;
use goniofit_lm::{LeastSquaresProblem, LmConfig};
use nalgebra::{DMatrix, DVector};

pub(crate) use super::quantile::{normal_quantile, student_t_quantile};

/// The probabilities of the reported intervals: one standard deviation (68.27 %) and 95 %.
pub(crate) const LEVELS: [f64; 2] = [0.682_689_492_137_086, 0.95];

/// How far a positive parameter is searched: a factor e^LOG_RANGE (10³) either way.
pub(crate) const LOG_RANGE: f64 = 6.907_755_278_982_137;

/// Maximum number of doubling steps on one side.
const MAX_STEPS: usize = 24;

/// Refinements per crossing (secant steps, bisections where they stall).
const REFINE_STEPS: usize = 12;

/// Accuracy of a crossing: |√Δχ²(t) − √th| ≤ CROSS_TOL·√th. Where the profile is
/// quadratic near the crossing, this puts the end within CROSS_TOL of its distance from
/// the estimate.
pub const CROSS_TOL: f64 = 1e-3;

/// Problems of at most this many samples profile the two sides of an interval on two
/// threads; larger ones (whose evaluations are parallel over sample blocks) one side at a
/// time, which halves the memory the intervals hold at once.
const SIDES_IN_PARALLEL_MAX_ROWS: usize = 16_384;

/// One end of an interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// The profile crosses the threshold here.
    At(f64),
    /// The interval reaches the parameter's domain edge (0 for an amplitude).
    Edge(f64),
    /// The profile stays below the threshold out to this value (the search limit, or where
    /// the model leaves its domain): the data sets no bound on this side.
    Open(f64),
}

impl Bound {
    /// The bound as a number, None when open.
    pub fn value(self) -> Option<f64> {
        match self {
            Bound::At(v) | Bound::Edge(v) => Some(v),
            Bound::Open(_) => None,
        }
    }
}

/// An interval at one probability.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Level {
    /// The probability P of the interval (one of [`LEVELS`]).
    pub prob: f64,
    /// The lower end.
    pub lo: Bound,
    /// The upper end.
    pub hi: Bound,
}

/// The profile intervals of one quantity.
#[derive(Debug, Clone, PartialEq)]
pub struct Interval {
    /// The quantity's report name (a parameter's layout name, `T/sigma`, `amplitude`, …).
    pub name: String,
    /// The best-fit value.
    pub value: f64,
    /// One entry per [`LEVELS`] probability.
    pub levels: Vec<Level>,
}

impl Interval {
    /// The interval at probability `prob` (one of [`LEVELS`]).
    pub fn at(&self, prob: f64) -> Option<&Level> {
        self.levels.iter().find(|l| (l.prob - prob).abs() < 1e-9)
    }

    /// The same interval for `factor · ψ` (`factor` > 0), or for `factor / ψ` with
    /// `invert` (the sides swap); used for Beckmann's α = 2σ/T from T/σ and π·s from s.
    pub fn mapped(&self, name: &str, factor: f64, invert: bool) -> Interval {
        let f = |b: Bound| {
            let g = |v: f64| if invert { factor / v } else { factor * v };
            match b {
                Bound::At(v) => Bound::At(g(v)),
                Bound::Edge(v) => Bound::Edge(g(v)),
                Bound::Open(v) => Bound::Open(g(v)),
            }
        };
        Interval {
            name: name.to_string(),
            value: if invert {
                factor / self.value
            } else {
                factor * self.value
            },
            levels: self
                .levels
                .iter()
                .map(|l| {
                    let (lo, hi) = if invert { (l.hi, l.lo) } else { (l.lo, l.hi) };
                    Level {
                        prob: l.prob,
                        lo: f(lo),
                        hi: f(hi),
                    }
                })
                .collect(),
        }
    }
}

/// What is profiled: a parameter by its layout index, or ln Π p_j^{c_j} over layout
/// indices, solved for `eliminate` (a log-transformed free parameter with c ≠ 0).
#[derive(Debug, Clone)]
pub(crate) enum Target {
    /// The free parameter at this layout index, searched in its fit variable x (ln p where
    /// log-transformed).
    Param(usize),
    /// ψ = Π p_j^{c_j}, profiled through ln ψ.
    Product {
        /// The pairs (layout index j, exponent c_j) of the product.
        coef: Vec<(usize, f64)>,
        /// The layout index of the log-transformed free parameter solved for to hold ψ at its trial
        /// value (its exponent must be non-zero).
        eliminate: usize,
    },
}

/// The threshold of Δχ² for probability `prob`: see the module doc.
pub fn threshold(prob: f64, chi2_min: f64, dof: usize, absolute: bool) -> f64 {
    let q = 0.5 * (1.0 + prob);
    if absolute {
        normal_quantile(q).powi(2)
    } else {
        let s2 = chi2_min / dof.max(1) as f64;
        s2 * student_t_quantile(q, dof.max(1) as f64).powi(2)
    }
}

/// A search limit in t, and whether it is the parameter's domain edge.
type Limit = (f64, bool);

/// The profile of one target over a full problem whose best fit is `p_best`.
pub(crate) struct Profiler<'a, 'p> {
    /// The full problem (every free parameter) the refits minimise.
    pub problem: &'a FitProblem<'p>,
    /// Best-fit parameters (layout order) of `problem`.
    pub p_best: Vec<f64>,
    /// χ² at `p_best`.
    pub chi2_min: f64,
    /// Covariance of the free x at the optimum, s²(JᵀJ)⁺.
    pub x_cov: DMatrix<f64>,
    /// Whether the weights are true inverse variances: thresholds z² instead of s²·t².
    pub absolute: bool,
    /// The solver settings of every refit, with ftol tightened so that the error of Δχ² stays
    /// a tenth of the crossing tolerance [`CROSS_TOL`].
    pub lm: LmConfig,
}

impl<'a, 'p> Profiler<'a, 'p> {
    /// Set up at `p_best` (the optimum of `problem`): χ² and the x-space standard errors
    /// from the Jacobian there.
    pub(crate) fn new(
        problem: &'a FitProblem<'p>,
        p_best: &[f64],
        absolute: bool,
        lm: &LmConfig,
    ) -> Self {
        let x = problem.layout.to_x(p_best);
        let (r, j) = problem.residuals_and_gram_factor(&x);
        let chi2_min = r.norm_squared();
        let unc = super::covariance::uncertainty(&j, 0.5 * chi2_min, problem.len(), 1e-9);
        let dof = problem.len().saturating_sub(x.len());
        // Each refit to the relative cost change that keeps the error of Δχ² below a tenth
        // of what CROSS_TOL allows at the smallest threshold (never looser than 1e-6).
        let th = threshold(LEVELS[0], chi2_min, dof, absolute);
        let ftol = (0.1 * CROSS_TOL * th / chi2_min).min(1e-6).max(lm.ftol);
        Profiler {
            problem,
            p_best: p_best.to_vec(),
            chi2_min,
            x_cov: unc.covariance,
            absolute,
            lm: LmConfig {
                progress: false,
                max_iters: 200,
                ftol: if ftol.is_finite() { ftol } else { lm.ftol },
                ..lm.clone()
            },
        }
    }

    fn dof(&self) -> usize {
        self.problem
            .len()
            .saturating_sub(self.problem.layout.free().len())
    }

    /// The restricted problem for `target` at t, and z at `x` (the full free x).
    fn restricted(&self, target: &Target, t: f64) -> Option<Restricted<'a, 'p>> {
        let layout = &self.problem.layout;
        let free = layout.free();
        let pos = |k: usize| free.iter().position(|&f| f == k);
        let transforms: Vec<Transform> = free.iter().map(|&k| layout.params[k].transform).collect();
        let (held, others, c_held) = match target {
            Target::Param(k) => (pos(*k)?, Vec::new(), 0.0),
            Target::Product { coef, eliminate } => {
                let held = pos(*eliminate)?;
                if transforms[held] != Transform::Log {
                    return None;
                }
                let c_held = coef.iter().find(|(k, _)| k == eliminate)?.1;
                let mut others = Vec::new();
                for &(k, c) in coef {
                    if k != *eliminate {
                        // A fixed factor enters as a constant through t.
                        if let Some(i) = pos(k) {
                            others.push((i, c));
                        }
                    }
                }
                (held, others, c_held)
            }
        };
        Some(Restricted::new(
            self.problem,
            (held, others, c_held),
            t,
            transforms,
            self.lm.stop.clone(),
        ))
    }

    /// The gradient g of t (the search variable of `target`) with respect to the free x at
    /// the optimum, and t there: e_i for a parameter, c_j d ln p_j/dx_j for a product.
    fn gradient(&self, target: &Target) -> Option<(f64, DVector<f64>)> {
        let layout = &self.problem.layout;
        let free = layout.free();
        let x = layout.to_x(&self.p_best);
        let mut g = DVector::zeros(free.len());
        match target {
            Target::Param(k) => {
                let i = free.iter().position(|f| f == k)?;
                g[i] = 1.0;
                Some((x[i], g))
            }
            Target::Product { coef, .. } => {
                let mut t0 = 0.0;
                for &(k, c) in coef {
                    t0 += c * self.p_best[k].ln();
                    if let Some(i) = free.iter().position(|&f| f == k) {
                        g[i] = c * dlnp_dx(layout.params[k].transform, x[i])?;
                    }
                }
                Some((t0, g))
            }
        }
    }

    /// ψ at the best fit (as t), the linearised standard error of t (gᵀCg; it sets the
    /// first step only), and the search limits (lo, hi, whether each is the domain edge).
    fn start(&self, target: &Target) -> Option<(f64, f64, Limit, Limit)> {
        let (t0, g) = self.gradient(target)?;
        let se = (g.transpose() * &self.x_cov * &g)[(0, 0)].max(0.0).sqrt();
        let (lo, hi) = match target {
            Target::Param(k) => match self.problem.layout.params[*k].transform {
                Transform::Log | Transform::LogAbove { .. } => {
                    ((t0 - LOG_RANGE, false), (t0 + LOG_RANGE, false))
                }
                tr @ Transform::NonNegative { .. } => {
                    let top = tr.to_x(1e3 * tr.from_x(t0) + 1e3 * se.min(1e300));
                    ((0.0, true), (top.max(t0 + 1.0), false))
                }
                Transform::Identity => {
                    let w = 1e3 * t0.abs().max(if se.is_finite() { se } else { 1.0 });
                    ((t0 - w, false), (t0 + w, false))
                }
            },
            Target::Product { .. } => ((t0 - LOG_RANGE, false), (t0 + LOG_RANGE, false)),
        };
        Some((t0, se, lo, hi))
    }

    /// dz/dt along the linearised profile path: the other free x follow t as their
    /// conditional mean does, dx/dt = Cg / (gᵀCg), without the held component. None where
    /// the covariance gives no finite direction. Used only to warm-start the first refit.
    fn path_slope(&self, target: &Target, held: usize) -> Option<DVector<f64>> {
        let (_, g) = self.gradient(target)?;
        let cg = &self.x_cov * &g;
        let v = g.dot(&cg);
        if !(v > 0.0 && v.is_finite() && cg.iter().all(|c| c.is_finite())) {
            return None;
        }
        Some(DVector::from_iterator(
            cg.len() - 1,
            (0..cg.len()).filter(|&i| i != held).map(|i| cg[i] / v),
        ))
    }

    /// The profile χ² at t, refitting from z0; returns (χ², z) or None when the fit
    /// cannot be evaluated there.
    fn solve(&self, target: &Target, t: f64, z0: &DVector<f64>) -> Option<(f64, DVector<f64>)> {
        let prob = self.restricted(target, t)?;
        if z0.is_empty() {
            let r = prob.residuals(z0);
            let c = r.norm_squared();
            return c.is_finite().then(|| (c, z0.clone()));
        }
        let mut rep = lm::minimize(&prob, z0.clone(), &self.lm);
        // The refit's last residuals serve the next refit's evaluations.
        prob.recycle(std::mem::replace(&mut rep.residuals, DVector::zeros(0)));
        let chi2 = 2.0 * rep.cost;
        chi2.is_finite().then_some((chi2, rep.x))
    }

    /// The profile point at t: the refit warm-started where the points already computed
    /// predict z (linear through the two nearest, or along `slope` from the estimate; from
    /// the estimate's z if that first start fails). None where the refit cannot be
    /// evaluated, or the predicted path leaves the model's domain: refitting from farther
    /// away against the domain edge costs many evaluations at large g and tells nothing
    /// about the data.
    fn point(&self, walk: &Walk, t: f64) -> Option<Point> {
        let mut near: Vec<&Point> = walk.pts.iter().collect();
        near.sort_by(|a, b| (a.t - t).abs().total_cmp(&(b.t - t).abs()));
        let p = near[0];
        let guess = match (near.get(1), walk.slope.as_ref()) {
            (Some(q), _) if q.t != p.t => &p.z + (&q.z - &p.z) * ((t - p.t) / (q.t - p.t)),
            (_, Some(s)) => &p.z + s * (t - p.t),
            _ => p.z.clone(),
        };
        let first = walk.pts.len() == 1;
        let (chi2, z) = self
            .solve(walk.target, t, &guess)
            .or_else(|| first.then(|| self.solve(walk.target, t, &p.z)).flatten())?;
        Some(Point {
            t,
            delta: (chi2 - self.chi2_min).max(0.0),
            z,
        })
    }

    /// z at the best fit (the free x without the held one), and the held position.
    fn z_best(&self, target: &Target) -> Option<(DVector<f64>, usize)> {
        let prob = self.restricted(target, 0.0)?;
        let x = self.problem.layout.to_x(&self.p_best);
        let z = DVector::from_iterator(
            x.len() - 1,
            (0..x.len()).filter(|&i| i != prob.held).map(|i| x[i]),
        );
        Some((z, prob.held))
    }

    /// The intervals of `target` at every [`LEVELS`] probability, in the variable t
    /// (x of a parameter, ln ψ of a product), mapped back to ψ.
    pub(crate) fn interval(&self, name: &str, target: &Target) -> Option<Interval> {
        let (t0, se, lo_lim, hi_lim) = self.start(target)?;
        let (z0, held) = self.z_best(target)?;
        let thr: Vec<f64> = LEVELS
            .iter()
            .map(|&p| threshold(p, self.chi2_min, self.dof(), self.absolute))
            .collect();
        // First trial: where the quadratic profile of the linearisation, Δχ² = s²(Δt/se)²,
        // reaches the smallest threshold.
        let s2 = self.chi2_min / self.dof().max(1) as f64;
        let span = (hi_lim.0 - lo_lim.0).abs();
        let first = se * (thr[0] / s2).sqrt();
        let first = if first.is_finite() && first > 0.0 {
            first.clamp(1e-9 * span.max(1e-300), 0.1 * span)
        } else {
            0.05 * span.min(2.0 * LOG_RANGE)
        };
        let slope = self.path_slope(target, held);
        // The two sides are independent searches: on two threads for a small problem. A
        // large one's model evaluation is already parallel over sample blocks, and two
        // concurrent solves would hold two sets of residuals and Jacobians (the peak memory
        // of a big fit), so its sides run one after the other.
        let side = |dir: f64, lim: Limit| {
            let mut walk = Walk {
                target,
                t0,
                dir,
                slope: slope.clone(),
                pts: vec![Point {
                    t: t0,
                    delta: 0.0,
                    z: z0.clone(),
                }],
            };
            self.side(&mut walk, first, lim, &thr)
        };
        let (lo, hi) = if self.problem.len() <= SIDES_IN_PARALLEL_MAX_ROWS {
            rayon::join(|| side(-1.0, lo_lim), || side(1.0, hi_lim))
        } else {
            (side(-1.0, lo_lim), side(1.0, hi_lim))
        };
        let sides = [lo, hi];
        let value_of = |t: f64| self.value_of(target, t);
        let map = |b: Bound| match b {
            Bound::At(t) => Bound::At(value_of(t)),
            Bound::Edge(t) => Bound::Edge(value_of(t)),
            Bound::Open(t) => Bound::Open(value_of(t)),
        };
        let levels = LEVELS
            .iter()
            .enumerate()
            .map(|(l, &prob)| Level {
                prob,
                lo: map(sides[0][l]),
                hi: map(sides[1][l]),
            })
            .collect();
        Some(Interval {
            name: name.to_string(),
            value: value_of(t0),
            levels,
        })
    }

    /// ψ from the search variable t.
    fn value_of(&self, target: &Target, t: f64) -> f64 {
        match target {
            Target::Param(k) => self.problem.layout.params[*k].transform.from_x(t),
            Target::Product { .. } => t.exp(),
        }
    }

    /// One side of the profile: the crossing of every threshold `thr` (ascending). Walks
    /// from the estimate to `first`, then to where √Δχ², taken as linear in t through the
    /// last two points, reaches the smallest threshold not yet reached (at most 4× as far
    /// per step), until Δχ² reaches the largest or the limit `lim` (value, whether it is
    /// the domain edge); then finds each crossing (most are walk points already).
    fn side(&self, walk: &mut Walk, first: f64, lim: Limit, thr: &[f64]) -> Vec<Bound> {
        let reached = |d: f64, th: f64| d.sqrt() >= th.sqrt() * (1.0 - CROSS_TOL);
        let mut dist = first;
        let mut end = Bound::Open(walk.t0);
        let mut retries = 0;
        for _ in 0..MAX_STEPS {
            let mut t = walk.t0 + walk.dir * dist;
            let at_limit = (t - lim.0) * walk.dir >= 0.0;
            if at_limit {
                t = lim.0;
            }
            let Some(p) = self.point(walk, t) else {
                // A step too long for the predicted path: halve it towards the last point
                // (three times at most) before the side ends open there.
                let last = (walk.pts[walk.pts.len() - 1].t - walk.t0).abs();
                retries += 1;
                if retries > 3 || walk.pts.len() == 1 {
                    break;
                }
                dist = 0.5 * (last + (t - walk.t0).abs());
                continue;
            };
            let delta = p.delta;
            let edge = self.at_domain_edge(walk.target, &p);
            walk.insert(p);
            let Some(&next) = thr.iter().find(|&&th| !reached(delta, th)) else {
                break;
            };
            if edge {
                // Going on would only refit against the domain edge (costly at large g).
                end = Bound::Open(t);
                break;
            }
            end = match at_limit {
                true if lim.1 => Bound::Edge(t),
                _ => Bound::Open(t),
            };
            if at_limit {
                break;
            }
            let n = walk.pts.len();
            let (a, b) = (&walk.pts[n - 2], &walk.pts[n - 1]);
            let (da, db) = ((a.t - walk.t0).abs(), (b.t - walk.t0).abs());
            let slope = (b.delta.sqrt() - a.delta.sqrt()) / (db - da);
            let aim = if slope > 0.0 {
                db + (next.sqrt() - b.delta.sqrt()) / slope
            } else {
                f64::INFINITY
            };
            dist = aim.clamp(db * (1.0 + CROSS_TOL), 4.0 * db);
        }
        thr.iter()
            .map(|&th| self.crossing(walk, th).unwrap_or(end))
            .collect()
    }

    /// The bound where Δχ² = th, to [`CROSS_TOL`] in √Δχ²: a computed point already there,
    /// or the root in the first bracket of the walk by secant steps on √Δχ² (nearly linear
    /// in t near a smooth minimum), bisecting where a secant step leaves the bracket or two
    /// steps do not halve it. A profile that jumps over th (the refits cannot follow it
    /// across the model's domain edge: the bracket shrinks below 1 % of its distance with
    /// Δχ² still above 4 th on its far side) is open up to the jump. None when no point
    /// reaches th.
    fn crossing(&self, walk: &mut Walk, th: f64) -> Option<Bound> {
        let g = |d: f64| d.sqrt() - th.sqrt();
        let tol = CROSS_TOL * th.sqrt();
        let i = walk.pts.iter().position(|p| g(p.delta) >= -tol)?;
        if g(walk.pts[i].delta).abs() <= tol || i == 0 {
            return Some(self.bound_at(walk, walk.pts[i].t));
        }
        let (mut ta, mut fa) = (walk.pts[i - 1].t, g(walk.pts[i - 1].delta));
        let (mut tb, mut fb) = (walk.pts[i].t, g(walk.pts[i].delta));
        let mut widths = vec![(tb - ta).abs()];
        for step in 0..REFINE_STEPS {
            let s = interpolate(&walk.pts, g);
            let inside = (s - ta) * (s - tb) < 0.0;
            let halving = step < 2 || widths[step] <= 0.5 * widths[step - 2];
            let t = if inside && halving {
                s
            } else {
                0.5 * (ta + tb)
            };
            let Some(p) = self.point(walk, t) else {
                break;
            };
            let ft = g(p.delta);
            walk.insert(p);
            if ft.abs() <= tol {
                return Some(self.bound_at(walk, t));
            }
            if ft < 0.0 {
                (ta, fa) = (t, ft);
            } else {
                (tb, fb) = (t, ft);
            }
            widths.push((tb - ta).abs());
        }
        let jump = fb > th.sqrt() && (tb - ta).abs() < 1e-2 * (tb - walk.t0).abs();
        Some(if jump {
            Bound::Open(ta)
        } else if fb < -fa {
            self.bound_at(walk, tb)
        } else {
            self.bound_at(walk, ta)
        })
    }

    /// The crossing at t (a computed point of `walk`), or open there when its refit lies
    /// at the edge of the model's domain (g or a past half its fit limit,
    /// [`FitProblem::domain_fraction`]): Δχ² then rises because the model can go no
    /// further, not because the data bounds ψ.
    fn bound_at(&self, walk: &Walk, t: f64) -> Bound {
        let edge = walk.pts.iter().find(|p| p.t == t);
        if edge.is_some_and(|p| self.at_domain_edge(walk.target, p)) {
            Bound::Open(t)
        } else {
            Bound::At(t)
        }
    }

    /// Whether the refit of a profile point lies past half the fit's limits of g or a.
    fn at_domain_edge(&self, target: &Target, p: &Point) -> bool {
        self.restricted(target, p.t)
            .and_then(|prob| prob.full_x(&p.z))
            .is_some_and(|(x, _)| {
                self.problem
                    .domain_fraction(&self.problem.layout.from_x(&x))
                    > 0.5
            })
    }
}

/// The t where g(Δχ²) = 0 as the points nearest it (by |g|) predict: inverse quadratic
/// interpolation through three of them, a secant through two when the g values coincide
/// (NaN when no two differ).
fn interpolate(pts: &[Point], g: impl Fn(f64) -> f64) -> f64 {
    let mut near: Vec<(f64, f64)> = pts.iter().map(|p| (g(p.delta), p.t)).collect();
    near.sort_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
    near.dedup_by(|a, b| a.0 == b.0);
    match near[..] {
        [(fa, ta), (fb, tb), (fc, tc), ..] => {
            ta * fb * fc / ((fa - fb) * (fa - fc))
                + tb * fa * fc / ((fb - fa) * (fb - fc))
                + tc * fa * fb / ((fc - fa) * (fc - fb))
        }
        [(fa, ta), (fb, tb)] => tb - fb * (tb - ta) / (fb - fa),
        _ => f64::NAN,
    }
}

/// A computed point of a profile: t, Δχ² = χ²(t) − χ²_min (≥ 0) and the refitted z.
#[derive(Debug, Clone)]
struct Point {
    t: f64,
    delta: f64,
    z: DVector<f64>,
}

/// One side of a profile being searched: the points so far, ordered by distance from the
/// estimate t0 (the first is t0 itself).
struct Walk<'t> {
    target: &'t Target,
    t0: f64,
    /// −1 for the lower side, +1 for the upper.
    dir: f64,
    /// dz/dt at the estimate, see [`Profiler::path_slope`].
    slope: Option<DVector<f64>>,
    pts: Vec<Point>,
}

impl Walk<'_> {
    /// Add a point, keeping the order by distance from t0.
    fn insert(&mut self, p: Point) {
        let d = (p.t - self.t0) * self.dir;
        let at = self
            .pts
            .iter()
            .position(|q| (q.t - self.t0) * self.dir > d)
            .unwrap_or(self.pts.len());
        self.pts.insert(at, p);
    }
}
