//! The domain a fit's point may run to: σ and T positive, g and a below the limits where
//! the models keep their stated cost and accuracy, a Gaussian lobe no narrower than the
//! angular sampling resolves. Outside it the solver sees non-finite residuals and rejects
//! the step.

use super::{Block, FitInput, FitProblem, ParamLayout};
use crate::geometry::Geometry;
use crate::model::Model;

/// Largest g a fit may step to: beyond it a trial step is rejected (σ ≫ λ is far past any
/// scene the data could tell from the rough limit).
pub(crate) const G_FIT_MAX: f64 = 1e7;

/// Largest a = v_xy² T²/4 a fit may step to (T ≫ λ: the lobe is narrower than e^{-1e10}).
pub(crate) const A_FIT_MAX: f64 = 1e10;

/// The (σ, T) of each channel under full parameters `p` (empty for models without them),
/// or None when `p` is not finite or some σ, T is not a positive normal number: the part of
/// [`FitProblem::in_domain`] that does not depend on the samples.
fn channel_roughness(
    model: &dyn Model,
    layout: &ParamLayout,
    p: &[f64],
) -> Option<Vec<(f64, f64)>> {
    if !p.iter().all(|v| v.is_finite()) {
        return None;
    }
    let specs = model.params();
    let find = |name: &str| specs.iter().position(|s| s.name == name);
    let (Some(js), Some(jt)) = (find("sigma"), find("T")) else {
        return Some(Vec::new());
    };
    let good = |v: f64| v.is_normal() && v > 0.0;
    layout
        .index
        .iter()
        .map(|ix| (p[ix[js]], p[ix[jt]]))
        .map(|(sigma, corr)| (good(sigma) && good(corr)).then_some((sigma, corr)))
        .collect()
}

/// The lower bound of a Gaussian lobe's width over these samples: (model parameter index
/// of `w`, bound), None for models without a lobe or samples that resolve no width.
pub(super) fn width_floor(model: &dyn Model, geo: &Geometry) -> Option<(usize, f64)> {
    let jw = model.params().iter().position(|s| s.name == "w")?;
    Some((jw, geo.width_floor()?))
}

/// Whether every channel's lobe width w is at least its floor (true without one).
fn width_resolved(layout: &ParamLayout, floor: Option<(usize, f64)>, p: &[f64]) -> bool {
    floor.is_none_or(|(jw, w_min)| layout.index.iter().all(|ix| p[ix[jw]] >= w_min))
}

/// Whether sample i of `geo` stays within the fit's limits of g and a at σ, T.
#[inline]
fn sample_in_domain(geo: &Geometry, i: usize, (sigma, corr): (f64, f64)) -> bool {
    geo.g(i, sigma) <= G_FIT_MAX && geo.a(i, corr) <= A_FIT_MAX
}

impl FitProblem<'_> {
    /// How near full parameters `p` come to the edge of the domain of [`Self::in_domain`]:
    /// the largest of g/[`G_FIT_MAX`] and a/[`A_FIT_MAX`] over the samples (0 for models
    /// without σ and T, ∞ where σ or T is not a positive normal number).
    pub(crate) fn domain_fraction(&self, p: &[f64]) -> f64 {
        let Some(sc) = channel_roughness(self.model, &self.layout, p) else {
            return f64::INFINITY;
        };
        if sc.is_empty() {
            return 0.0;
        }
        let mut worst = 0.0f64;
        for b in &self.blocks {
            let (sigma, corr) = sc[b.channel];
            for i in 0..b.geo.len() {
                worst = worst.max(b.geo.g(i, sigma) / G_FIT_MAX);
                worst = worst.max(b.geo.a(i, corr) / A_FIT_MAX);
            }
        }
        worst
    }

    /// Whether full parameters `p` keep every sample inside the domain where the models are
    /// evaluated at their stated cost and accuracy: finite values, σ, T > 0 and normal,
    /// g ≤ [`G_FIT_MAX`], a ≤ [`A_FIT_MAX`], and a Gaussian lobe no narrower than half the
    /// narrowest width the angular sampling resolves
    /// ([`Geometry::width_floor`]). Outside, the solver sees non-finite residuals and
    /// rejects the step.
    pub(crate) fn in_domain(&self, p: &[f64]) -> bool {
        let Some(sc) = channel_roughness(self.model, &self.layout, p) else {
            return false;
        };
        if !width_resolved(&self.layout, self.w_floor, p) {
            return false;
        }
        sc.is_empty() || self.blocks.iter().all(|b| b.in_domain(sc[b.channel]))
    }
}

