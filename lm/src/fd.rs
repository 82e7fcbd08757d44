//! Finite-difference Jacobians, for models without an analytic one.

use nalgebra::{DMatrix, DVector};

use super::EPSMCH;

/// Finite-difference Jacobian of `f` at `x`, for models without an analytic one.
///
/// * With `r0 = Some(f(x))`: forward differences (`n` evaluations), step
///   `hⱼ = √ε · |xⱼ|` (`√ε` when `xⱼ = 0`), as MINPACK `fdjac2`; error `O(√ε)` relative.
/// * With `r0 = None`: central differences (`2n` evaluations), step `hⱼ = ε^{1/3} · max(|xⱼ|, 1e-8)`
///   … capped below by `ε^{1/3}·1e-8`; error `O(ε^{2/3})` relative.
///
/// In both cases the step is rounded so that `xⱼ + hⱼ` is exactly representable.
pub fn finite_difference_jacobian<F: Fn(&DVector<f64>) -> DVector<f64>>(
    f: F,
    x: &DVector<f64>,
    r0: Option<&DVector<f64>>,
) -> DMatrix<f64> {
    let n = x.len();
    let mut xt = x.clone();
    match r0 {
        Some(r0) => {
            let mut jac = DMatrix::zeros(r0.len(), n);
            for j in 0..n {
                let xj = x[j];
                let mut h = EPSMCH.sqrt() * xj.abs();
                if h == 0.0 {
                    h = EPSMCH.sqrt();
                }
                xt[j] = xj + h;
                let h = xt[j] - xj;
                let r1 = f(&xt);
                xt[j] = xj;
                for i in 0..r0.len().min(r1.len()) {
                    jac[(i, j)] = (r1[i] - r0[i]) / h;
                }
            }
            jac
        }
        None => {
            let mut jac: Option<DMatrix<f64>> = None;
            for j in 0..n {
                let xj = x[j];
                let h = EPSMCH.cbrt() * xj.abs().max(1e-8);
                xt[j] = xj + h;
                let hp = xt[j] - xj;
                let rp = f(&xt);
                xt[j] = xj - h;
                let hm = xj - xt[j];
                let rm = f(&xt);
                xt[j] = xj;
                let jac = jac.get_or_insert_with(|| DMatrix::zeros(rp.len(), n));
                for i in 0..jac.nrows().min(rp.len()).min(rm.len()) {
                    jac[(i, j)] = (rp[i] - rm[i]) / (hp + hm);
                }
            }
            jac.unwrap_or_else(|| DMatrix::zeros(f(x).len(), 0))
        }
    }
}
