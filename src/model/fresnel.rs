//! Fresnel reflectance of the specular facet, normalised at normal incidence (He, Torrance,
//! Sillion & Greenberg 1991, the factor F² of the Kirchhoff series at the local angle).
//!
//! ```text
//! cos θ_loc = √((1 + ŝ·k̂₂)/2) = √(h/2)          (h = |v|²/(2k²), geometry column `h`)
//! F(θ_loc; η) = R(θ_loc; η) / R(0; η),  η = n + iκ (relative to the incident medium)
//! R = (|r_s|² + |r_p|²)/2                       (unpolarised)
//! ```
//!
//! With w = √(η² − 1 + c²) (c = cos θ_loc; the principal root, Re w ≥ 0) the amplitudes
//! are r_s = (c − w)/(c + w) = (1 − η²)/(c + w)² and
//! r_p = (η²c − w)/(η²c + w) = (η² − 1)(c²(η² + 1) − 1)/(η²c + w)². The common factor
//! η² − 1 cancels between R and R(0) = |1 − η|²/|1 + η|², so
//!
//! ```text
//! F = |1 + η|⁴ (|A_s|² + |A_p|²)/2,  A_s = (c + w)⁻²,  A_p = (c²(η² + 1) − 1)(η²c + w)⁻²
//! ```
//!
//! has no cancellation near n = 1 (where R itself is the difference of nearly equal
//! numbers) and no division by R(0). F = 1 at normal incidence and F = 1/R(0) at grazing
//! (R = 1). The dielectric form is the conductor form at κ = 0. Schlick's approximation
//! R ≈ F₀ + (1 − F₀)(1 − c)⁵ with F₀ = ((n − 1)/(n + 1))² normalises to
//! F = 1 + 4n(1 − c)⁵/(n − 1)².
//!
//! | parameter | unit | domain |
//! |---|---|---|
//! | `n` | 1 | > 0 (Schlick: ≠ 1); the models take n > 1 for the dielectric and Schlick forms |
//! | `kappa` (κ) | 1 | > 0 (F is even in κ; κ = 0 is the dielectric form) |
//!
//! Accuracy: F to 1e-13 relative and ∂F/∂n, ∂F/∂κ to 1e-12 (|∂F| + F), tested against a
//! 30-digit mpmath reference of the textbook r_s, r_p formulas (`tests/lib/fresnel_shadowing.rs`:
//! n 1.01–4, κ 0–10, θ_loc up to 89.9°; worst measured 3e-15 and 5e-15). F is finite wherever w ≠ 0, i.e. except at the critical angle of a real
//! index n < 1 (and n = 1, κ = 0 at exact grazing). Beyond that critical angle F has a
//! kink at κ = 0, and ∂F/∂κ there is the derivative from κ > 0.

use std::ops::{Add, Mul, Sub};

/// Which Fresnel factor multiplies the KBS lobe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Fresnel {
    /// No factor: the paper's model (a perfect conductor).
    #[default]
    None,
    /// Real refractive index `n`.
    Dielectric,
    /// Complex refractive index n + iκ (`n`, `kappa`).
    Conductor,
    /// Schlick's approximation with F₀ from `n`.
    Schlick,
}

impl Fresnel {
    /// All choices, in help order.
    pub const ALL: [Fresnel; 4] = [
        Fresnel::None,
        Fresnel::Dielectric,
        Fresnel::Conductor,
        Fresnel::Schlick,
    ];