impl FitInput {
    /// `FitProblem::in_domain` for these samples, without building the problem.
    pub fn in_domain(&self, model: &dyn Model, layout: &ParamLayout, p: &[f64]) -> bool {
        let Some(sc) = channel_roughness(model, layout, p) else {
            return false;
        };
        if !width_resolved(layout, width_floor(model, &self.geo), p) {
            return false;
        }
        sc.is_empty()
            || (0..self.geo.len()).all(|i| sample_in_domain(&self.geo, i, sc[self.channel[i]]))
    }
}

impl Block {
    /// Whether every sample stays within the fit's limits of g and a at σ, T: decided from
    /// [`Self::reach`] unless the bound lies within rounding of a limit, then sample by
    /// sample (the same answer as [`sample_in_domain`] on each).
    fn in_domain(&self, (sigma, corr): (f64, f64)) -> bool {
        const ROUNDING: f64 = 1e-12;
        let tau = 2.0 * std::f64::consts::PI;
        let g = (tau * sigma * self.reach.0).powi(2);
        let a = (tau * corr).powi(2) * self.reach.1 * 0.25;
        if g * (1.0 + ROUNDING) <= G_FIT_MAX && a * (1.0 + ROUNDING) <= A_FIT_MAX {
            return true;
        }
        if g * (1.0 - ROUNDING) > G_FIT_MAX || a * (1.0 - ROUNDING) > A_FIT_MAX {
            return false;
        }
        (0..self.geo.len()).all(|i| sample_in_domain(&self.geo, i, (sigma, corr)))
    }
}

#[cfg(test)]
mod tests {
    use super::{sample_in_domain, A_FIT_MAX, G_FIT_MAX};
    use crate::fit::problem::{Block, Rows};
    use crate::geometry::{Geometry, Quantity, Sample};

    /// Samples from normal incidence to 89.9°, in and out of plane, at two wavelengths.
    fn block() -> Block {
        let mut samples = Vec::new();
        let mut wavelength = Vec::new();
        for (k, deg) in [0.0, 10.0, 45.0, 70.0, 89.9].iter().enumerate() {
            for phi in [0.0, 1.0, std::f64::consts::PI] {
                let t = f64::to_radians(*deg);
                samples.push(Sample {
                    theta_i: t,
                    theta_r: 0.5 * t,
                    phi_r: phi,
                });
                wavelength.push(if k % 2 == 0 { 0.5 } else { 0.9 });
            }
        }
        let geo = Geometry::new(&samples, &wavelength, Quantity::Radiance).unwrap();
        let n = geo.len();
        Block::new(geo, Rows::Run(0..n), 0)
    }

    #[test]
    fn block_domain_check_agrees_with_each_sample_at_the_limits() {
        let b = block();
        let each = |sc: (f64, f64)| (0..b.geo.len()).all(|i| sample_in_domain(&b.geo, i, sc));
        // σ and T that put the block's largest g or a at the limit, then a relative step of
        // 1e-15 … 1e-3 either side of it: the bound and the per-sample check agree at each.
        let g_max = (0..b.geo.len())
            .map(|i| b.geo.g(i, 1.0))
            .fold(0.0, f64::max);
        let a_max = (0..b.geo.len())
            .map(|i| b.geo.a(i, 1.0))
            .fold(0.0, f64::max);
        let sigma_edge = (G_FIT_MAX / g_max).sqrt();
        let corr_edge = (A_FIT_MAX / a_max).sqrt();
        let mut checked = (0, 0);
        for step in [0.0, 1e-15, 1e-13, 1e-11, 1e-6, 1e-3] {
            for sign in [-1.0, 1.0] {
                let f = 1.0 + sign * step;
                for sc in [
                    (sigma_edge * f, 1.0),
                    (1e-3, corr_edge * f),
                    (sigma_edge * f, corr_edge * f),
                ] {
                    let inside = each(sc);
                    assert_eq!(b.in_domain(sc), inside, "σ, T = {sc:?}");
                    if inside {
                        checked.0 += 1
                    } else {
                        checked.1 += 1
                    }
                }
            }
        }
        assert!(
            checked.0 > 5 && checked.1 > 5,
            "both sides reached: {checked:?}"
        );
    }
}
