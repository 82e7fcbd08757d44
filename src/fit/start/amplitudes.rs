//! The linear amplitudes at a grid point (variable projection): with the nonlinear
//! parameters held, the model is f = rest + Σ_c p_c · column_c, and the amplitudes p_c ≥ 0
//! (scales, lobe strengths) that fit the data best are solved for without evaluating the
//! model again.
//!
//! - Absolute and relative residuals are linear in p: a non-negative least-squares solve
//!   ([`nnls`], active set) is exact.
//! - Log residuals are not: their linearisation around the data weights each sample by
//!   1/max(|y|, floor), so a handful of values at the floor (zeros, dark grazing samples) can
//!   outweigh the whole lobe and drive an amplitude to its bound (Cornell krylon_blue 640 nm:
//!   the lobe's scale came out 1e-7 of its fitted value, and the start search then ran to
//!   T → 0; CUReT sample 4: every grid point's lobe amplitude at the bound, so the grid
//!   could not rank them). The linearised solve only starts a damped Gauss–Newton run on
//!   the log residual itself, in ln p_c ([`LOG_ITERS`] steps at most).

use super::grid_cache::PointBasis;
use crate::fit::problem::{FitProblem, ResidualKind};
use nalgebra::{DMatrix, DVector};

/// Iterations of the Gauss–Newton refinement of log-residual amplitudes: the grid only ranks
/// its points (the solver refines the winners), so a few steps that bring the amplitudes
/// near their optimum are enough, and they bound the work at a grid point.
pub(crate) const LOG_ITERS: usize = 10;

/// Most sweeps of the SVD in [`nnls`] (a few unknowns converge in a handful; the bound only
/// turns a matrix the SVD cannot handle into "no amplitudes" instead of an endless loop).
pub(crate) const SVD_MAX_ITERS: usize = 1000;

/// Relative cost reduction below which the log-residual refinement stops.
pub(crate) const LOG_FTOL: f64 = 1e-6;

/// What the amplitude solves need of a problem's data besides the problem itself, computed
/// once per problem (the grid solves at every one of its points): the weights of the
/// linearised residuals and, for log residuals, ln max(yᵢ, floor).
pub(crate) struct Prepared {
    /// √wᵢ, divided by max(|yᵢ|, floor) for relative and log residuals (linearised around
    /// the data).
    d: Vec<f64>,
    /// ln max(yᵢ, floor) for log residuals (empty otherwise).
    log_y: Vec<f64>,
}

impl Prepared {
    /// The data side of `problem`'s amplitude solves, computed once per fit.
    pub(crate) fn new(problem: &FitProblem) -> Self {
        let (y, floor, kind) = (problem.y(), problem.floor, problem.kind());
        let d = problem
            .sqrt_weight()
            .iter()
            .zip(y)
            .map(|(sw, yi)| match kind {
                ResidualKind::Absolute => sw,
                _ => sw / yi.abs().max(floor),
            })
            .collect();
        let log_y = match kind {
            ResidualKind::Log => y.iter().map(|v| v.max(floor).ln()).collect(),
            _ => Vec::new(),
        };
        Prepared { d, log_y }
    }
}

/// Solve the linear parameters `linear` of `p` at the model values `basis` (f = rest +
/// Σ p_k column_k) for the problem's data and residual kind (`prep` from
/// [`Prepared::new`] of the same problem). Sets `p[k]` (every amplitude > 0: one at its
/// bound 0 is set to 10⁻³ of the largest, so the solver's transform has a gradient there)
/// and returns the cost ½Σwr² there; None when the model or the solve is not finite.
pub(crate) fn solve(
    problem: &FitProblem,
    basis: &PointBasis,
    prep: &Prepared,
    p: &mut [f64],
    linear: &[usize],
) -> Option<f64> {
    if linear.is_empty() {
        return exact_cost(problem, basis, p, linear);
    }
    let coef = linearised(problem, basis, &prep.d)?;
    set(p, linear, &coef, &problem.layout, basis);

    if problem.kind() != ResidualKind::Log {
        return exact_cost(problem, basis, p, linear);
    }
    // Log residuals: refine the best of the linearised solve and the log-space starts on
    // the log residual itself.
    log_start(problem, basis, &prep.log_y, p, linear);
    refine_log(problem, basis, &prep.log_y, p, linear)
}

