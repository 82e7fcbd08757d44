//! Smith shadowing–masking for the Gaussian (Beckmann) slope distribution that the KBS
//! rough limit implies (eq. 43: e^{−a/g} = exp(−tan²θ_h/α²) with α = 2σ/T).
//!
//! ```text
//! G₁(θ) = 1/(1 + Λ(ν)),  ν = 1/(α tan θ) = T cot θ/(2σ)
//! Λ(ν) = ½ [e^{−ν²}/(√π ν) − erfc ν]
//! smith:             G = G₁(θi) G₁(θr)
//! smith-correlated:  G = 1/(1 + Λ(νi) + Λ(νr))      (height-correlated)
//! ```
//!
//! G depends on σ and T only through T/σ: ∂ln G/∂ln T = −∂ln G/∂ln σ, and
//! ν ∂Λ/∂ν = −e^{−ν²}/(2√π ν). G = 1 at normal incidence and as σ/T → 0; G = 0 at
//! θ = 90°.
//!
//! Accuracy: G to 1e-13 relative and ∂ln G/∂ln T to 1e-11 (1 + |·|), tested against a
//! 30-digit mpmath reference of the erf form (`tests/lib/fresnel_shadowing.rs`: θ up to 89.9°,
//! T/σ 0.5–200; worst measured 7e-16 and 2e-16), and Λ(ν) itself to 1e-15 (1 + Λ) against
//! a dense 30-digit table of ν from 1e-3 to 6.5 (`tests/ref/lambda_reference.csv`).
//!
//! Cost: one `exp` per direction, no division and no branch on ν (random geometries cost
//! what ordered ones do). Λ = ½ e^{−ν²}(y/√π − erfcx ν) with y = 1/ν, and
//! erfcx ν = e^{ν²} erfc ν from a table of eight polynomial pieces (degree 11, Chebyshev
//! interpolants from `tests/ref/smith_lambda.py`, summed by Estrin's scheme): in ν below
//! ν = 1.25, as y·P(y) above (the last piece reaches y = 0). Worst |ΔΛ|/(1 + Λ) of the
//! table in binary64: 3e-16 (tested at 1e-15 against the dense reference). The lobe
//! passes cot θ and tan θ of both directions ([`Shadowing::direction`]), computed once per
//! dataset ([`crate::geometry::FactorColumns`]), so that ν = (T/2σ) cot θ and
//! y = (2σ/T) tan θ are products. The lobe evaluates Λ of its directions four at a time
//! (`directions`: the same table, each lane's piece loaded per lane, e^{−ν²} by a
//! Taylor `exp` of relative error ≤ 2ε), to the same 1e-15 (1 + Λ) against the dense
//! reference.

mod lanes;
pub(crate) use lanes::directions;

/// Which shadowing–masking factor multiplies the KBS lobe.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Shadowing {
    /// No factor: the paper's model.
    #[default]
    None,
    /// Uncorrelated Smith G₁(θi) G₁(θr).
    Smith,
    /// Height-correlated Smith 1/(1 + Λi + Λr).
    SmithCorrelated,
}

impl Shadowing {
    /// All choices, in help order.
    pub const ALL: [Shadowing; 3] = [
        Shadowing::None,
        Shadowing::Smith,
        Shadowing::SmithCorrelated,
    ];

