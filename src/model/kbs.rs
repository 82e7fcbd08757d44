//! Kirchhoff–Beckmann–Spizzichino scattering from a rough surface with Gaussian heights
//! and Gaussian correlation (Peters 2000, eq. 36–43).
//!
//! ```text
//! ⟨|ρ|²⟩ = e^{−g} [ ρ0² + (π T² F² / A) S(g, a) ]                (eq. 37)
//! L = s cos²θi ⟨|ρ|²⟩                                             (eq. 28)
//! g = (2πσ/λ)² (cos θi + cos θr)²,  a = v_xy² T² / 4
//! ```
//!
//! Without patch half-sizes the coherent ρ0² term is left out and A = λ² (so s does not
//! depend on the length unit); with (X, Y) it is included and A = 4XY.
//!
//! Evaluated as L = s π (T/λ)² h² (kσ)² Q(g, a) with h = |v|²/(2k²) and
//! Q = e^{−g} S / g ([`super::series`]): cos²θi F² = h²/c² and g = (kσ c)², so the grazing
//! factors cancel analytically and L stays finite as cos θi → 0 or c → 0.
//!
//! | parameter | unit | domain |
//! |---|---|---|
//! | `sigma` (σ) | unit of λ | > 0 |
//! | `T` | unit of λ | > 0 |
//! | `scale` (s) | 1 | > 0 |
//! | `n` (with `--fresnel`) | 1 | > 0 |
//! | `kappa` (κ, with `--fresnel conductor`) | 1 | > 0 |
//!
//! Options `fresnel` and `shadowing` multiply the whole lobe by the normalised Fresnel
//! factor F(θ_loc; n, κ) ([`super::fresnel`]) and Smith's G(θi, θr; T/σ)
//! ([`super::shadowing`]); the Jacobian gains the columns ∂L/∂n, ∂L/∂κ after `scale`, and
//! G's dependence on T/σ enters the σ and T columns. The factors' own errors (≤ 1e-13
//! relative) add to the accuracy below.
//!
//! Accuracy: in `series` and `auto` modes, relative `tol` (default 1e-10) on L for results
//! that are normal floating-point numbers, and |Δ ∂ln L/∂ln σ|, |Δ ∂ln L/∂ln T| ≤
//! 2 tol (1 + |·|) on the Jacobian, plus rounding of a few ulps times the condition number
//! (see [`super::series`]; checked against a 60-digit reference in `tests/lib/kbs_reference.rs`,
//! worst measured relative error of L 3e-12). `smooth` and `rough` are the paper's
//! approximations (eq. 42, 43), exact only in their limits.

use super::fresnel::{self, schlick_ratio, Fresnel, FresnelValue};
use super::shadowing::{self, ShadowValue, Shadowing};
use super::{series, EvalMode, Mode, Model, ModelOptions, ParamSpec};
use crate::error::{Error, Result};
use crate::geometry::{FactorColumns, Geometry};
use std::f64::consts::PI;

/// The KBS model with a chosen evaluation mode.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Kbs {
    /// The evaluation mode and tolerance, the patch size and the Fresnel and shadowing
    /// factors.
    pub opts: ModelOptions,
}

pub(crate) const SIGMA: ParamSpec = ParamSpec {
    name: "sigma",
    unit: "λ unit",
    positive: true,
    lower: 0.0,
    doc: "rms surface height σ",
};
pub(crate) const CORR_LEN: ParamSpec = ParamSpec {
    name: "T",
    unit: "λ unit",
    positive: true,
    lower: 0.0,
    doc: "surface correlation length T",
};