/// Replace the amplitudes of `p` by the lowest-cost start of the log residual among them
/// and, for each column c, the amplitude that alone fits the data best in log space,
/// ln p_c = Σ wᵢ (ln max(yᵢ, floor) − ln column_ci) / Σ wᵢ over the samples where the column
/// is positive, and the same over those whose value is above the floor (the others at 10⁻³
/// of it; samples at the floor say nothing of a model value below it, and where weights
/// grow as the values fall they would set the mean alone). The linearised solve weights each sample by
/// 1/max(|y|, floor), so where the data's dark samples dominate it can put every model
/// value below the floor, where the log residual is flat and no solve moves (a Lambertian
/// term on a lobe-only scan; a wide lobe on a Cornell paint).
fn log_start(
    problem: &FitProblem,
    basis: &PointBasis,
    ly: &[f64],
    p: &mut [f64],
    linear: &[usize],
) {
    let n = basis.rest.len();
    let sw = problem.sqrt_weight();
    let floor = problem.floor;
    let cost = |q: &[f64]| -> f64 {
        let c: f64 = (0..n)
            .map(|i| {
                let r = sw[i] * (value_at(basis, q, linear, i).max(floor).ln() - ly[i]);
                r * r
            })
            .sum();
        if c.is_finite() {
            c
        } else {
            f64::INFINITY
        }
    };
    let mut best = cost(p);
    let above = floor.ln();
    for (c, &k) in linear.iter().flat_map(|k| [k, k]).enumerate() {
        let (c, lit_only) = (c / 2, c % 2 == 1);
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..n {
            let col = basis.columns[c * n + i];
            if col > 0.0 && col.is_finite() && (!lit_only || ly[i] > above) {
                let w = sw[i] * sw[i];
                num += w * (ly[i] - col.ln());
                den += w;
            }
        }
        let amp = (num / den).exp();
        if !(den > 0.0 && amp.is_normal()) {
            continue;
        }
        let mut q = p.to_vec();
        for &other in linear {
            q[other] = 1e-3 * amp;
        }
        q[k] = amp;
        let qc = cost(&q);
        if qc < best {
            best = qc;
            p.copy_from_slice(&q);
        }
    }
    leave_plateau(basis, p, linear, floor, &cost, best);
}

/// Steps per decade of `leave_plateau`'s scan in its first decade above the floor (a
/// factor 1.037: with weights that follow the values, 1/σ_L² with σ_L ∝ L, the valley just
/// above the floor can be a few per cent wide).
pub(crate) const PLATEAU_STEPS_NEAR: usize = 64;

/// Steps per decade of `leave_plateau`'s scan beyond its first decade.
pub(crate) const PLATEAU_STEPS_FAR: usize = 16;

/// Decades above the floor `leave_plateau` scans.
pub(crate) const PLATEAU_DECADES: usize = 12;

/// When every model value at `p` lies at or below the floor (the log residual is flat
/// there: no solve moves), scale the amplitudes together from where the largest value
/// reaches the floor up [`PLATEAU_DECADES`] decades, and keep the lowest cost of the scan
/// if it is below `best` (a Lambertian term on a lobe-only file: its optimum lies just
/// above the floor, in a valley narrower than a Gauss–Newton step from the data's mean).
fn leave_plateau(
    basis: &PointBasis,
    p: &mut [f64],
    linear: &[usize],
    floor: f64,
    cost: &dyn Fn(&[f64]) -> f64,
    mut best: f64,
) {
    let n = basis.rest.len();
    let peak = (0..n)
        .map(|i| value_at(basis, p, linear, i))
        .filter(|v| v.is_finite())
        .fold(f64::NEG_INFINITY, f64::max);
    if !(peak > 0.0 && peak <= floor) || (0..n).any(|i| basis.rest[i] > floor) {
        return;
    }
    let base = p.to_vec();
    let near = (0..PLATEAU_STEPS_NEAR).map(|j| j as f64 / PLATEAU_STEPS_NEAR as f64);
    let far = (0..=(PLATEAU_DECADES - 1) * PLATEAU_STEPS_FAR)
        .map(|j| 1.0 + j as f64 / PLATEAU_STEPS_FAR as f64);
    for decades in near.chain(far) {
        let t = floor / peak * 10f64.powf(decades);
        let mut q = base.clone();
        linear.iter().for_each(|&k| q[k] *= t);
        let c = cost(&q);
        if c < best {
            best = c;
            p.copy_from_slice(&q);
        }
    }
}

/// Normal equations AᵀA x = Aᵀb of a few unknowns, accumulated one row of A at a time.
struct Normal {
    ata: DMatrix<f64>,
    atb: DVector<f64>,
}

impl Normal {
    fn new(k: usize) -> Self {
        Normal {
            ata: DMatrix::zeros(k, k),
            atb: DVector::zeros(k),
        }
    }