    /// The option's name (`none`, `smith`, `smith-correlated`).
    pub fn name(self) -> &'static str {
        match self {
            Shadowing::None => "none",
            Shadowing::Smith => "smith",
            Shadowing::SmithCorrelated => "smith-correlated",
        }
    }

    /// The choice named `name` (case-insensitive).
    pub fn parse(name: &str) -> Option<Shadowing> {
        Self::ALL
            .into_iter()
            .find(|s| s.name().eq_ignore_ascii_case(name.trim()))
    }

    /// G and ∂ln G/∂ln T (= −∂ln G/∂ln σ) for the incidence and view cotangents
    /// `cot_i`, `cot_r` (≥ 0; ∞ at normal incidence) and the ratio `t_over_sigma` = T/σ > 0.
    /// `None` gives G = 1.
    #[inline]
    pub fn eval(self, cot_i: f64, cot_r: f64, t_over_sigma: f64) -> ShadowValue {
        if self == Shadowing::None {
            return ShadowValue::ONE;
        }
        let k = 0.5 * t_over_sigma;
        self.combine(lambda(k * cot_i), lambda(k * cot_r))
    }

    /// [`Self::eval`] the lobe's way, from (cot θ, tan θ) of incidence and view as
    /// `crate::geometry::cot_tan` gives them ([`Self::direction`]: no division for ν and
    /// 1/ν; G the same to 1e-15 relative).
    #[inline]
    pub fn eval_cot_tan(
        self,
        incidence: (f64, f64),
        view: (f64, f64),
        t_over_sigma: f64,
    ) -> ShadowValue {
        if self == Shadowing::None {
            return ShadowValue::ONE;
        }
        let k = 0.5 * t_over_sigma;
        let k = (k, 1.0 / k);
        self.combine(Self::direction(incidence, k), Self::direction(view, k))
    }

    /// Λ and ν ∂Λ/∂ν (`lambda`) of one direction, for [`Self::combine`], from its
    /// (cot θ, tan θ) as `crate::geometry::cot_tan` gives them (tan θ = 1/cot θ, both
    /// ≥ 0) and `(k, 1/k)` with k = T/(2σ) > 0: ν = k cot θ and 1/ν = tan θ/k, without a
    /// division (∞ at normal incidence, where Λ = 0; 0 at grazing, where Λ = ∞). ν and 1/ν
    /// carry a few ulps of rounding each: Λ is `lambda`'s to 1e-15 (1 + Λ).
    #[inline(always)]
    pub fn direction((cot, tan): (f64, f64), (k, inv_k): (f64, f64)) -> (f64, f64) {
        lambda_ny(k * cot, tan * inv_k)
    }

    /// G from Λ and ν ∂Λ/∂ν of both directions ([`Self::direction`]; a grazing direction,
    /// Λ = ∞, gives G = 0). `None` gives G = 1.
    #[inline(always)]
    pub fn combine(self, (li, dli): (f64, f64), (lr, dlr): (f64, f64)) -> ShadowValue {
        if li.is_infinite() || lr.is_infinite() {
            // A grazing direction (θ = 90°): nothing is lit or seen, G = 0 for every T/σ.
            return ShadowValue {
                g: 0.0,
                d_ln_t: 0.0,
            };
        }
        // ∂Λ/∂ln T = ν ∂Λ/∂ν.
        match self {
            Shadowing::Smith => {
                let (ui, ur) = (1.0 + li, 1.0 + lr);
                let g = 1.0 / (ui * ur);
                ShadowValue {
                    g,
                    d_ln_t: -(dli * ur + dlr * ui) * g,
                }
            }
            _ => {
                let g = 1.0 / (1.0 + li + lr);
                ShadowValue {
                    g,
                    d_ln_t: -(dli + dlr) * g,
                }
            }
        }
    }
}

/// A shadowing factor G and its logarithmic derivative in T (module doc).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShadowValue {
    /// G in [0, 1]: the fraction of the surface both lit and seen.
    pub g: f64,
    /// ∂ln G/∂ln T; ∂ln G/∂ln σ is its negative.
    pub d_ln_t: f64,
}

impl ShadowValue {
    /// No shadowing: G = 1.
    pub const ONE: ShadowValue = ShadowValue {
        g: 1.0,
        d_ln_t: 0.0,
    };
}

/// Smith's Λ(ν) of the Beckmann distribution and ν ∂Λ/∂ν = −e^{−ν²}/(2√π ν), for ν ≥ 0
/// (Λ = ∞ at ν = 0, the grazing direction); accuracy and cost in the module doc.
#[inline(always)]
pub(crate) fn lambda(nu: f64) -> (f64, f64) {
    lambda_ny(nu, 1.0 / nu)
}

