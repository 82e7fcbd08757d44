//! KBS + Lambertian: surface (KBS) plus body (Lambertian) reflection,
//! L = s cos²θi ⟨|ρ|²⟩ + s_d cos θi (docs/conventions.md, "Models").
//!
//! | parameter | unit | domain |
//! |---|---|---|
//! | `sigma` (σ) | unit of λ | > 0 |
//! | `T` | unit of λ | > 0 |
//! | `scale` (s) | 1 | > 0 |
//! | `scale_d` (s_d) | 1 | > 0 |
//! | `n`, `kappa` (with `--fresnel`) | 1 | > 0 |
//!
//! The Fresnel and shadowing factors (options `fresnel`, `shadowing`) multiply the KBS part
//! only; their parameters follow `scale_d`.
//!
//! Accuracy: that of [`super::kbs::Kbs`]; the Lambertian part is exact to rounding.

use super::kbs::{Kbs, CORR_LEN, INDEX_N, INDEX_N_CONDUCTOR, KAPPA, SIGMA};
use super::{Mode, Model, ModelOptions, ParamSpec};
use crate::error::Result;
use crate::geometry::Geometry;

/// KBS surface scattering plus a Lambertian body term.
#[derive(Debug, Clone, Copy)]
pub(crate) struct KbsLambert {
    /// The KBS lobe (its options: mode, factors); the Lambertian term has none.
    pub kbs: Kbs,
}

const SCALE_D: ParamSpec = ParamSpec {
    name: "scale_d",
    unit: "1",
    positive: true,
    lower: 0.0,
    doc: "Lambertian (body) scale s_d",
};
const PARAMS: [ParamSpec; 4] = [SIGMA, CORR_LEN, super::lambert::SCALE, SCALE_D];
const PARAMS_N: [ParamSpec; 5] = [SIGMA, CORR_LEN, super::lambert::SCALE, SCALE_D, INDEX_N];
const PARAMS_NK: [ParamSpec; 6] = [
    SIGMA,
    CORR_LEN,
    super::lambert::SCALE,
    SCALE_D,
    INDEX_N_CONDUCTOR,
    KAPPA,
];

impl KbsLambert {
    /// See [`Kbs::new`] for the options' domain.
    pub(crate) fn new(opts: ModelOptions) -> Result<Self> {
        Ok(KbsLambert {
            kbs: Kbs::new(opts)?,
        })
    }
}

/// The KBS lobe's parameters within the model's `p` (σ, T, s, then the Fresnel ones, which
/// follow s_d in `p`), and how many Fresnel parameters there are.
fn lobe_params(p: &[f64]) -> ([f64; 5], usize) {
    let mut kp = [0.0; 5];
    kp[..3].copy_from_slice(&p[..3]);
    let nf = p.len() - 4;
    kp[3..3 + nf].copy_from_slice(&p[4..]);
    (kp, nf)
}

/// The Lambertian term s_d cos θi added to the lobe's values.
fn add_diffuse(geo: &Geometry, s_d: f64, out: &mut [f64]) {
    for (o, c) in out.iter_mut().zip(&geo.cos_i) {
        *o += s_d * c;
    }
}

impl Model for KbsLambert {
    fn name(&self) -> &'static str {
        "kbs+lambert"
    }

    fn params(&self) -> &'static [ParamSpec] {
        match self.kbs.opts.fresnel.param_count() {
            0 => &PARAMS,
            1 => &PARAMS_N,
            _ => &PARAMS_NK,
        }
    }

    fn radiance(&self, geo: &Geometry, p: &[f64], out: &mut [f64], jac: Option<&mut [f64]>) {
        let n = geo.len();
        let (kp, nf) = lobe_params(p);
        let kp = &kp[..3 + nf];
        match jac {
            None => self.kbs.lobe(geo, kp, out, None),
            Some(j) => {
                let (j_kbs, rest) = j.split_at_mut(3 * n);
                let (j_d, j_f) = rest.split_at_mut(n);
                self.kbs.lobe(geo, kp, out, Some((j_kbs, j_f)));
                j_d.copy_from_slice(&geo.cos_i);
            }
        }
        add_diffuse(geo, p[3], out);
    }

    fn options(&self) -> Option<ModelOptions> {
        Some(self.kbs.opts)
    }

    fn radiance_modes(&self, geo: &Geometry, p: &[f64], out: &mut [f64]) -> Vec<Mode> {
        let (kp, nf) = lobe_params(p);
        let modes = self.kbs.lobe_modes(geo, &kp[..3 + nf], out);
        add_diffuse(geo, p[3], out);
        modes
    }
}
