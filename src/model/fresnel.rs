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
//! n 1.01–4, κ 0–10, θ_loc up to 89.9°; worst measured 3e-15 and 4e-15). F is finite wherever w ≠ 0, i.e. except at the critical angle of a real
//! index n < 1 (and n = 1, κ = 0 at exact grazing). Beyond that critical angle F has a
//! kink at κ = 0, and ∂F/∂κ there is the derivative from κ > 0.
//!
//! The lobe evaluates the conductor form (n, κ > 0) and the dielectric form (n > 1) four
//! samples at a time (`conductor`, `dielectric`), within 1e-14 (|F| + |∂F|) of
//! [`complex_ratio`] and [`real_ratio`].

mod lanes;
pub(crate) use lanes::{conductor, dielectric};

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
    #[inline(always)]
    pub fn eval(self, cos_loc: f64, p: &[f64]) -> FresnelValue {
        match self {
            Fresnel::None => FresnelValue {
                f: 1.0,
                d_n: 0.0,
                d_kappa: 0.0,
            },
            Fresnel::Dielectric if p[0] >= FLAT_INDEX => FresnelValue {
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

/// Index from which the dielectric factor is F = 1 with ∂F/∂n = 0: there |F − 1| ≤
/// 2/(n cos θ_loc) is below 2·10⁻¹⁴ for θ_loc up to 89.9°, and ∂F/∂n ~ 2/(n² cos θ_loc)
/// below 10⁻³⁰, while [`real_ratio`]'s ∂F/∂n, the difference of two terms of order 4/n,
/// would be their rounding (a relative 10⁻¹⁵ of F on the solver's ln(n − 1), a column
/// shaped like the lobe's amplitude) and its terms of order n⁴ overflow beyond n ~ 10⁷⁷.
/// A fit whose index runs here has run to the edge n → ∞ of its domain.
pub(crate) const FLAT_INDEX: f64 = 1e17;

/// A normalised Fresnel factor F = R(θ_loc)/R(0) and its partial derivatives.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FresnelValue {
    /// F, 1 at normal incidence.
    pub f: f64,
    /// ∂F/∂n.
    pub d_n: f64,
    /// ∂F/∂κ (0 for the dielectric and Schlick forms).
    pub d_kappa: f64,
}

impl FresnelValue {
    /// No factor: F = 1.
    pub const ONE: FresnelValue = FresnelValue {
        f: 1.0,
        d_n: 0.0,
        d_kappa: 0.0,
    };
}

#[cfg(test)]
pub(crate) use crate::geometry::cos_local;

/// Unpolarised Fresnel reflectance of the index η = n + iκ at incidence cos θ = `c`
/// (0 ≤ c ≤ 1), divided by its value at normal incidence, with ∂/∂n and ∂/∂κ (module doc),
/// in real arithmetic: two square roots and one division for w and F, one more division
/// for the derivatives.
#[inline(always)]
pub(crate) fn complex_ratio(c: f64, n: f64, kappa: f64) -> FresnelValue {
    // η² = er + i·ei; w² = η² − 1 + c² = x + i·ei, w = a + ib its principal root (a ≥ 0)
    // without cancellation: t = √((|w²| + |x|)/2); |w|² = |w²|.
    let (er, ei) = (n * n - kappa * kappa, 2.0 * n * kappa);
    let c2 = c * c;
    let x = er - (1.0 - c2);
    let w_abs2 = (x * x + ei * ei).sqrt();
    let t = (0.5 * (w_abs2 + x.abs())).sqrt();
    let (a, b) = if t == 0.0 {
        (0.0, 0.0)
    } else if x >= 0.0 {
        (t, ei / (2.0 * t))
    } else {
        (ei.abs() / (2.0 * t), t.copysign(ei))
    };
    // |A_s|² = U⁻², U = |c + w|²; |A_p|² = |N|²/D², N = c²(η² + 1) − 1, D = |η²c + w|².
    let ca = c + a;
    let u = ca * ca + b * b;
    let (dr, di) = (er * c + a, ei * c + b);
    let d = dr * dr + di * di;
    let (nr, ni) = (er * c2 + (c2 - 1.0), ei * c2);
    let np = nr * nr + ni * ni;
    let (u2, d2) = (u * u, d * d);
    // One division for U⁻¹ and D⁻¹ while U²D² is normal (|η| below about 1e25).
    let den = u2 * d2;
    let (u_inv, d_inv) = if den.is_normal() {
        let inv = 1.0 / den;
        (u * d2 * inv, u2 * d * inv)
    } else {
        (1.0 / u, 1.0 / d)
    };
    let m = 0.5 * (u_inv * u_inv + np * (d_inv * d_inv));
    let q = (1.0 + n) * (1.0 + n) + kappa * kappa;
    let p = q * q;
    // ∂|f|²/∂n = 2 Re(f̄ f'), ∂|f|²/∂κ = −2 Im(f̄ f') for f holomorphic in η, with
    // w' = η/w = η w̄/|w|², N' = 2c²η, (η²c + w)' = 2cη + w'.
    let inv_w2 = 1.0 / w_abs2;
    let (wr, wi) = mul((n, kappa), (a * inv_w2, -b * inv_w2));
    let zs = mul((ca, -b), (wr, wi));
    let zn = mul((nr, -ni), (2.0 * c2 * n, 2.0 * c2 * kappa));
    let zd = mul((dr, -di), (2.0 * c * n + wr, 2.0 * c * kappa + wi));
    // ∂M/∂n = Re Z, ∂M/∂κ = −Im Z with Z = −2U⁻³ z_s + D⁻² z_n − 2|N|² D⁻³ z_d.
    let (ks, kn) = (-2.0 * u_inv * u_inv * u_inv, d_inv * d_inv);
    let kd = -2.0 * np * kn * d_inv;
    let z_re = ks * zs.0 + kn * zn.0 + kd * zd.0;
    let z_im = ks * zs.1 + kn * zn.1 + kd * zd.1;
    FresnelValue {
        f: p * m,
        d_n: 4.0 * q * (1.0 + n) * m + p * z_re,
        d_kappa: 4.0 * q * kappa * m - p * z_im,
    }
}

/// The complex product of (re, im) pairs.
#[inline(always)]
fn mul((a, b): (f64, f64), (c, d): (f64, f64)) -> (f64, f64) {
    (a * c - b * d, a * d + b * c)
}

/// [`complex_ratio`] at κ = 0 for n > 1, in real arithmetic (w² = n² − 1 + c² > 0): the
/// same formulas, the same accuracy, one division.
#[inline(always)]
pub(crate) fn real_ratio(c: f64, n: f64) -> FresnelValue {
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
pub(crate) fn schlick_ratio(c: f64, n: f64) -> FresnelValue {
    let one_minus_c = (1.0 - c).max(0.0);
    let x5 = one_minus_c.powi(5);
    let nm1 = n - 1.0;
    FresnelValue {
        f: 1.0 + 4.0 * n * x5 / (nm1 * nm1),
        d_n: -4.0 * (n + 1.0) * x5 / (nm1 * nm1 * nm1),
        d_kappa: 0.0,
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
    fn the_dielectric_factor_is_one_from_the_flat_index_on_and_meets_it_there() {
        for c in [1e-3, 0.1, 0.5, 0.9, 1.0] {
            for n in [FLAT_INDEX, 1e30, 1e300, f64::INFINITY] {
                let v = Fresnel::Dielectric.eval(c, &[n]);
                assert_eq!((v.f, v.d_n, v.d_kappa), (1.0, 0.0, 0.0), "c={c} n={n}");
                let unset = FresnelValue {
                    f: 0.0,
                    d_n: 1.0,
                    d_kappa: 1.0,
                };
                let mut out = [unset; 5];
                dielectric(&[c; 5], n, &mut out);
                assert!(out.iter().all(|v| *v == FresnelValue::ONE), "c={c} n={n}");
            }
            // Just below it the formulas give 1 within 2/(n c) and their rounding (10⁻¹⁴),
            // ∂F/∂n within 10⁻³⁰.
            let below = real_ratio(c, 0.99 * FLAT_INDEX);
            let bound = 2.0 / (0.99 * FLAT_INDEX * c) + 1e-14;
            assert!((below.f - 1.0).abs() < bound, "c={c}: {below:?}");
            assert!(below.d_n.abs() < 1e-30, "c={c}: {below:?}");
        }
    }
}