/// [`lambda`] at ν with y = 1/ν given (ν ≥ 0; y = ∞ at ν = 0 gives Λ = ∞). Branch-free
/// in ν, so that samples of random geometry cost the same: beyond ν = √50 ≈ 7.1 the factor
/// e^{−ν²} is taken at ν² = 50, which leaves Λ and ν ∂Λ/∂ν below 1e-22 (0 in 1 + Λ, as the
/// exact values below 1e-23 are).
#[inline(always)]
fn lambda_ny(nu: f64, y: f64) -> (f64, f64) {
    const INV_SQRT_PI: f64 = 0.564_189_583_547_756_3;
    let k = E_PIECES[1..].iter().filter(|p| nu >= p.nu_lo).count();
    let piece = &E_PIECES[k];
    let erfcx = piece.erfcx(nu, y);
    let e = (-(nu * nu).min(50.0)).exp();
    let first = y * INV_SQRT_PI;
    ((0.5 * e * (first - erfcx)).max(0.0), -0.5 * e * first)
}

/// cot θ = cos θ/sin θ of a polar angle θ ∈ [0, π/2] (∞ at 0, 0 at π/2 up to rounding,
/// clamped at 0).
#[inline]
#[cfg(test)]
pub(crate) fn cot(theta: f64) -> f64 {
    crate::geometry::cot_tan(theta).0
}

/// One piece of the table of erfcx (module doc), for ν from `nu_lo` up to the next
/// piece's: erfcx ν = P(t) (`in_y` false) or y·P(t) (true), t = (u − mid)·inv_half ∈ [−1, 1]
/// with u = ν or y.
struct EPiece {
    nu_lo: f64,
    in_y: bool,
    mid: f64,
    inv_half: f64,
    c: [f64; 12],
}

impl EPiece {
    /// erfcx ν by Estrin's scheme (a chain of five multiply-adds instead of Horner's
    /// eleven).
    #[inline(always)]
    fn erfcx(&self, nu: f64, y: f64) -> f64 {
        let c = &self.c;
        let (u, factor) = if self.in_y { (y, y) } else { (nu, 1.0) };
        let t = (u - self.mid) * self.inv_half;
        let t2 = t * t;
        let t4 = t2 * t2;
        let pair = |k: usize| c[k] + c[k + 1] * t;
        let q0 = pair(0) + pair(2) * t2;
        let q1 = pair(4) + pair(6) * t2;
        let q2 = pair(8) + pair(10) * t2;
        factor * ((q0 + q1 * t4) + q2 * (t4 * t4))
    }
}