    /// The option's name (`none`, `dielectric`, `conductor`, `schlick`).
    pub fn name(self) -> &'static str {
        match self {
            Fresnel::None => "none",
            Fresnel::Dielectric => "dielectric",
            Fresnel::Conductor => "conductor",
            Fresnel::Schlick => "schlick",
        }
    }

    /// The choice named `name` (case-insensitive).
    pub fn parse(name: &str) -> Option<Fresnel> {
        Self::ALL
            .into_iter()
            .find(|f| f.name().eq_ignore_ascii_case(name.trim()))
    }

    /// How many parameters the factor adds (`n`; `n`, `kappa`).
    pub fn param_count(self) -> usize {
        match self {
            Fresnel::None => 0,
            Fresnel::Dielectric | Fresnel::Schlick => 1,
            Fresnel::Conductor => 2,
        }
    }

    /// The normalised factor at `cos_loc` with the factor's parameters `p` (`[n]` or
    /// `[n, kappa]`; ignored for `None`, which gives F = 1).
    #[inline]
    pub fn eval(self, cos_loc: f64, p: &[f64]) -> FresnelValue {
        match self {
            Fresnel::None => FresnelValue {
                f: 1.0,
                d_n: 0.0,
                d_kappa: 0.0,
            },
            Fresnel::Dielectric if p[0] > 1.0 => real_ratio(cos_loc, p[0]),
            Fresnel::Dielectric => complex_ratio(cos_loc, p[0], 0.0),
            Fresnel::Conductor => complex_ratio(cos_loc, p[0], p[1]),
            Fresnel::Schlick => schlick_ratio(cos_loc, p[0]),
        }
    }
}

/// A normalised Fresnel factor F = R(θ_loc)/R(0) and its partial derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FresnelValue {
    pub f: f64,
    /// ∂F/∂n.
    pub d_n: f64,
    /// ∂F/∂κ (0 for the dielectric and Schlick forms).
    pub d_kappa: f64,
}

pub use crate::geometry::cos_local;

/// Unpolarised Fresnel reflectance of the index η = n + iκ at incidence cos θ = `c`
/// (0 ≤ c ≤ 1), divided by its value at normal incidence, with ∂/∂n and ∂/∂κ (module doc).
#[inline]
pub fn complex_ratio(c: f64, n: f64, kappa: f64) -> FresnelValue {
    let eta = C::new(n, kappa);
    let eta2 = eta * eta;
    let c2 = c * c;
    let w = (eta2 - C::real(1.0 - c2)).sqrt();
    let dw = eta.div(w); // ∂w/∂η
    let u_inv = C::real(c).add(w).inv();
    let a_s = u_inv * u_inv;
    // ∂A_s/∂η = −2 A_s w'/(c + w).
    let da_s = a_s * dw * u_inv * C::real(-2.0);
    let num = eta2 * C::real(c2) + C::real(c2 - 1.0);
    let d_inv = (eta2 * C::real(c) + w).inv();
    let a_p = num * d_inv * d_inv;
    // ∂A_p/∂η = 2c²η/D² − 2 A_p (2ηc + w')/D.
    let da_p = eta * C::real(2.0 * c2) * d_inv * d_inv
        - a_p * (eta * C::real(2.0 * c) + dw) * d_inv * C::real(2.0);
    let m = 0.5 * (a_s.norm2() + a_p.norm2());
    // ∂M/∂n = Re(Ā A'), ∂M/∂κ = Re(Ā i A') = −Im(Ā A') (A holomorphic).
    let g = a_s.conj() * da_s + a_p.conj() * da_p;
    let q = (1.0 + n) * (1.0 + n) + kappa * kappa;
    let p = q * q;
    FresnelValue {
        f: p * m,
        d_n: 4.0 * q * (1.0 + n) * m + p * g.re,
        d_kappa: 4.0 * q * kappa * m - p * g.im,
    }
}

/// [`complex_ratio`] at κ = 0 for n > 1, in real arithmetic (w² = n² − 1 + c² > 0): the
/// same formulas, the same accuracy, one division.
#[inline]
pub fn real_ratio(c: f64, n: f64) -> FresnelValue {
    let (n2, c2) = (n * n, c * c);
    let w = (n2 - 1.0 + c2).sqrt();
    // One division for w⁻¹, (c + w)⁻¹ and (n²c + w)⁻¹ (all factors ≥ √(n² − 1) > 0).
    let (u, d) = (c + w, n2 * c + w);
    let inv = 1.0 / (w * u * d);
    let dw = n * (u * d) * inv;
    let u_inv = w * d * inv;
    let a_s = u_inv * u_inv;
    let da_s = -2.0 * a_s * dw * u_inv;
    let num = n2 * c2 + (c2 - 1.0);
    let d_inv = w * u * inv;
    let a_p = num * d_inv * d_inv;
    let da_p = 2.0 * c2 * n * d_inv * d_inv - 2.0 * a_p * (2.0 * n * c + dw) * d_inv;
    let m = 0.5 * (a_s * a_s + a_p * a_p);
    let q = (1.0 + n) * (1.0 + n);
    let p = q * q;
    FresnelValue {
        f: p * m,
        d_n: 4.0 * q * (1.0 + n) * m + p * (a_s * da_s + a_p * da_p),
        d_kappa: 0.0,
    }
}

