//! KBS + Lambertian: surface (KBS) plus body (Lambertian) reflection,
//! L = s cos²θi ⟨|ρ|²⟩ + s_d cos θi (docs/conventions.md, "Models").
//!
//! | parameter | unit | domain |
//! |---|---|---|
//! | `sigma` (σ) | unit of λ | > 0 |
//! | `T` | unit of λ | > 0 |
//! | `scale` (s) | 1 | > 0 |
//! | `scale_d` (s_d) | 1 | > 0 |
//!
//! Accuracy: that of [`super::kbs::Kbs`]; the Lambertian part is exact to rounding.

use super::kbs::{Kbs, CORR_LEN, SIGMA};
use super::{Mode, Model, ModelOptions, ParamSpec};
use crate::error::Result;
use crate::geometry::Geometry;

/// KBS surface scattering plus a Lambertian body term.
#[derive(Debug, Clone, Copy)]
pub struct KbsLambert {
    pub kbs: Kbs,
}

const PARAMS: [ParamSpec; 4] = [
    SIGMA,
    CORR_LEN,
    super::lambert::SCALE,
    ParamSpec {
        name: "scale_d",
        unit: "1",
        positive: true,
        doc: "Lambertian (body) scale s_d",
    },
];

impl KbsLambert {
    /// See [`Kbs::new`] for the options' domain.
    pub fn new(opts: ModelOptions) -> Result<Self> {
        Ok(KbsLambert {
            kbs: Kbs::new(opts)?,
        })
    }
}

impl Model for KbsLambert {
    fn name(&self) -> &'static str {
        "kbs+lambert"
    }

    fn params(&self) -> &'static [ParamSpec] {
        &PARAMS
    }

    fn radiance(&self, geo: &Geometry, p: &[f64], out: &mut [f64], jac: Option<&mut [f64]>) {
        let n = geo.len();
        match jac {
            None => self.kbs.radiance(geo, &p[..3], out, None),
            Some(j) => {
                let (j_kbs, j_d) = j.split_at_mut(3 * n);
                self.kbs.radiance(geo, &p[..3], out, Some(j_kbs));
                j_d.copy_from_slice(&geo.cos_i);
            }
        }
        for (o, c) in out.iter_mut().zip(&geo.cos_i) {
            *o += p[3] * c;
        }
    }

    fn modes(&self, geo: &Geometry, p: &[f64]) -> Vec<Mode> {
        self.kbs.modes(geo, &p[..3])
    }
}
