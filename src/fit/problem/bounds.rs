//! Amplitudes at their bound 0: the active set of a solve.
//!
//! An amplitude p = u(√(x² + 1) − 1) ([`super::layout::Transform::NonNegative`]) that the
//! data would rather see below 0 runs to x → 0, where dp/dx = x vanishes: the Gauss–Newton
//! model of the cost then has no curvature in x there (the cost's own is g·d²p/dx² = g·u),
//! each step overshoots the bound, and Levenberg–Marquardt crawls. A Cornell channel whose
//! Lambertian term is absent (garnet_red 550 nm, `kbs+lambert`, absolute residuals) spent
//! its 1000 iterations so, 5·10⁻⁴ above the optimum it reaches in 27 with the term held at 0.
//!
//! So a solve ends with the bound made active where the data asks for it
//! ([`minimize`]): an amplitude whose removal costs little and whose gradient pushes it to
//! 0 is held at 0 and the others solved again; the point is kept if it is lower, and the
//! solver then confirms it on the whole problem (the amplitude's column is 0 there, so the
//! confirmation ends at once, and the report's Jacobian is that of every free parameter).

use super::ParamLayout;
use goniofit_lm as lm;
use goniofit_lm::{LeastSquaresProblem, LmConfig, LmReport};
use nalgebra::{DMatrix, DVector};

/// Relative cost by which removing an amplitude (p = 0, the others held) may raise the
/// solve's cost for the bound to be tried: a component that carries more of the fit than
/// this is no absent one (its removal is tried only when it is within reach of the bound).
pub(crate) const BOUND_TRY: f64 = 1e-2;

/// Minimise `problem` (solver variables of `layout`) from `x0`, then settle the amplitudes
/// at their bound (see the module doc): the returned report is the lowest-cost of the run
/// and the run with the bound active, with the work of both counted.
pub(in crate::fit) fn minimize<P: LeastSquaresProblem + ?Sized>(
    layout: &ParamLayout,
    problem: &P,
    x0: DVector<f64>,
    config: &LmConfig,
) -> LmReport {
    let best = lm::minimize(problem, x0, config);
    if !best.cost.is_finite() {
        return best;
    }
    let best = match bound_candidate(layout, problem, &best) {
        Some(j) => hold_at_bound(problem, best, j, config),
        None => best,
    };
    release(layout, problem, best, config)
}

/// The better of `best` and the solve with free variable `j` held at 0 (confirmed on the
/// whole problem), with the work of both.
fn hold_at_bound<P: LeastSquaresProblem + ?Sized>(
    problem: &P,
    mut best: LmReport,
    j: usize,
    config: &LmConfig,
) -> LmReport {
    let held = HeldAtZero { inner: problem, j };
    let run = lm::minimize(&held, without(&best.x, j), config);
    if run.cost.partial_cmp(&best.cost) != Some(std::cmp::Ordering::Less) {
        add_counts(&mut best, &run);
        return best;
    }
    let mut confirmed = lm::minimize(problem, with_zero(&run.x, j), config);
    add_counts(&mut confirmed, &run);
    if confirmed.cost.is_finite() && confirmed.cost <= best.cost {
        add_counts(&mut confirmed, &best);
        return confirmed;
    }
    add_counts(&mut best, &confirmed);
    best
}

/// `best`, or where the solve goes from it with an amplitude at its bound 0 (x = 0: its
/// Jacobian column is 0 there, so no solve can leave it) released, when the cost's
/// derivative in that amplitude is negative there (the data asks for some of it): the
/// solve restarts at the Gauss–Newton amplitude, and the lower of the two is kept.
fn release<P: LeastSquaresProblem + ?Sized>(
    layout: &ParamLayout,
    problem: &P,
    mut best: LmReport,
    config: &LmConfig,
) -> LmReport {
    let free = layout.free();
    for (j, &k) in free.iter().enumerate() {
        let t = layout.params[k].transform;
        if !t.is_non_negative() || best.x[j] != 0.0 || best.x.len() != free.len() {
            continue;
        }
        // ∂r/∂p at the bound, from the Jacobian a hair inside it (p = u·ε²/2).
        let mut probe = best.x.clone();
        probe[j] = RELEASE_PROBE;
        let column = problem.jacobian(&probe).column(j) / t.dp_dx(RELEASE_PROBE);
        let (g, h) = (column.dot(&best.residuals), column.norm_squared());
        if !(g.is_finite() && h.is_finite()) || g >= 0.0 || h <= 0.0 {
            continue;
        }
        let mut start = best.x.clone();
        start[j] = t.to_x(-g / h);
        let mut run = lm::minimize(problem, start, config);
        if run.cost < best.cost {
            add_counts(&mut run, &best);
            best = run;
        } else {
            add_counts(&mut best, &run);
        }
    }
    best
}