/// Schlick's approximation normalised at normal incidence, F = 1 + 4n(1 − c)⁵/(n − 1)²,
/// with ∂F/∂n = −4(n + 1)(1 − c)⁵/(n − 1)³; `n` ≠ 1 (F is unbounded there, as F₀ → 0).
#[inline]
pub fn schlick_ratio(c: f64, n: f64) -> FresnelValue {
    let one_minus_c = (1.0 - c).max(0.0);
    let x5 = one_minus_c.powi(5);
    let nm1 = n - 1.0;
    FresnelValue {
        f: 1.0 + 4.0 * n * x5 / (nm1 * nm1),
        d_n: -4.0 * (n + 1.0) * x5 / (nm1 * nm1 * nm1),
        d_kappa: 0.0,
    }
}

/// A complex number, only what [`complex_ratio`] needs (no dependency, no polar form).
#[derive(Debug, Clone, Copy)]
struct C {
    re: f64,
    im: f64,
}

impl C {
    #[inline]
    fn new(re: f64, im: f64) -> C {
        C { re, im }
    }
    #[inline]
    fn real(re: f64) -> C {
        C { re, im: 0.0 }
    }
    #[inline]
    fn conj(self) -> C {
        C::new(self.re, -self.im)
    }
    #[inline]
    fn norm2(self) -> f64 {
        self.re * self.re + self.im * self.im
    }
    #[inline]
    fn inv(self) -> C {
        let d = self.norm2();
        C::new(self.re / d, -self.im / d)
    }
    #[inline]
    fn div(self, o: C) -> C {
        self * o.inv()
    }
    /// The principal square root (Re ≥ 0), without cancellation: t = √((|z| + |x|)/2).
    #[inline]
    fn sqrt(self) -> C {
        let (x, y) = (self.re, self.im);
        if x == 0.0 && y == 0.0 {
            return C::real(0.0);
        }
        let t = (0.5 * (self.norm2().sqrt() + x.abs())).sqrt();
        if x >= 0.0 {
            C::new(t, y / (2.0 * t))
        } else {
            C::new(y.abs() / (2.0 * t), t.copysign(y))
        }
    }
}

impl Add for C {
    type Output = C;
    #[inline]
    fn add(self, o: C) -> C {
        C::new(self.re + o.re, self.im + o.im)
    }
}

impl Sub for C {
    type Output = C;
    #[inline]
    fn sub(self, o: C) -> C {
        C::new(self.re - o.re, self.im - o.im)
    }
}

impl Mul for C {
    type Output = C;
    #[inline]
    fn mul(self, o: C) -> C {
        C::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_is_one_and_grazing_is_the_inverse_of_r0() {
        for (n, k) in [(1.01, 0.0), (1.5, 0.0), (4.0, 0.0), (0.2, 3.0), (2.5, 10.0)] {
            let r0 = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
            let at0 = complex_ratio(1.0, n, k).f;
            let grazing = complex_ratio(0.0, n, k).f;
            assert!((at0 - 1.0).abs() < 1e-14, "n={n} κ={k}: {at0}");
            assert!((grazing * r0 - 1.0).abs() < 1e-13, "n={n} κ={k}: {grazing}");
        }
    }

    #[test]
    fn sqrt_is_the_principal_root() {
        for (x, y) in [
            (4.0, 0.0),
            (-4.0, 0.0),
            (-4.0, -0.0),
            (3.0, 4.0),
            (-3.0, 4.0),
        ] {
            let r = C::new(x, y).sqrt();
            let sq = r * r;
            assert!(r.re >= 0.0);
            assert!(
                (sq.re - x).abs() < 1e-14 && (sq.im - y).abs() < 1e-14,
                "{x},{y}"
            );
        }
    }
}