    /// Add the row `row` of A with right-hand side `b` (lower triangle of AᵀA only).
    fn add(&mut self, row: &[f64], b: f64) {
        for a in 0..row.len() {
            self.atb[a] += row[a] * b;
            for c in 0..=a {
                self.ata[(a, c)] += row[a] * row[c];
            }
        }
    }

    /// The finished (symmetric) AᵀA and Aᵀb.
    fn finish(mut self) -> (DMatrix<f64>, DVector<f64>) {
        let k = self.atb.len();
        for a in 0..k {
            for c in 0..a {
                self.ata[(c, a)] = self.ata[(a, c)];
            }
        }
        (self.ata, self.atb)
    }
}

/// The non-negative least-squares amplitudes of the residuals dᵢ(yᵢ − fᵢ), from the normal
/// equations accumulated in one pass over the samples (no n × k matrix is formed: the grid
/// solves this at every one of its points).
fn linearised(problem: &FitProblem, basis: &PointBasis, d: &[f64]) -> Option<Vec<f64>> {
    let n = problem.len();
    let k = basis.columns.len() / n.max(1);
    let y = problem.y();
    if k == 1 {
        return linearised_one(y, basis, d);
    }
    let mut normal = Normal::new(k);
    let mut row = vec![0.0; k];
    for i in 0..n {
        let b = d[i] * (y[i] - basis.rest[i]);
        for (c, r) in row.iter_mut().enumerate() {
            *r = d[i] * basis.columns[c * n + i];
        }
        if !(b.is_finite() && row.iter().all(|v| v.is_finite())) {
            return None;
        }
        normal.add(&row, b);
    }
    let (ata, atb) = normal.finish();
    nnls(&ata, &atb)
}

/// [`linearised`] for one amplitude (the scale of a single-lobe fit, every grid point of a
/// small KBS fit): the same sums in the same order, without the matrices, and the same
/// result as [`nnls`] of one unknown.
fn linearised_one(y: &[f64], basis: &PointBasis, d: &[f64]) -> Option<Vec<f64>> {
    let (mut ata, mut atb) = (0.0, 0.0);
    for (((&yi, &rest), &col), &di) in y.iter().zip(&basis.rest).zip(&basis.columns).zip(d) {
        let b = di * (yi - rest);
        let r = di * col;
        if !(b.is_finite() && r.is_finite()) {
            return None;
        }
        atb += r * b;
        ata += r * r;
    }
    if !(ata.is_finite() && atb.is_finite()) {
        return None;
    }
    let x = if ata > 0.0 { atb / ata } else { 0.0 };
    x.is_finite().then_some(vec![x.max(0.0)])
}

/// Non-negative least squares from the normal equations (AᵀA, Aᵀb) of a few unknowns, by
/// active sets: solve the free unknowns (SVD, rank-safe), fix the most negative one at 0,
/// repeat. Exact when at most one bound is active (every goniofit model has at most two
/// amplitudes per channel, and the channels' columns do not overlap), otherwise a feasible
/// point no worse than clamping. The solve runs on the equations with unit diagonal and
/// right-hand side of largest entry 1 (columns and data in any unit, 10⁻⁹⁰ or 10⁹⁰, give
/// the same amplitudes in that unit; an unknown whose column is zero is 0). None when the
/// normal equations or the solve are not finite, or the SVD does not converge within
/// [`SVD_MAX_ITERS`] sweeps.
pub(crate) fn nnls(ata: &DMatrix<f64>, atb: &DVector<f64>) -> Option<Vec<f64>> {
    // nalgebra's unbounded SVD never returns on a matrix with an infinite or NaN entry
    // (AᵀA of finite columns can overflow): such a grid point has no amplitudes.
    if !ata.iter().chain(atb.iter()).all(|v| v.is_finite()) {
        return None;
    }
    let k = atb.len();
    let unit: Vec<f64> = (0..k)
        .map(|j| {
            let d = ata[(j, j)];
            if d.is_normal() && d > 0.0 {
                1.0 / d.sqrt()
            } else {
                0.0
            }
        })
        .collect();
    let rhs = DVector::from_fn(k, |j, _| unit[j] * atb[j]);
    let b0 = rhs.amax();
    if !(b0.is_normal() && b0.is_finite()) {
        return Some(vec![0.0; k]);
    }
    let a = DMatrix::from_fn(k, k, |i, j| unit[i] * ata[(i, j)] * unit[j]);
    let x = nnls_unit(&a, &(rhs / b0))?;
    let coef: Vec<f64> = (0..k).map(|j| x[j] * unit[j] * b0).collect();
    coef.iter().all(|v| v.is_finite()).then_some(coef)
}

