//! Lambertian reflection (Peters 2000, eq. 29–31).
//!
//! L = s · cos θi, with s = C·Ẽ10/π. For a BRDF (`Quantity::Brdf`) this is the constant s;
//! a Lambertian reflectance factor R is a BRDF × π, so s = R/π.
//!
//! | parameter | unit | domain |
//! |---|---|---|
//! | `scale` (s) | radiance per unit irradiance | > 0 |
//!
//! Exact to rounding (one multiplication per sample).

use super::{Model, ParamSpec};
use crate::geometry::Geometry;

/// The Lambertian model.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Lambert;

pub(crate) const SCALE: ParamSpec = ParamSpec {
    name: "scale",
    unit: "1",
    positive: true,
    lower: 0.0,
    doc: "overall scale s",
};

const PARAMS: [ParamSpec; 1] = [SCALE];

impl Model for Lambert {
    fn name(&self) -> &'static str {
        "lambert"
    }

    fn params(&self) -> &'static [ParamSpec] {
        &PARAMS
    }

    fn radiance(&self, geo: &Geometry, p: &[f64], out: &mut [f64], jac: Option<&mut [f64]>) {
        for (o, c) in out.iter_mut().zip(&geo.cos_i) {
            *o = p[0] * c;
        }
        if let Some(j) = jac {
            j.copy_from_slice(&geo.cos_i);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Quantity, Sample};

    #[test]
    fn cosine_law_and_constant_brdf() {
        let s: Vec<Sample> = [0.0, 60.0, 89.0]
            .iter()
            .map(|&t| Sample::from_degrees(t, 10.0, 0.0))
            .collect();
        let geo = Geometry::new(&s, &[1.0], Quantity::Radiance).unwrap();
        let mut out = vec![0.0; 3];
        Lambert.eval(&geo, &[2.0], &mut out, None);
        assert!((out[1] - 1.0).abs() < 1e-15);
        let geo = Geometry::new(&s, &[1.0], Quantity::Brdf).unwrap();
        Lambert.eval(&geo, &[2.0], &mut out, None);
        for v in out {
            assert!((v - 2.0).abs() < 1e-12);
        }
    }
}