/// The index of a dielectric (and Schlick's F₀ from it): n > 1, the sample denser than
/// the air it is measured in. n < 1 would be total internal reflection, which no sample
/// in air shows (its F is constant beyond the critical angle: towards n → 0 a second
/// copy of `scale`); Schlick's F is the same at n and 1/n.
pub(crate) const INDEX_N: ParamSpec = ParamSpec {
    name: "n",
    unit: "1",
    positive: true,
    lower: 1.0,
    doc: "refractive index n (> 1)",
};
/// The real part of a conductor's complex index (a metal's lies below 1: silver ≈ 0.05).
pub(crate) const INDEX_N_CONDUCTOR: ParamSpec = ParamSpec {
    name: "n",
    unit: "1",
    positive: true,
    lower: 0.0,
    doc: "refractive index n (real part)",
};
pub(crate) const KAPPA: ParamSpec = ParamSpec {
    name: "kappa",
    unit: "1",
    positive: true,
    lower: 0.0,
    doc: "extinction coefficient κ (imaginary part of the index)",
};

const PARAMS: [ParamSpec; 3] = [SIGMA, CORR_LEN, super::lambert::SCALE];
const PARAMS_N: [ParamSpec; 4] = [SIGMA, CORR_LEN, super::lambert::SCALE, INDEX_N];
const PARAMS_NK: [ParamSpec; 5] = [
    SIGMA,
    CORR_LEN,
    super::lambert::SCALE,
    INDEX_N_CONDUCTOR,
    KAPPA,
];

/// Per-sample KBS value and its derivatives.
#[derive(Debug, Clone, Copy)]
pub(crate) struct KbsPoint {
    /// Radiance (incoherent + coherent).
    pub value: f64,
    /// ∂L/∂σ, ∂L/∂T, ∂L/∂s.
    pub d_sigma: f64,
    pub d_corr: f64,
    pub d_scale: f64,
}

impl Kbs {
    /// A KBS model; `opts.tol` must lie in [1e-16, 0.1], patch sizes must be positive.
    pub(crate) fn new(opts: ModelOptions) -> Result<Self> {
        let (lo, hi) = super::TOL_RANGE;
        if !(lo..=hi).contains(&opts.tol) {
            return Err(Error::Usage(format!(
                "tolerance {} is outside [1e-16, 0.1]",
                opts.tol
            )));
        }
        if let Some((x, y)) = opts.patch {
            if !(x.is_finite() && y.is_finite() && x > 0.0 && y > 0.0) {
                return Err(Error::Usage(format!(
                    "patch half-sizes X={x}, Y={y} must be finite and positive"
                )));
            }
        }
        Ok(Kbs { opts })
    }

    /// The lobe at `p` = (σ, T, s, then the Fresnel parameters) into `out`; with `jac`, the
    /// σ, T, s columns (column-major, 3 · len) and the Fresnel parameters' columns.
    pub(crate) fn lobe(
        &self,
        geo: &Geometry,
        p: &[f64],
        out: &mut [f64],
        jac: Option<(&mut [f64], &mut [f64])>,
    ) {
        let batch = self.batch_ln_q(geo, p[0], p[1]);
        self.lobe_from(geo, p, &batch, out, jac);
    }

    /// [`Self::lobe`]'s values with the evaluation mode of each sample, from one evaluation
    /// of ln Q (a forced mode is every sample's).
    pub(crate) fn lobe_modes(&self, geo: &Geometry, p: &[f64], out: &mut [f64]) -> Vec<Mode> {
        let batch = self.batch_ln_q(geo, p[0], p[1]);
        self.lobe_from(geo, p, &batch, out, None);
        match self.forced_mode() {
            Some(m) => vec![m; geo.len()],
            None => batch.2.iter().map(|q| q.mode).collect(),
        }
    }

    /// The mode every sample is evaluated in when the options force one.
    fn forced_mode(&self) -> Option<Mode> {
        match self.opts.mode {
            EvalMode::Series => Some(Mode::Series),
            EvalMode::Smooth => Some(Mode::Smooth),
            EvalMode::Rough => Some(Mode::Rough),
            EvalMode::Auto => None,
        }
    }