/// [`nnls`] of normal equations scaled to unit diagonal and right-hand side.
fn nnls_unit(ata: &DMatrix<f64>, atb: &DVector<f64>) -> Option<Vec<f64>> {
    let k = atb.len();
    if k == 1 {
        // One unknown: x = Aᵀb / AᵀA when AᵀA > 0 (what the SVD solve gives), else 0.
        let a = ata[(0, 0)];
        let x = if a > 0.0 { atb[0] / a } else { 0.0 };
        return x.is_finite().then_some(vec![x.max(0.0)]);
    }
    let mut free: Vec<usize> = (0..k).collect();
    let mut coef = vec![0.0; k];
    while !free.is_empty() {
        let m = free.len();
        let sub = DMatrix::from_fn(m, m, |i, j| ata[(free[i], free[j])]);
        let rhs = DVector::from_fn(m, |i, _| atb[free[i]]);
        let svd = sub.try_svd(true, true, f64::EPSILON, SVD_MAX_ITERS)?;
        let tol = 1e-14 * svd.singular_values.max();
        let x = svd.solve(&rhs, tol).ok()?;
        if !x.iter().all(|v| v.is_finite()) {
            return None;
        }
        let (worst, &lowest) = x
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .expect("at least one free unknown");
        coef.iter_mut().for_each(|c| *c = 0.0);
        for (i, &c) in free.iter().enumerate() {
            coef[c] = x[i];
        }
        if lowest > 0.0 {
            break;
        }
        coef[free[worst]] = 0.0;
        free.remove(worst);
    }
    Some(coef)
}

/// Set the amplitudes `linear` of `p` to the solve's `coef`. One at its bound 0 (the solve
/// found no use for its column) is given a value whose column adds at most [`AT_BOUND`] of
/// the model's largest value, so the solver's transform has a gradient there while the cost
/// stays that of the solve (a rule relative to the largest amplitude would not: a Lambertian
/// scale and a narrow lobe's strength can differ by 10⁵ at the same brightness).
fn set(
    p: &mut [f64],
    linear: &[usize],
    coef: &[f64],
    layout: &crate::fit::problem::layout::ParamLayout,
    basis: &PointBasis,
) {
    let n = basis.rest.len();
    let col_max = |c: usize| {
        basis.columns[c * n..(c + 1) * n]
            .iter()
            .fold(
                0.0f64,
                |m, v| if v.is_finite() { m.max(v.abs()) } else { m },
            )
    };
    let peak = (0..n)
        .map(|i| {
            coef.iter()
                .enumerate()
                .fold(basis.rest[i], |acc, (c, a)| {
                    acc + a.max(0.0) * basis.columns[c * n + i]
                })
                .abs()
        })
        .filter(|v| v.is_finite())
        .fold(0.0f64, f64::max);
    for (c, &k) in linear.iter().enumerate() {
        let tiny = AT_BOUND * peak / col_max(c);
        let tiny = if tiny.is_normal() {
            tiny
        } else {
            1e-3 * layout.params[k].transform.unit()
        };
        p[k] = if coef[c] > 0.0 && coef[c].is_finite() {
            coef[c]
        } else {
            tiny
        };
    }
}

/// Largest share of the model's peak value the column of an amplitude at its bound 0 adds
/// after `set` (a start for the solver, invisible in the cost).
pub(crate) const AT_BOUND: f64 = 1e-9;

/// The model value of sample `i` at `p` from the basis.
#[inline]
fn value_at(basis: &PointBasis, p: &[f64], linear: &[usize], i: usize) -> f64 {
    let n = basis.rest.len();
    linear
        .iter()
        .enumerate()
        .fold(basis.rest[i], |acc, (c, &k)| {
            acc + p[k] * basis.columns[c * n + i]
        })
}

/// The model values at `p` from the basis.
fn values(basis: &PointBasis, p: &[f64], linear: &[usize]) -> Vec<f64> {
    (0..basis.rest.len())
        .map(|i| value_at(basis, p, linear, i))
        .collect()
}

