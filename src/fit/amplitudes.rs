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
use super::problem::{FitProblem, ResidualKind};
use nalgebra::{DMatrix, DVector};

/// Iterations of the Gauss–Newton refinement of log-residual amplitudes: the grid only ranks
/// its points (the solver refines the winners), so a few steps that bring the amplitudes
/// near their optimum are enough, and they bound the work at a grid point.
pub const LOG_ITERS: usize = 10;

/// Most sweeps of the SVD in [`nnls`] (a few unknowns converge in a handful; the bound only
/// turns a matrix the SVD cannot handle into "no amplitudes" instead of an endless loop).
pub const SVD_MAX_ITERS: usize = 1000;

/// Relative cost reduction below which the log-residual refinement stops.
pub const LOG_FTOL: f64 = 1e-6;

/// Solve the linear parameters `linear` of `p` at the model values `basis` (f = rest +
/// Σ p_k column_k) for the problem's data and residual kind, with the residual weights `d`
/// of [`linear_weights`]. Sets `p[k]` (every amplitude > 0: one at its bound 0 is set to
/// 10⁻³ of the largest, so the solver's transform has a gradient there) and returns the
/// cost ½Σwr² there; None when the model or the solve is not finite.
pub fn solve(
    problem: &FitProblem,
    basis: &PointBasis,
    d: &[f64],
    p: &mut [f64],
    linear: &[usize],
) -> Option<f64> {
    if linear.is_empty() {
        return exact_cost(problem, basis, p, linear);
    }
    let coef = linearised(problem, basis, d)?;
    set(p, linear, &coef);
    if problem.kind() != ResidualKind::Log {
        return exact_cost(problem, basis, p, linear);
    }
    // Log residuals: refine the linearised solve on the log residual itself.
    let ly: Vec<f64> = problem
        .y()
        .iter()
        .map(|v| v.max(problem.floor).ln())
        .collect();
    refine_log(problem, basis, &ly, p, linear)
}

/// The weights of the linearised residuals: √wᵢ, divided by max(|yᵢ|, floor) for relative
/// and log residuals (linearised around the data).
pub fn linear_weights(problem: &FitProblem) -> Vec<f64> {
    let y = problem.y();
    problem
        .sqrt_weight()
        .iter()
        .zip(y)
        .map(|(sw, yi)| match problem.kind() {
            ResidualKind::Absolute => *sw,
            _ => sw / yi.abs().max(problem.floor),
        })
        .collect()
}

/// The non-negative least-squares amplitudes of the residuals dᵢ(yᵢ − fᵢ).
fn linearised(problem: &FitProblem, basis: &PointBasis, d: &[f64]) -> Option<Vec<f64>> {
    let n = problem.len();
    let k = basis.columns.len() / n.max(1);
    let y = problem.y();
    let a = DMatrix::from_fn(n, k, |i, c| d[i] * basis.columns[c * n + i]);
    let b = DVector::from_fn(n, |i, _| d[i] * (y[i] - basis.rest[i]));
    if !a.iter().chain(b.iter()).all(|v| v.is_finite()) {
        return None;
    }
    nnls(&a.tr_mul(&a), &a.tr_mul(&b))
}

/// Non-negative least squares from the normal equations (AᵀA, Aᵀb) of a few unknowns, by
/// active sets: solve the free unknowns (SVD, rank-safe), fix the most negative one at 0,
/// repeat. Exact when at most one bound is active (every goniofit model has at most two
/// amplitudes per channel, and the channels' columns do not overlap), otherwise a feasible
/// point no worse than clamping. None when the normal equations or the solve are not
/// finite, or the SVD does not converge within [`SVD_MAX_ITERS`] sweeps.
pub fn nnls(ata: &DMatrix<f64>, atb: &DVector<f64>) -> Option<Vec<f64>> {
    // nalgebra's unbounded SVD never returns on a matrix with an infinite or NaN entry
    // (AᵀA of finite columns can overflow): such a grid point has no amplitudes.
    if !ata.iter().chain(atb.iter()).all(|v| v.is_finite()) {
        return None;
    }
    let k = atb.len();
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

/// Write amplitudes into `p`, each at least 10⁻³ of the largest (1e-3 when all are 0).
fn set(p: &mut [f64], linear: &[usize], coef: &[f64]) {
    let largest = coef.iter().fold(0.0f64, |m, v| m.max(*v));
    let tiny = if largest > 0.0 { 1e-3 * largest } else { 1e-3 };
    for (c, &k) in linear.iter().enumerate() {
        p[k] = if coef[c] > tiny { coef[c] } else { tiny };
    }
}

/// The model values at `p` from the basis.
fn values(basis: &PointBasis, p: &[f64], linear: &[usize]) -> Vec<f64> {
    let n = basis.rest.len();
    (0..n)
        .map(|i| {
            linear
                .iter()
                .enumerate()
                .fold(basis.rest[i], |acc, (c, &k)| {
                    acc + p[k] * basis.columns[c * n + i]
                })
        })
        .collect()
}

/// ½Σwr² at `p` with the problem's own residuals; None when not finite.
fn exact_cost(
    problem: &FitProblem,
    basis: &PointBasis,
    p: &[f64],
    linear: &[usize],
) -> Option<f64> {
    let r = problem.raw_residuals(&values(basis, p, linear));
    let cost = 0.5
        * r.iter()
            .zip(problem.sqrt_weight())
            .map(|(r, s)| (r * s) * (r * s))
            .sum::<f64>();
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
            .zip(sw)
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
        let mut jtj = DMatrix::<f64>::zeros(k, k);
        let mut g = DVector::<f64>::zeros(k);
        let mut row = vec![0.0; k];
        for i in (0..n).filter(|&i| f[i] > floor) {
            for (c, &kk) in linear.iter().enumerate() {
                row[c] = sw[i] * p[kk] * basis.columns[c * n + i] / f[i];
            }
            for a in 0..k {
                g[a] += row[a] * r[i];
                for b in 0..=a {
                    jtj[(a, b)] += row[a] * row[b];
                }
            }
        }
        for a in 0..k {
            for b in 0..a {
                jtj[(b, a)] = jtj[(a, b)];
            }
        }
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
