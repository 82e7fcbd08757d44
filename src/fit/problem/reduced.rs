//! The Jacobian of a problem of many samples reduced block by block of samples
//! ([`Reduced`]: its triangular factor and the residuals transformed alike): the solver's
//! steps and the covariance need only that, and the `n × p` Jacobian (8p bytes per sample)
//! is never held.

use super::{Block, FitProblem};
use crate::lm::{Reduced, Stop};
use nalgebra::{DMatrix, DVector};

/// Problems of at least this many samples, with a linear loss, give the solver their
/// Jacobian reduced ([`FitProblem::reduces`]); smaller ones give the whole Jacobian, and
/// their steps are MINPACK's to the bit. Both give the same steps to rounding.
pub const REDUCE_MIN_ROWS: usize = 1 << 17;

impl FitProblem<'_> {
    /// Whether the solver gets this problem's Jacobian reduced ([`REDUCE_MIN_ROWS`] samples
    /// or more, linear loss).
    pub fn reduces(&self) -> bool {
        self.n >= REDUCE_MIN_ROWS && self.loss.is_linear()
    }

    /// The weighted residuals √wᵢ rᵢ at solver variables `x` and their Jacobian reduced
    /// block by block of samples (each block reduced on the thread that evaluated it, the
    /// blocks then stacked in order, so the result does not depend on the threads), cut
    /// short once `stop` is requested (then NaN). Linear loss only.
    pub fn weighted_reduced(
        &self,
        x: &DVector<f64>,
        stop: Option<&Stop>,
    ) -> (DVector<f64>, Reduced) {
        let p = self.layout.from_x(x);
        let n_free = self.layout.free().len();
        if !self.in_domain(&p) {
            return (
                DVector::from_element(self.n, f64::NAN),
                not_evaluated(n_free),
            );
        }
        let column = self.solver_columns(x);
        let n_spec = self.model.params().len();
        let finish = |b: &Block, f: &mut [f64], jac: &mut [f64]| {
            self.weigh_block(b, f, jac);
            let m = f.len();
            let mut block = vec![0.0; m * n_free];
            for s in 0..n_spec {
                if let Some((col, chain)) = column[self.layout.index[b.channel][s]] {
                    let (to, from) = (&mut block[col * m..(col + 1) * m], &jac[s * m..(s + 1) * m]);
                    for (t, &v) in to.iter_mut().zip(from) {
                        *t = v * chain;
                    }
                }
            }
            let mut red = Reduced::empty(n_free);
            red.push_rows(&block, f);
            red
        };
        let mut rw = DVector::zeros(self.n);
        let mut red = Reduced::empty(n_free);
        self.eval_blocks(&p, true, stop, finish, |b, r, _, part| {
            for (row, i) in b.idx.iter().enumerate() {
                rw[i] = r[row];
            }
            red.push(&part);
        });
        (rw, red)
    }

    /// The reduced Jacobian at `x`: the one the last residual evaluation left at `x`
    /// (handed over once), else evaluated — unless `stop` is requested: then every entry
    /// is NaN.
    pub fn reduced_until(&self, x: &DVector<f64>, stop: Option<&Stop>) -> Reduced {
        if let Ok(mut c) = self.cache.lock() {
            if let Some(red) = c
                .as_mut()
                .filter(|c| &c.x == x)
                .and_then(|c| c.reduced.take())
            {
                return red;
            }
            *c = None;
        }
        if stop.is_some_and(Stop::is_requested) {
            return not_evaluated(self.layout.free().len());
        }
        self.weighted_reduced(x, None).1
    }

    /// The weighted residuals at `x` and a matrix with the Jacobian's `JᵀJ`: the
    /// Jacobian's reduced `A` ([`Reduced`]) for a problem that [`Self::reduces`], else the
    /// Jacobian itself — what the covariance needs.
    pub fn residuals_and_gram_factor(&self, x: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
        if self.reduces() {
            let (r, red) = self.weighted_reduced(x, None);
            (r, red.a)
        } else {
            self.residuals_and_jacobian(x)
        }
    }
}

/// The reduced Jacobian of a point not evaluated: `n × n`, NaN.
fn not_evaluated(n: usize) -> Reduced {
    Reduced {
        a: DMatrix::from_element(n, n, f64::NAN),
        b: DVector::from_element(n, f64::NAN),
    }
}
