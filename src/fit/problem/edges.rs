//! Edges: the limits of the physical domain a fit's point can run to (a KBS lobe with
//! T/σ → 0 or kT → 0, an amplitude at its lower bound 0), checked by the start search, the
//! solve and the acceptance of the result.

use super::{FitInput, FitParam, ParamLayout};

/// T/σ below which a KBS lobe is not a surface's specular lobe: Beckmann's α = 2σ/T > 20
/// is far outside the paper's domain, and the lobe then only mimics a diffuse term.
pub(crate) const MIN_T_OVER_SIGMA: f64 = 0.1;

/// k·T = 2πT/λ below which a KBS lobe is wider than the hemisphere (its angular width in
/// v_xy is ~2/(kT) ≫ the largest v_xy ≈ 2): flat, so again only a second diffuse term.
pub(crate) const MIN_KT: f64 = 0.1;

/// Whether a KBS point (layout order) lies at an edge of the physical domain:
/// T/σ < [`MIN_T_OVER_SIGMA`] or 2πT/λ < [`MIN_KT`] (λ: the median wavelength of `input`).
/// The start search rejects such refined starts; false for models without σ and T.
pub(in crate::fit) fn at_kbs_edge(layout: &ParamLayout, input: &FitInput, p: &[f64]) -> bool {
    let first = |name: &str| layout.find(name).first().copied();
    let (Some(ks), Some(kt)) = (first("sigma"), first("T")) else {
        return false;
    };
    let lambda = input.geo.wavelength.median();
    let k_t = 2.0 * std::f64::consts::PI * p[kt] / lambda;
    below(p[kt] / p[ks], MIN_T_OVER_SIGMA) || below(k_t, MIN_KT)
}

/// Whether a free non-negative parameter at `value` with standard error `se` sits at its
/// lower bound 0 (within 10⁻³ standard errors, or exactly 0).
pub(in crate::fit) fn at_lower_bound(fp: &FitParam, value: f64, se: Option<f64>) -> bool {
    fp.fixed.is_none()
        && fp.transform.is_non_negative()
        && se.is_some_and(|e| value <= 1e-3 * e.max(f64::MIN_POSITIVE) || value == 0.0)
}

/// Whether `v` is below `limit` or not a number (NaN counts as past the edge).
pub(in crate::fit) fn below(v: f64, limit: f64) -> bool {
    v.partial_cmp(&limit) != Some(std::cmp::Ordering::Greater)
        && v.partial_cmp(&limit) != Some(std::cmp::Ordering::Equal)
}