    /// [`Self::lobe`] from the batch's g, a and ln Q ([`Self::batch_ln_q`]).
    fn lobe_from(
        &self,
        geo: &Geometry,
        p: &[f64],
        (g, a, q): &(Vec<f64>, Vec<f64>, Vec<series::LnQ>),
        out: &mut [f64],
        jac: Option<(&mut [f64], &mut [f64])>,
    ) {
        let (sigma, corr, s) = (p[0], p[1], p[2]);
        let n = geo.len();
        let point = |i: usize| self.point_from(geo, i, sigma, corr, s, g[i], a[i], q[i]);
        let fc = self.opts.has_factors().then(|| geo.factor_columns());
        match (jac, fc) {
            (None, None) => {
                for (i, o) in out.iter_mut().enumerate() {
                    *o = point(i).value;
                }
            }
            (None, Some(fc)) => {
                // The factor of every sample first (a loop of independent samples), then
                // the lobe times it.
                let m = self.factors(fc, p, |f, sh| f.f * sh.g);
                for (i, o) in out.iter_mut().enumerate() {
                    *o = point(i).value * m[i];
                }
            }
            (Some((j, j_f)), fc) => {
                // G of every sample first, and F with its derivatives four samples at a
                // time where the form has lanes; then the lobe times them.
                let shadows = fc.map(|fc| (fc, self.shadow_each(fc, corr / sigma, |_, sh| sh)));
                let (fresnel, fp) = (self.opts.fresnel, &p[3..]);
                let lanes = matches!(fresnel, Fresnel::Conductor | Fresnel::Dielectric);
                let fresnels = fc
                    .filter(|_| lanes)
                    .map(|fc| fresnel_each(fresnel, &fc.cos_loc, fp));
                let shared = (1.0 / sigma, 1.0 / corr);
                let (j_sigma, rest) = j.split_at_mut(n);
                let (j_corr, j_s) = rest.split_at_mut(n);
                for i in 0..n {
                    let (pt, d_n, d_kappa) = match &shadows {
                        Some((fc, sh)) => {
                            let f = match &fresnels {
                                Some(f) => f[i],
                                None => fresnel.eval(fc.cos_loc[i], fp),
                            };
                            with_factors(point(i), (f, sh[i]), shared)
                        }
                        None => (point(i), 0.0, 0.0),
                    };
                    out[i] = pt.value;
                    j_sigma[i] = pt.d_sigma;
                    j_corr[i] = pt.d_corr;
                    j_s[i] = pt.d_scale;
                    if let Some(c) = j_f.get_mut(i) {
                        *c = d_n;
                    }
                    if let Some(c) = j_f.get_mut(n + i) {
                        *c = d_kappa;
                    }
                }
            }
        }
    }

    /// `each(F, G)` of every sample at the parameters `p` (σ, T, s, then the Fresnel
    /// parameters) from the batch's factor columns `fc`: one loop per Fresnel form.
    #[inline(always)]
    fn factors<T>(
        &self,
        fc: &FactorColumns,
        p: &[f64],
        each: impl Fn(FresnelValue, ShadowValue) -> T,
    ) -> Vec<T> {
        let (fp, cos_loc, t_over_sigma) = (&p[3..], &fc.cos_loc[..], p[1] / p[0]);
        match self.opts.fresnel {
            Fresnel::None => self.shadow_each(fc, t_over_sigma, |_, sh| {
                each(Fresnel::None.eval(0.0, fp), sh)
            }),
            Fresnel::Dielectric | Fresnel::Conductor => {
                let f = fresnel_each(self.opts.fresnel, cos_loc, fp);
                self.shadow_each(fc, t_over_sigma, |i, sh| each(f[i], sh))
            }
            Fresnel::Schlick => self.shadow_each(fc, t_over_sigma, |i, sh| {
                each(schlick_ratio(cos_loc[i], fp[0]), sh)
            }),
        }
    }