/// ½Σwr² at `p` with the problem's own residuals, in one pass over the samples (no
/// vectors: the grid takes this at every point); None when not finite.
fn exact_cost(
    problem: &FitProblem,
    basis: &PointBasis,
    p: &[f64],
    linear: &[usize],
) -> Option<f64> {
    let sw = problem.sqrt_weight();
    let n = basis.rest.len();
    let sum: f64 = match linear {
        // One amplitude: the fold of `value_at` written out (the same arithmetic).
        &[k] => {
            let pk = p[k];
            (0..n)
                .map(|i| {
                    let r = problem.residual(i, basis.rest[i] + pk * basis.columns[i]) * sw[i];
                    r * r
                })
                .sum()
        }
        _ => (0..n)
            .map(|i| {
                let r = problem.residual(i, value_at(basis, p, linear, i)) * sw[i];
                r * r
            })
            .sum(),
    };
    let cost = 0.5 * sum;
    cost.is_finite().then_some(cost)
}

/// Damped Gauss–Newton on the log residuals in u_c = ln p_c (at most [`LOG_ITERS`]
/// iterations, stopping when the cost falls by less than [`LOG_FTOL`] relative): every
/// step lowers the cost, so the result is no worse than the start. Returns the cost.
fn refine_log(
    problem: &FitProblem,
    basis: &PointBasis,
    ly: &[f64],
    p: &mut [f64],
    linear: &[usize],
) -> Option<f64> {
    let n = basis.rest.len();
    let k = linear.len();
    let sw = problem.sqrt_weight();
    let floor = problem.floor;
    // Weighted log residuals at `q` and their cost ½Σ(√w r)², from ln max(y, floor) = ly.
    let residuals = |q: &[f64]| -> (Vec<f64>, Vec<f64>, f64) {
        let f = values(basis, q, linear);
        let r: Vec<f64> = f
            .iter()
            .zip(ly)
            .zip(sw.iter())
            .map(|((fi, l), s)| s * (fi.max(floor).ln() - l))
            .collect();
        let cost = 0.5 * r.iter().map(|v| v * v).sum::<f64>();
        (f, r, cost)
    };
    let (mut f, mut r, mut cost) = residuals(p);
    if !cost.is_finite() {
        return None;
    }
    let mut mu = 1e-3;
    for _ in 0..LOG_ITERS {
        // JᵀJ and Jᵀr, J_ic = √wᵢ p_c column_ic / fᵢ where fᵢ is above the floor (0 below).
        let mut normal = Normal::new(k);
        let mut row = vec![0.0; k];
        for i in (0..n).filter(|&i| f[i] > floor) {
            for (c, &kk) in linear.iter().enumerate() {
                row[c] = sw[i] * p[kk] * basis.columns[c * n + i] / f[i];
            }
            normal.add(&row, r[i]);
        }
        let (jtj, g) = normal.finish();
        let mut improved = false;
        while mu < 1e12 {
            let mut m = jtj.clone();
            for c in 0..k {
                m[(c, c)] += mu * jtj[(c, c)].max(1e-12);
            }
            let Some(step) = m.lu().solve(&(-&g)) else {
                mu *= 10.0;
                continue;
            };
            let mut q = p.to_vec();
            for (c, &kk) in linear.iter().enumerate() {
                q[kk] = p[kk] * step[c].clamp(-30.0, 30.0).exp();
            }
            let (fq, rq, cq) = residuals(&q);
            if cq < cost {
                improved = cost - cq > LOG_FTOL * cost;
                p.copy_from_slice(&q);
                (f, r, cost) = (fq, rq, cq);
                mu = (mu / 3.0).max(1e-9);
                break;
            }
            mu *= 4.0;
        }
        if !improved {
            break;
        }
    }
    Some(cost)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nnls_matches_the_unconstrained_solve_inside_and_clamps_with_a_resolve() {
        // A = [[1, 0], [1, 1], [0, 1]], b = [1, 3, 2]: x = (1, 2) exactly (interior).
        let a = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 1.0, 1.0, 0.0, 1.0]);
        let b = DVector::from_row_slice(&[1.0, 3.0, 2.0]);
        let x = nnls(&a.tr_mul(&a), &a.tr_mul(&b)).unwrap();
        assert!(
            (x[0] - 1.0).abs() < 1e-12 && (x[1] - 2.0).abs() < 1e-12,
            "{x:?}"
        );
        // b = [-1, 1, 2]: the unconstrained solve gives x = (-1, 2); with x0 held at 0 the
        // best x1 is (1 + 2)/2 = 1.5 (not the 2 that clamping alone would keep).
        let b = DVector::from_row_slice(&[-1.0, 1.0, 2.0]);
        let x = nnls(&a.tr_mul(&a), &a.tr_mul(&b)).unwrap();
        assert_eq!(x[0], 0.0);
        assert!((x[1] - 1.5).abs() < 1e-12, "{x:?}");
    }
}
