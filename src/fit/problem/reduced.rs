//! The Jacobian of a problem of many samples reduced block by block of samples
//! ([`Reduced`]: its triangular factor and the residuals transformed alike): the solver's
//! steps and the covariance need only that, and the `n × p` Jacobian (8p bytes per sample)
//! is never held.

use super::{Block, FitProblem};
use goniofit_lm::{Reduced, Stop};
use nalgebra::{DMatrix, DVector};

/// Problems of at least this many samples, with a linear loss, give the solver their
/// Jacobian reduced ([`FitProblem::reduces`]); smaller ones give the whole Jacobian, and
/// their steps are MINPACK's to the bit. Both give the same steps to rounding.
pub(crate) const REDUCE_MIN_ROWS: usize = 1 << 17;

/// Spent residual vectors a big problem keeps ([`FitProblem::keep_spare`]): a solve holds
/// the current point's and a trial's, and a refit that ends hands its last one back, so
/// two serve a whole walk of profile refits.
pub(crate) const SPARES: usize = 2;

impl FitProblem<'_> {
    /// Whether the solver gets this problem's Jacobian reduced ([`REDUCE_MIN_ROWS`] samples
    /// or more, linear loss).
    pub(crate) fn reduces(&self) -> bool {
        self.n >= REDUCE_MIN_ROWS && self.loss.is_linear()
    }

    /// The weighted residuals √wᵢ rᵢ at solver variables `x` and their Jacobian reduced
    /// block by block of samples (each block reduced on the thread that evaluated it, the
    /// blocks then stacked in order, so the result does not depend on the threads), cut
    /// short once `stop` is requested (then NaN). Linear loss only.
    pub(crate) fn weighted_reduced(
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
        // Every entry is written below (the blocks cover the samples).
        let mut rw = self
            .take_spare()
            .unwrap_or_else(|| DVector::from_vec(vec![0.0; self.n]));
        let mut red = Reduced::empty(n_free);
        self.eval_blocks(&p, true, stop, finish, |b, r, _, part| {
            for (row, i) in b.idx.iter().enumerate() {
                rw[i] = r[row];
            }
            red.push(&part);
        });
        (rw, red)
    }

    /// Keep residuals the solver is done with for the next reduced evaluations to fill (a
    /// big fit's evaluations then reuse the memory of [`SPARES`] vectors instead of mapping
    /// 8 bytes per sample afresh each time); other problems drop them.
    pub(crate) fn keep_spare(&self, spent: DVector<f64>) {
        if self.reduces() && spent.len() == self.n {
            if let Ok(mut s) = self.spare.lock() {
                if s.len() < SPARES {
                    s.push(spent);
                }
            }
        }
    }

    /// Drop the residuals kept by [`FitProblem::keep_spare`]: once the solves on this
    /// problem are done.
    pub(crate) fn forget_spare(&self) {
        if let Ok(mut s) = self.spare.lock() {
            *s = Vec::new();
        }
    }

    fn take_spare(&self) -> Option<DVector<f64>> {
        self.spare.lock().ok()?.pop()
    }

    /// The reduced Jacobian at `x`: the one the last residual evaluation left at `x`
    /// (handed over once), else evaluated — unless `stop` is requested: then every entry
    /// is NaN.
    pub(crate) fn reduced_until(&self, x: &DVector<f64>, stop: Option<&Stop>) -> Reduced {
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
    pub(crate) fn residuals_and_gram_factor(
        &self,
        x: &DVector<f64>,
    ) -> (DVector<f64>, DMatrix<f64>) {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::problem::{Channels, FitInput, ParamLayout, ResidualKind};
    use crate::geometry::{Geometry, Quantity, Sample};
    use goniofit_lm::{minimize, LeastSquaresProblem, LmConfig};

    /// A KBS hemisphere scan of `n` samples (deterministic angles) whose values are the
    /// model's at σ = 0.25 λ, T = 2.5 λ with a deterministic ±1 % perturbation.
    fn input(model: &dyn crate::model::Model, n: usize) -> FitInput {
        let samples: Vec<Sample> = (0..n)
            .map(|i| {
                let u = |k: usize, m: usize| ((i * k) % m) as f64 / m as f64;
                Sample::from_degrees(
                    80.0 * u(7, 97),
                    85.0 * u(13, 331),
                    360.0 * u(1, 1009) - 180.0,
                )
            })
            .collect();
        let geo = Geometry::new(&samples, &[1.0], Quantity::Radiance).unwrap();
        let layout = ParamLayout::new(model, &[String::new()]);
        let p: Vec<f64> = layout
            .params
            .iter()
            .map(|fp| match fp.name.as_str() {
                "sigma" => 0.25,
                "T" => 2.5,
                _ => 1.0,
            })
            .collect();
        let mut f = vec![0.0; n];
        model.eval(&geo, &layout.model_params(&p, 0), &mut f, None);
        let y: Vec<f64> = (0..n)
            .map(|i| f[i] * (1.0 + 0.01 * ((i * 7919 % 201) as f64 / 100.0 - 1.0)))
            .collect();
        FitInput {
            geo,
            y: y.into(),
            weight: vec![1.0; n].into(),
            channel: Channels::single(n),
            channel_names: vec![String::new()],
        }
    }

    #[test]
    fn a_big_problem_reduces_its_jacobian_to_the_dense_one_and_solves_alike() {
        let model = crate::model::by_name("kbs", &Default::default()).unwrap();
        let n = REDUCE_MIN_ROWS + 1000;
        let input = input(model.as_ref(), n);
        let layout = ParamLayout::new(model.as_ref(), &input.channel_names);
        let problem =
            FitProblem::new(model.as_ref(), layout, &input, ResidualKind::Absolute, 0.0).unwrap();
        assert!(problem.reduces());
        let start: Vec<f64> = (problem.layout.params.iter())
            .map(|fp| match fp.name.as_str() {
                "sigma" => 0.3,
                "T" => 2.0,
                _ => 0.8,
            })
            .collect();
        let x = problem.layout.to_x(&start);
        let (r_dense, j) = problem.residuals_and_jacobian(&x);
        let (r, red) = problem.weighted_reduced(&x, None);
        assert_eq!(r, r_dense, "the same residuals to the bit");
        let gram = j.tr_mul(&j);
        let diff = (red.a.tr_mul(&red.a) - &gram).norm();
        assert!(diff <= 1e-12 * gram.norm(), "JᵀJ off by {diff}");
        let (g, g_dense) = (red.gradient(), j.tr_mul(&r));
        assert!((&g - &g_dense).norm() <= 1e-12 * g_dense.norm());
        // The solve with the reduced Jacobian and the one with the dense Jacobian (the
        // problem behind a wrapper that supplies only that) reach the same optimum.
        struct Dense<'a, 'p>(&'a FitProblem<'p>);
        impl LeastSquaresProblem for Dense<'_, '_> {
            fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
                self.0.residuals_and_jacobian(x).0
            }
            fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
                self.0.residuals_and_jacobian(x).1
            }
        }
        let config = LmConfig::default();
        let reduced = minimize(&problem, x.clone(), &config);
        let dense = minimize(&Dense(&problem), x, &config);
        assert!(reduced.termination.converged() && dense.termination.converged());
        assert_eq!(reduced.jacobian.shape(), (3, 3));
        assert!((reduced.cost - dense.cost).abs() <= 1e-12 * dense.cost);
        for k in 0..3 {
            let (a, b) = (reduced.x[k], dense.x[k]);
            assert!(
                (a - b).abs() <= 1e-9 * b.abs().max(1.0),
                "x[{k}]: {a} vs {b}"
            );
        }
    }
}