/// The cost's gradient Jᵀr̃ at `report`'s point: from its Jacobian, or from the problem's
/// reduced Jacobian there when the report holds that ([`lm::Reduced`]: `Aᵀb = Jᵀr̃`).
fn gradient<P: LeastSquaresProblem + ?Sized>(problem: &P, report: &LmReport) -> DVector<f64> {
    if report.jacobian.nrows() == report.residuals.len() {
        return report.jacobian.tr_mul(&report.residuals);
    }
    match problem.reduced_jacobian(&report.x) {
        Some(red) => red.gradient(),
        None => problem.jacobian(&report.x).tr_mul(&report.residuals),
    }
}

/// The solver variable of an amplitude at its bound at which [`release`] takes the cost's
/// derivative in it (p = u·ε²/2 ≈ 5·10⁻¹⁷ u: the point is the bound's to rounding).
pub(crate) const RELEASE_PROBE: f64 = 1e-8;

/// The free amplitude (index among the free variables) of `report`'s point whose bound is
/// worth trying: its gradient pushes it towards 0, and setting it to 0 raises the cost by
/// at most [`BOUND_TRY`] relative; of several, the cheapest to remove. None when no
/// amplitude is such, or it is at 0 already.
fn bound_candidate<P: LeastSquaresProblem + ?Sized>(
    layout: &ParamLayout,
    problem: &P,
    report: &LmReport,
) -> Option<usize> {
    let free = layout.free();
    let g = gradient(problem, report);
    let mut best: Option<(usize, f64)> = None;
    for (j, &k) in free.iter().enumerate() {
        let x = report.x[j];
        // dc/dx · x > 0: a larger |x| (larger p) raises the cost.
        if !layout.params[k].transform.is_non_negative()
            || x == 0.0
            || (g[j] * x).partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater)
        {
            continue;
        }
        let mut z = report.x.clone();
        z[j] = 0.0;
        let cost = 0.5 * problem.residuals(&z).norm_squared();
        if cost.is_finite()
            && cost <= report.cost * (1.0 + BOUND_TRY)
            && best.is_none_or(|(_, c)| cost < c)
        {
            best = Some((j, cost));
        }
    }
    best.map(|(j, _)| j)
}

/// `x` without entry `j`.
fn without(x: &DVector<f64>, j: usize) -> DVector<f64> {
    x.clone().remove_row(j)
}

/// `x` with a 0 inserted at entry `j`.
fn with_zero(x: &DVector<f64>, j: usize) -> DVector<f64> {
    x.clone().insert_row(j, 0.0)
}

/// Add `other`'s iteration, evaluation and time counts to `to`.
fn add_counts(to: &mut LmReport, other: &LmReport) {
    to.iterations += other.iterations;
    to.evaluations += other.evaluations;
    to.jacobian_evaluations += other.jacobian_evaluations;
    to.seconds += other.seconds;
}

/// A problem with free variable `j` held at x = 0 (the amplitude at its bound).
struct HeldAtZero<'p, P: ?Sized> {
    inner: &'p P,
    j: usize,
}

impl<P: LeastSquaresProblem + ?Sized> LeastSquaresProblem for HeldAtZero<'_, P> {
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
        self.inner.residuals(&with_zero(x, self.j))
    }

    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        self.inner
            .jacobian(&with_zero(x, self.j))
            .remove_column(self.j)
    }

    fn step_residuals(&self, x: &DVector<f64>) -> Option<DVector<f64>> {
        self.inner.step_residuals(&with_zero(x, self.j))
    }

    fn recycle(&self, spent: DVector<f64>) {
        self.inner.recycle(spent);
    }

    fn reduced_jacobian(&self, x: &DVector<f64>) -> Option<lm::Reduced> {
        let red = self.inner.reduced_jacobian(&with_zero(x, self.j))?;
        Some(lm::Reduced {
            a: red.a.remove_column(self.j),
            b: red.b,
        })
    }
}