    /// `each(i, G_i)` of every sample i at T/σ = `t_over_sigma`: Smith's Λ from each
    /// sample's (cot θ, tan θ), or once per distinct polar angle when the samples share
    /// them ([`crate::geometry::PolarAngles`]).
    #[inline(always)]
    fn shadow_each<T>(
        &self,
        fc: &FactorColumns,
        t_over_sigma: f64,
        each: impl Fn(usize, ShadowValue) -> T,
    ) -> Vec<T> {
        let shadowing = self.opts.shadowing;
        let n = fc.cos_loc.len();
        let k = 0.5 * t_over_sigma;
        let k = (k, 1.0 / k);
        if shadowing == Shadowing::None {
            return (0..n).map(|i| each(i, ShadowValue::ONE)).collect();
        }
        let g = |li, lr| shadowing.combine(li, lr);
        match &fc.polar {
            Some(polar) => {
                let lam = lambdas(&polar.cot_tan, k);
                let (at_i, at_r) = (&polar.incidence, &polar.view);
                (0..n)
                    .map(|i| each(i, g(lam[at_i[i] as usize], lam[at_r[i] as usize])))
                    .collect()
            }
            None => {
                let (li, lr) = (lambdas(&fc.incidence, k), lambdas(&fc.view, k));
                (0..n).map(|i| each(i, g(li[i], lr[i]))).collect()
            }
        }
    }

    /// ln Q of every sample (evaluated together, [`series::ln_q_batch`]), with g and a.
    fn batch_ln_q(
        &self,
        geo: &Geometry,
        sigma: f64,
        corr: f64,
    ) -> (Vec<f64>, Vec<f64>, Vec<series::LnQ>) {
        let (g, a): (Vec<f64>, Vec<f64>) = (0..geo.len())
            .map(|i| (geo.g(i, sigma), geo.a(i, corr)))
            .unzip();
        let mut q = vec![series::smooth(0.0, 0.0); geo.len()];
        series::ln_q_batch(&g, &a, self.opts.mode, self.opts.tol, &mut q);
        (g, a, q)
    }

    /// Radiance at sample i from its g, a and ln Q.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn point_from(
        &self,
        geo: &Geometry,
        i: usize,
        sigma: f64,
        corr: f64,
        s: f64,
        g: f64,
        a: f64,
        q: series::LnQ,
    ) -> KbsPoint {
        let lambda = geo.wavelength[i];
        let k_sigma = 2.0 * PI * sigma / lambda;
        let t = corr / lambda;
        let area = match self.opts.patch {
            Some((x, y)) => 4.0 * x * y / (lambda * lambda),
            None => 1.0,
        };
        let h = geo.h(i);
        // pref · Q directly while both are comfortably normal; otherwise in logarithms (the
        // product can be normal when a factor is not). s enters linearly (it may be ≤ 0
        // inside a fit's linear solve), outside the logarithm.
        let pref = (PI * t * t / area) * (h * k_sigma) * (h * k_sigma);
        let unit = if q.ln_q == f64::NEG_INFINITY {
            // Q = 0 (the flat-surface limit): so is the radiance, whatever the prefactor.
            0.0
        } else if pref.is_normal() && q.ln_q.abs() < 700.0 {
            pref * q.ln_q.exp()
        } else {
            let ln_pref = if pref.is_normal() {
                pref.ln()
            } else {
                (PI * t * t / area).ln() + 2.0 * h.ln() + 2.0 * k_sigma.ln()
            };
            // Below e^−746 the result is 0 (and libm's exp takes a slow path to say so).
            let ln_unit = ln_pref + q.ln_q;
            if ln_unit < -746.0 {
                0.0
            } else {
                ln_unit.exp()
            }
        };
        let inc = s * unit;
        let mut value = inc;
        let mut d_scale = unit;
        let mut d_sigma = scaled(inc, 2.0 + 2.0 * g * q.d_g, sigma);
        let d_corr = scaled(inc, 2.0 + 2.0 * a * q.d_a, corr);
        if let Some((x, y)) = self.opts.patch {
            let k = 2.0 * PI / lambda;
            let (vx, vy) = geo.v_xy(i);
            let rho0 = sinc(k * vx * x) * sinc(k * vy * y);
            let coh_unit = geo.cos_i[i].powi(2) * (-g).exp() * rho0 * rho0;
            let coh = s * coh_unit;
            value += coh;
            d_scale += coh_unit;
            d_sigma -= 2.0 * g / sigma * coh;
        }
        KbsPoint {
            value,
            d_sigma,
            d_corr,
            d_scale,
        }
    }
}

