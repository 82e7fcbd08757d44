//! The problem a profile refit solves ([`super::profile`]): the fit with one quantity ψ
//! held at a trial value, in the solver variables z (the free x without the one ψ fixes).

use crate::fit::problem::{FitProblem, Transform};
use goniofit_lm::{LeastSquaresProblem, Reduced, Stop};
use nalgebra::{DMatrix, DVector};
use std::sync::Mutex;

/// The problem with ψ held at `t`: solver variables z are the free x without the one that
/// ψ fixes (see [`super::profile::Target`]).
pub(super) struct Restricted<'a, 'p> {
    base: &'a FitProblem<'p>,
    /// Position of the held variable among the free x.
    pub(super) held: usize,
    /// (free position, coefficient) of the other factors of a product; empty for a
    /// parameter.
    others: Vec<(usize, f64)>,
    /// Coefficient of the held variable (a product), or 0 for a parameter.
    c_held: f64,
    t: f64,
    transforms: Vec<Transform>,
    cache: Mutex<Option<(DVector<f64>, Held)>>,
    /// The fit's stop (signals, time limit): an evaluation it cuts short is NaN, which the
    /// refit rejects, so a stop ends the walk within one block's evaluation.
    stop: Option<Stop>,
}

/// d ln p / dx for a transform at x (None where p = 0).
pub(super) fn dlnp_dx(tr: Transform, x: f64) -> Option<f64> {
    let p = tr.from_x(x);
    (p > 0.0 && p.is_finite()).then(|| tr.dp_dx(x) / p)
}

impl<'a, 'p> Restricted<'a, 'p> {
    /// `base` with ψ held at `t`: `(held, others, c_held)` as the fields say, the free
    /// parameters' `transforms`, the fit's `stop`.
    pub(super) fn new(
        base: &'a FitProblem<'p>,
        (held, others, c_held): (usize, Vec<(usize, f64)>, f64),
        t: f64,
        transforms: Vec<Transform>,
        stop: Option<Stop>,
    ) -> Self {
        Restricted {
            base,
            held,
            others,
            c_held,
            t,
            transforms,
            cache: Mutex::new(None),
            stop,
        }
    }
}

impl Restricted<'_, '_> {
    /// The number of free x (z has one fewer).
    fn n_free(&self) -> usize {
        self.transforms.len()
    }

    /// The full x from z, and ∂x_held/∂z_j for a product (None outside the domain).
    pub(super) fn full_x(&self, z: &DVector<f64>) -> Option<(DVector<f64>, Vec<f64>)> {
        let n = self.n_free();
        let mut x = DVector::zeros(n);
        let mut j = 0;
        for i in 0..n {
            if i != self.held {
                x[i] = z[j];
                j += 1;
            }
        }
        let mut grad = vec![0.0; n];
        if self.others.is_empty() && self.c_held == 0.0 {
            x[self.held] = self.t;
        } else {
            let mut sum = 0.0;
            for &(i, c) in &self.others {
                let p = self.transforms[i].from_x(x[i]);
                if !(p > 0.0 && p.is_finite()) {
                    return None;
                }
                sum += c * p.ln();
                grad[i] = -c / self.c_held * dlnp_dx(self.transforms[i], x[i])?;
            }
            x[self.held] = (self.t - sum) / self.c_held;
        }
        Some((x, grad))
    }

    /// The residuals at `z` and their Jacobian in z: whole, or reduced ([`Reduced`]) for a
    /// base problem that [`FitProblem::reduces`].
    fn eval(&self, z: &DVector<f64>) -> (DVector<f64>, Held) {
        let m = self.base.len();
        let n = self.n_free();
        let reduces = self.base.reduces();
        let Some((x, grad)) = self.full_x(z) else {
            let r = DVector::from_element(m, f64::NAN);
            let rows = if reduces { n } else { m };
            let a = DMatrix::from_element(rows, n - 1, f64::NAN);
            return match reduces {
                true => (
                    r,
                    Held::Reduced(Reduced {
                        a,
                        b: DVector::from_element(n, f64::NAN),
                    }),
                ),
                false => (r, Held::Whole(a)),
            };
        };
        if reduces {
            let (r, red) = self.base.weighted_reduced(&x, self.stop.as_ref());
            let a = self.in_z(red.a, &grad);
            return (r, Held::Reduced(Reduced { a, b: red.b }));
        }
        let (r, j) = self.whole(&x, &grad);
        (r, Held::Whole(j))
    }

