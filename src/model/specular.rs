//! Gaussian specular lobe and Lambertian + specular (Peters 2000, eq. 34–35).
//!
//! Lobe:  L_spec = B / (w √(2π)) · exp(−½ [((θr − θi)/w)² + (φr/(2w))²]),
//! with w the angular width in radians and φr wrapped to (−π, π].
//! Lambertian + specular: L = s cos θi + L_spec.
//!
//! | parameter | unit | domain |
//! |---|---|---|
//! | `scale` (s) | radiance per unit irradiance | > 0 |
//! | `B` | lobe strength (radiance · rad) | > 0 |
//! | `w` | rad | > 0 |
//!
//! Exact to rounding; the exponent is computed once per sample.

use super::{lambert::SCALE, Model, ParamSpec};
use crate::geometry::Geometry;

/// Lambertian + Gaussian specular lobe.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct LambertSpecular;

const PARAMS: [ParamSpec; 3] = [
    SCALE,
    ParamSpec {
        name: "B",
        unit: "1",
        positive: true,
        lower: 0.0,
        doc: "specular lobe strength",
    },
    ParamSpec {
        name: "w",
        unit: "rad",
        positive: true,
        lower: 0.0,
        doc: "specular lobe angular width",
    },
];

/// The Gaussian lobe of eq. 34 for one sample, and its exponent's quadratic form
/// q = (θr − θi)² + φr²/4 (so that ∂/∂w is cheap).
#[inline]
pub(crate) fn gaussian_lobe(b: f64, w: f64, theta_i: f64, theta_r: f64, phi_r: f64) -> (f64, f64) {
    let q = (theta_r - theta_i).powi(2) + 0.25 * phi_r * phi_r;
    let norm = b / (w * (2.0 * std::f64::consts::PI).sqrt());
    (norm * (-0.5 * q / (w * w)).exp(), q)
}

impl Model for LambertSpecular {
    fn name(&self) -> &'static str {
        "lambert-specular"
    }

    fn params(&self) -> &'static [ParamSpec] {
        &PARAMS
    }

    fn radiance(&self, geo: &Geometry, p: &[f64], out: &mut [f64], jac: Option<&mut [f64]>) {
        let (s, b, w) = (p[0], p[1], p[2]);
        let n = geo.len();
        let mut jac = jac;
        for i in 0..n {
            let (lobe, q) = gaussian_lobe(b, w, geo.theta_i[i], geo.theta_r[i], geo.phi_r[i]);
            out[i] = s * geo.cos_i[i] + lobe;
            if let Some(j) = jac.as_deref_mut() {
                j[i] = geo.cos_i[i];
                j[n + i] = lobe / b;
                j[2 * n + i] = lobe * (q / (w * w * w) - 1.0 / w);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Quantity, Sample};

    #[test]
    fn lobe_peaks_at_mirror_with_stated_height() {
        let w = 0.1;
        let (peak, _) = gaussian_lobe(1.0, w, 0.5, 0.5, 0.0);
        assert!((peak - 1.0 / (w * (2.0 * std::f64::consts::PI).sqrt())).abs() < 1e-14);
        // One width off in θr: e^{-1/2}; 2w off in φr: e^{-1/2}.
        let (off, _) = gaussian_lobe(1.0, w, 0.5, 0.5 + w, 0.0);
        assert!((off / peak - (-0.5f64).exp()).abs() < 1e-14);
        let (off, _) = gaussian_lobe(1.0, w, 0.5, 0.5, 2.0 * w);
        assert!((off / peak - (-0.5f64).exp()).abs() < 1e-14);
    }

    #[test]
    fn phi_is_wrapped() {
        let s = [
            Sample::from_degrees(30.0, 30.0, 350.0),
            Sample::from_degrees(30.0, 30.0, -10.0),
        ];
        let geo = Geometry::new(&s, &[1.0], Quantity::Radiance).unwrap();
        let mut out = [0.0; 2];
        LambertSpecular.eval(&geo, &[0.1, 1.0, 0.2], &mut out, None);
        assert!((out[0] - out[1]).abs() < 1e-12);
    }
}