/// F with ∂F/∂n, ∂F/∂κ at each `cos_loc` for the Fresnel parameters `fp` ((n, κ) or n)
/// of the conductor or dielectric form `fresnel` ([`fresnel::conductor`],
/// [`fresnel::dielectric`]: four at a time).
fn fresnel_each(fresnel: Fresnel, cos_loc: &[f64], fp: &[f64]) -> Vec<FresnelValue> {
    let mut out = vec![FresnelValue::ONE; cos_loc.len()];
    match fresnel {
        Fresnel::Conductor => fresnel::conductor(cos_loc, fp[0], fp[1], &mut out),
        _ => fresnel::dielectric(cos_loc, fp[0], &mut out),
    }
    out
}

/// Λ and ν ∂Λ/∂ν of each direction's (cot θ, tan θ) at `(k, 1/k)`, k = T/(2σ)
/// ([`shadowing::directions`]: four at a time).
fn lambdas(cot_tan: &[(f64, f64)], k: (f64, f64)) -> Vec<(f64, f64)> {
    let mut out = vec![(0.0, 0.0); cot_tan.len()];
    shadowing::directions(cot_tan, k, &mut out);
    out
}

/// The point times the factors F and G of its sample, with ∂L/∂n and ∂L/∂κ
/// (`(1/σ, 1/T)` computed once per batch).
#[inline(always)]
fn with_factors(
    pt: KbsPoint,
    (f, sh): (FresnelValue, ShadowValue),
    (inv_sigma, inv_corr): (f64, f64),
) -> (KbsPoint, f64, f64) {
    let m = f.f * sh.g;
    let value = pt.value * m;
    // G depends on T/σ only: ∂ln G/∂ln σ = −∂ln G/∂ln T (0 where L is 0).
    let d_ln = if value == 0.0 { 0.0 } else { value * sh.d_ln_t };
    let lit = pt.value * sh.g;
    let out = KbsPoint {
        value,
        d_sigma: pt.d_sigma * m - d_ln * inv_sigma,
        d_corr: pt.d_corr * m + d_ln * inv_corr,
        d_scale: pt.d_scale * m,
    };
    (out, lit * f.d_n, lit * f.d_kappa)
}

/// inc · `factor` / x: a derivative of the radiance `inc` from its log-derivative factor;
/// 0 where the radiance is 0 and the factor is not finite (at g = ∞ or a = ∞, the rough and
/// flat limits of an extreme parameter, g ∂lnQ/∂g or a ∂lnQ/∂a is ∞ · 0).
#[inline]
fn scaled(inc: f64, factor: f64, x: f64) -> f64 {
    if inc == 0.0 && !factor.is_finite() {
        0.0
    } else {
        inc * factor / x
    }
}

/// sin(x)/x, 1 at 0.
#[inline]
pub(crate) fn sinc(x: f64) -> f64 {
    if x.abs() < 1e-4 {
        1.0 - x * x / 6.0
    } else {
        x.sin() / x
    }
}

impl Model for Kbs {
    fn name(&self) -> &'static str {
        match self.opts.mode {
            EvalMode::Smooth => "kbs-smooth",
            EvalMode::Rough => "kbs-rough",
            _ => "kbs",
        }
    }

    fn params(&self) -> &'static [ParamSpec] {
        match self.opts.fresnel.param_count() {
            0 => &PARAMS,
            1 => &PARAMS_N,
            _ => &PARAMS_NK,
        }
    }

    fn radiance(&self, geo: &Geometry, p: &[f64], out: &mut [f64], jac: Option<&mut [f64]>) {
        let n = geo.len();
        self.lobe(geo, p, out, jac.map(|j| j.split_at_mut(3 * n)));
    }

    fn options(&self) -> Option<ModelOptions> {
        Some(self.opts)
    }

    fn radiance_modes(&self, geo: &Geometry, p: &[f64], out: &mut [f64]) -> Vec<Mode> {
        self.lobe_modes(geo, p, out)
    }
}