    /// The residuals at the full `x` and their whole Jacobian in z (`grad`: see
    /// [`Self::full_x`]).
    fn whole(&self, x: &DVector<f64>, grad: &[f64]) -> (DVector<f64>, DMatrix<f64>) {
        let e = self.base.evaluate(x, self.stop.as_ref());
        (e.residuals, self.in_z(e.jacobian, grad))
    }

    /// A Jacobian in x (or its reduced `A`, whose columns transform alike) taken to z:
    /// ∂r/∂z_j = ∂r/∂x_j + ∂r/∂x_held · ∂x_held/∂z_j (`grad`), formed in its own storage
    /// (no second m × n matrix for a big fit), then the held column removed.
    fn in_z(&self, mut jx: DMatrix<f64>, grad: &[f64]) -> DMatrix<f64> {
        for (i, &gi) in grad.iter().enumerate() {
            if i != self.held && gi != 0.0 {
                for row in 0..jx.nrows() {
                    let h = jx[(row, self.held)];
                    jx[(row, i)] += gi * h;
                }
            }
        }
        jx.remove_column(self.held)
    }
}

/// A restricted problem's Jacobian at its last evaluated point.
enum Held {
    /// The whole `m × n` Jacobian.
    Whole(DMatrix<f64>),
    /// Reduced ([`Reduced`]), for a base problem that [`FitProblem::reduces`].
    Reduced(Reduced),
}

impl LeastSquaresProblem for Restricted<'_, '_> {
    /// The residuals at `z`, their Jacobian kept for the solver's next request (the one
    /// kept before dropped first: one `m × n` matrix held, not two).
    fn residuals(&self, z: &DVector<f64>) -> DVector<f64> {
        if let Ok(mut c) = self.cache.lock() {
            *c = None;
        }
        let (r, j) = self.eval(z);
        if let Ok(mut c) = self.cache.lock() {
            *c = Some((z.clone(), j));
        }
        r
    }

    fn recycle(&self, spent: DVector<f64>) {
        self.base.keep_spare(spent);
    }

    /// The cached Jacobian when the last evaluation was at `z`; else the cache is dropped
    /// first (as [`FitProblem::cached_jacobian`] does: no stale `m × n` matrix is held
    /// while the new one is evaluated).
    fn jacobian(&self, z: &DVector<f64>) -> DMatrix<f64> {
        match (self.held_at(z), self.full_x(z)) {
            (Held::Whole(j), _) => j,
            (Held::Reduced(_), Some((x, grad))) => self.whole(&x, &grad).1,
            (Held::Reduced(_), None) => {
                DMatrix::from_element(self.base.len(), self.n_free() - 1, f64::NAN)
            }
        }
    }

    /// The cached reduced Jacobian when the last evaluation was at `z`, else evaluated;
    /// None when the base problem does not reduce.
    fn reduced_jacobian(&self, z: &DVector<f64>) -> Option<Reduced> {
        if !self.base.reduces() {
            return None;
        }
        match self.held_at(z) {
            Held::Reduced(red) => Some(red),
            Held::Whole(_) => None,
        }
    }

    /// Under a robust loss, the base problem's step residuals at the full x (the same at
    /// every parametrisation; one more model pass per Jacobian, only for robust fits).
    fn step_residuals(&self, z: &DVector<f64>) -> Option<DVector<f64>> {
        if self.base.loss().is_linear() {
            return None;
        }
        let (x, _) = self.full_x(z)?;
        self.base.step_residuals(&x)
    }
}

impl Restricted<'_, '_> {
    /// The Jacobian at `z`: the one cached by the last evaluation there (handed over), else
    /// evaluated.
    fn held_at(&self, z: &DVector<f64>) -> Held {
        if let Ok(mut c) = self.cache.lock() {
            if let Some((cz, j)) = c.take() {
                if &cz == z {
                    return j;
                }
            }
        }
        self.eval(z).1
    }
}