/// Generated by `tests/ref/smith_lambda.py` (the comments: the worst error of Λ per piece).
#[rustfmt::skip]
const E_PIECES: [EPiece; 8] = [
    // nu in [0.0, 0.3], in nu: worst error of Lambda 3.2e-16
    EPiece { nu_lo: 0.0, in_y: false, mid: 0.15, inv_half: 6.666666666666667, c: [
        0.8509363086677635,
        -0.13096474117427753,
        0.016199360268606484,
        -0.0017214807135852823,
        0.00016287614495835668,
        -1.4027441115326373e-05,
        1.1163654308972715e-06,
        -8.299978175010958e-08,
        5.812388421837378e-09,
        -3.859190735421715e-10,
        2.4679920086392237e-11,
        -1.4934673677123124e-12,
    ] },
    // nu in [0.3, 0.65], in nu: worst error of Lambda 1.8e-16
    EPiece { nu_lo: 0.3, in_y: false, mid: 0.475, inv_half: 5.7142857142857135, c: [
        0.6287356740249552,
        -0.09293904843506588,
        0.011529471615853618,
        -0.001258580686837866,
        0.00012423527427188037,
        -1.1286790539574417e-05,
        9.554971468986111e-07,
        -7.606637783236552e-08,
        5.734365682769308e-09,
        -4.117151856874664e-10,
        2.863824627435189e-11,
        -1.8871833550388276e-12,
    ] },
    // nu in [0.65, 0.95], in nu: worst error of Lambda 6.4e-17
    EPiece { nu_lo: 0.65, in_y: false, mid: 0.8, inv_half: 6.666666666666668, c: [
        0.4891005892231147,
        -0.051872733650779344,
        0.004780035219426714,
        -0.00039568818720757306,
        3.0034104984263705e-05,
        -2.119556645445121e-06,
        1.4047352938433384e-07,
        -8.809486652962063e-09,
        5.258639187305248e-10,
        -3.0023248855705294e-11,
        1.659240017842319e-12,
        -8.757510333213058e-14,
    ] },
    // nu in [0.95, 1.25], in nu: worst error of Lambda 2.9e-17
    EPiece { nu_lo: 0.95, in_y: false, mid: 1.1, inv_half: 6.666666666666666, c: [
        0.4017304606364951,
        -0.03668582305428351,
        0.0029857745603644073,
        -0.00022185214417417502,
        1.5287161909204554e-05,
        -9.877166115008981e-07,
        6.032930292950286e-08,
        -3.5055112889248612e-09,
        1.9474566179063093e-10,
        -1.0386521975724523e-11,
        5.374465453365742e-13,
        -2.666150669613948e-14,
    ] },
    // nu in [1.25, 1.6], in y: worst error of Lambda 1.1e-17
    EPiece { nu_lo: 1.25, in_y: true, mid: 0.7125, inv_half: 11.428571428571425, c: [
        0.47454510917140835,
        -0.014905717353056352,
        0.00011001013549274365,
        3.2432360958420004e-05,
        -3.3948040127896476e-06,
        2.141106238852854e-07,
        -7.96481659171438e-09,
        -1.4557511436098445e-10,
        6.085020605172628e-11,
        -6.946130805795385e-12,
        5.566195165932843e-13,
        -3.18784406101467e-14,
    ] },
    // nu in [1.6, 2.2], in y: worst error of Lambda 2.7e-18
    EPiece { nu_lo: 1.6, in_y: true, mid: 0.5397727272727272, inv_half: 11.733333333333333, c: [
        0.5040901824249288,
        -0.01445346198612451,
        -0.0001702828276509808,
        6.337719773115419e-05,
        -5.2523142666912496e-06,
        2.2086886147276338e-07,
        6.320018023580529e-09,
        -2.29178685474777e-09,
        2.5969018371002203e-10,
        -1.8483918174866654e-11,
        5.090661725781341e-13,
        8.005673542915385e-14,
    ] },
    // nu in [2.2, 3.2], in y: worst error of Lambda 2.0e-19
    EPiece { nu_lo: 2.2, in_y: true, mid: 0.38352272727272724, inv_half: 14.080000000000002, c: [
        0.529561850817537,
        -0.010874719694552904,
        -0.0004416648337030091,
        6.207796357071165e-05,
        -2.9943980279496046e-06,
        -5.088511556353312e-08,
        2.3265808466861144e-08,
        -2.242404473675649e-09,
        9.548543482748468e-11,
        5.795607307596387e-12,
        -1.6095648427772619e-12,
        1.6716752838735087e-13,
    ] },
    // nu in [3.2, inf], in y: worst error of Lambda 1.5e-18
    EPiece { nu_lo: 3.2, in_y: true, mid: 0.15625, inv_half: 6.4, c: [
        0.5575405099172299,
        -0.012848398024902228,
        -0.005573330867990289,
        0.0007606849846973528,
        9.032169409315961e-05,
        -4.416076187623883e-05,
        2.8180185950743764e-06,
        2.0575732146853124e-06,
        -6.20015575063932e-07,
        -1.1514758725920446e-08,
        4.7927611233941126e-08,
        -9.131934543375241e-09,
    ] },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lambda_is_negligible_beyond_the_exponential_clamp() {
        // Beyond ν² = 50 the exact Λ < 1e-23 and |ν ∂Λ/∂ν| < 1e-22: both are 0 in 1 + Λ.
        for nu in [7.1, 8.0, 30.0, 1e3, 1e150, f64::INFINITY] {
            let (l, d) = lambda(nu);
            assert!(
                (0.0..1e-22).contains(&l) && d.abs() < 1e-22,
                "ν={nu}: {l:e} {d:e}"
            );
        }
        assert_eq!(lambda(0.0).0, f64::INFINITY);
    }

    #[test]
    fn lambda_derivative_matches_central_differences() {
        for nu in [0.01, 0.3, 1.0, 2.5, 5.0] {
            let h = 1e-6 * nu;
            let d = (lambda(nu + h).0 - lambda(nu - h).0) / (2.0 * h) * nu;
            let want = lambda(nu).1;
            assert!(
                (d - want).abs() <= 1e-7 * want.abs(),
                "ν={nu}: {d} vs {want}"
            );
        }
    }
}
