//! Robust losses, as scipy's `least_squares` names and defines them, and the IRLS-style
//! correction of residuals and Jacobian that lets a Gauss–Newton solver minimise them.
//!
//! The fit minimises `cost = ½ Σᵢ C² ρ(fᵢ²/C²)` over the weighted residuals `fᵢ = √wᵢ rᵢ`,
//! `C` = `f_scale` (the residual size where a sample starts to count as an outlier, in the
//! unit of the weighted residual). With `z = f²/C²`:
//!
//! | loss | ρ(z) | ρ'(z) | ρ''(z) |
//! |---|---|---|---|
//! | `linear` | z | 1 | 0 |
//! | `soft_l1` | 2(√(1+z) − 1) | (1+z)^{−½} | −½(1+z)^{−3/2} |
//! | `huber` | z (z ≤ 1), 2√z − 1 | 1, z^{−½} | 0, −½z^{−3/2} |
//! | `cauchy` | ln(1+z) | 1/(1+z) | −1/(1+z)² |
//! | `arctan` | arctan z | 1/(1+z²) | −2z/(1+z²)² |
//!
//! The solver sees three things per sample ([`Loss::correct`]):
//! - the *cost residual* `sᵢ = sign(fᵢ) C √ρ(zᵢ)`, so that ½‖s‖² is exactly the cost (the
//!   solver's ratio of actual to predicted reduction and its stopping rules work on it);
//! - the Jacobian row scaled by `√max(ρ' + 2ρ''z, ε)` and the *step residual*
//!   `f̃ᵢ = ρ'(zᵢ) fᵢ / √max(ρ' + 2ρ''z, ε)`, ε = 2.2e-16: scipy's
//!   `scale_for_robust_loss_function` (`_lsq/common.py`). Then `J̃ᵀf̃ = Σ ρ' f ∇f` is the exact
//!   gradient of the cost and `J̃ᵀJ̃ = Σ (ρ' + 2ρ''z) ∇f∇fᵀ` its Gauss–Newton Hessian (second
//!   derivatives of f dropped), floored at ε where the loss is flat or concave in f (Huber
//!   beyond its corner, Cauchy beyond z = 1, arctan beyond z = 1/√3): such a sample
//!   pushes the step but adds no curvature.
//!
//! The covariance of a robust fit is scipy's `curve_fit`'s: `s² (J̃ᵀJ̃)⁺` from the scaled
//! Jacobian at the optimum, with `s² = 2·cost/(n − p) = Σ C²ρ(zᵢ)/(n − p)`. For `linear`
//! every formula reduces to plain least squares, bit for bit (no correction is applied).
//!
//! Accuracy: ρ, ρ', ρ'' to a few ulps for z ∈ [0, 1e300] (soft_l1 and cauchy through
//! `ln_1p`/`sqrt` forms without cancellation at small z).

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// Which robust loss ρ (scipy's names).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LossKind {
    /// ρ(z) = z: plain least squares.
    #[default]
    Linear,
    /// ρ(z) = 2(√(1+z) − 1): a smooth l1; usually the first robust choice.
    SoftL1,
    /// ρ(z) = z for z ≤ 1, 2√z − 1 beyond.
    Huber,
    /// ρ(z) = ln(1 + z): outliers weakened strongly; the cost has more local minima.
    Cauchy,
    /// ρ(z) = arctan z: a single residual's cost is bounded by π/2 · C².
    Arctan,
}

impl LossKind {
    /// Every loss, in the order the CLI lists them.
    pub const ALL: [LossKind; 5] = [
        LossKind::Linear,
        LossKind::SoftL1,
        LossKind::Huber,
        LossKind::Cauchy,
        LossKind::Arctan,
    ];

    /// scipy's name (`linear`, `soft_l1`, `huber`, `cauchy`, `arctan`).
    pub fn name(self) -> &'static str {
        match self {
            LossKind::Linear => "linear",
            LossKind::SoftL1 => "soft_l1",
            LossKind::Huber => "huber",
            LossKind::Cauchy => "cauchy",
            LossKind::Arctan => "arctan",
        }
    }

    /// The loss of a scipy name (case-insensitive), or None.
    pub fn from_name(name: &str) -> Option<LossKind> {
        Self::ALL
            .into_iter()
            .find(|k| k.name().eq_ignore_ascii_case(name))
    }

    /// `[ρ(z), ρ'(z), ρ''(z)]` of the unit-scale loss at z = f²/C² ≥ 0.
    pub fn rho(self, z: f64) -> [f64; 3] {
        match self {
            LossKind::Linear => [z, 1.0, 0.0],
            LossKind::SoftL1 => {
                let t = 1.0 + z;
                let st = t.sqrt();
                // 2(√t − 1) = 2z/(√t + 1), exact for small z.
                [2.0 * z / (st + 1.0), 1.0 / st, -0.5 / (t * st)]
            }
            LossKind::Huber if z <= 1.0 => [z, 1.0, 0.0],
            LossKind::Huber => {
                let sz = z.sqrt();
                [2.0 * sz - 1.0, 1.0 / sz, -0.5 / (z * sz)]
            }
            LossKind::Cauchy => {
                let t = 1.0 + z;
                [z.ln_1p(), 1.0 / t, -1.0 / (t * t)]
            }
            LossKind::Arctan => {
                let t = 1.0 + z * z;
                [z.atan(), 1.0 / t, -2.0 * z / (t * t)]
            }
        }
    }
}

impl std::fmt::Display for LossKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// A robust loss with its scale `C` (`f_scale`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Loss {
    /// The function ρ (`linear`: plain least squares).
    pub kind: LossKind,
    /// C > 0, finite, in the unit of the weighted residual √w r (for relative residuals
    /// without weights: a fraction of the value, 0.03 = 3 %). Default 1 (scipy's).
    pub f_scale: f64,
}

impl Default for Loss {
    fn default() -> Self {
        Loss {
            kind: LossKind::Linear,
            f_scale: 1.0,
        }
    }
}

/// Smallest curvature factor ρ' + 2ρ''z kept (scipy's `EPS`).
const CURVATURE_FLOOR: f64 = f64::EPSILON;

/// What the solver uses of one weighted residual f under a robust loss.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corrected {
    /// sign(f) C √ρ(z): ½ s² is the sample's cost.
    pub cost_residual: f64,
    /// ρ'(z) f / √max(ρ' + 2ρ''z, ε): the residual the Gauss–Newton step uses.
    pub step_residual: f64,
    /// √max(ρ' + 2ρ''z, ε): the factor of the sample's Jacobian row.
    pub jacobian_scale: f64,
}

impl Loss {
    /// A loss with its scale; `f_scale` must be finite and > 0.
    pub fn new(kind: LossKind, f_scale: f64) -> crate::error::Result<Loss> {
        if !(f_scale.is_finite() && f_scale > 0.0) {
            return Err(crate::error::Error::Param {
                name: "f_scale".into(),
                message: format!(
                    "{f_scale} is not a valid loss scale; use a finite number > 0, the size of a residual beyond which a sample counts as an outlier (e.g. 0.03 for 3 % with --residual relative)"
                ),
            });
        }
        Ok(Loss { kind, f_scale })
    }

    /// Whether this is plain least squares (no correction at all).
    pub fn is_linear(&self) -> bool {
        self.kind == LossKind::Linear
    }

    /// The cost term C² ρ(f²/C²) of one weighted residual (twice its share of the cost);
    /// f² exactly for `linear`.
    pub fn term(&self, f: f64) -> f64 {
        if self.is_linear() {
            return f * f;
        }
        let c = self.f_scale;
        let z = (f / c) * (f / c);
        c * c * self.kind.rho(z)[0]
    }

    /// The corrected residuals and Jacobian factor of one weighted residual f (see the
    /// module doc).
    pub fn correct(&self, f: f64) -> Corrected {
        let c = self.f_scale;
        let z = (f / c) * (f / c);
        let [rho, d1, d2] = self.kind.rho(z);
        let jacobian_scale = (d1 + 2.0 * d2 * z).max(CURVATURE_FLOOR).sqrt();
        Corrected {
            cost_residual: (c * rho.sqrt()).copysign(f),
            step_residual: d1 * f / jacobian_scale,
            jacobian_scale,
        }
    }
}

impl Loss {
    /// Under a robust loss, replace weighted residuals `r` by the cost residuals, scale the
    /// rows of their Jacobian `j`, and return the step residuals ([`Loss::correct`] per
    /// row); linear: nothing changes and None. Rows of NaN stay NaN (a rejected point).
    pub fn correct_in_place(
        &self,
        r: &mut DVector<f64>,
        j: &mut DMatrix<f64>,
    ) -> Option<DVector<f64>> {
        if self.is_linear() {
            return None;
        }
        let mut step = DVector::zeros(r.len());
        let mut scale = DVector::zeros(r.len());
        for i in 0..r.len() {
            let c = self.correct(r[i]);
            r[i] = c.cost_residual;
            step[i] = c.step_residual;
            scale[i] = c.jacobian_scale;
        }
        for mut col in j.column_iter_mut() {
            col.component_mul_assign(&scale);
        }
        Some(step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Closed forms of ρ, ρ', ρ'' written out independently of [`LossKind::rho`].
    fn closed(kind: LossKind, z: f64) -> [f64; 3] {
        match kind {
            LossKind::Linear => [z, 1.0, 0.0],
            LossKind::SoftL1 => [
                2.0 * ((1.0 + z).powf(0.5) - 1.0),
                (1.0 + z).powf(-0.5),
                -0.5 * (1.0 + z).powf(-1.5),
            ],
            LossKind::Huber if z <= 1.0 => [z, 1.0, 0.0],
            LossKind::Huber => [2.0 * z.powf(0.5) - 1.0, z.powf(-0.5), -0.5 * z.powf(-1.5)],
            LossKind::Cauchy => [(1.0 + z).ln(), 1.0 / (1.0 + z), -(1.0 + z).powi(-2)],
            LossKind::Arctan => [
                z.atan(),
                1.0 / (1.0 + z * z),
                -2.0 * z / (1.0 + z * z).powi(2),
            ],
        }
    }

    const ZS: [f64; 9] = [0.0, 1e-3, 0.1, 0.5, 1.0, 2.0, 10.0, 1e3, 1e8];

    #[test]
    fn rho_and_its_derivatives_match_the_closed_forms() {
        for kind in LossKind::ALL {
            for z in ZS {
                let got = kind.rho(z);
                let want = closed(kind, z);
                for k in 0..3 {
                    // (the closed forms lose up to 3 digits to cancellation at z = 1e-3)
                    let tol = 1e-12 * want[k].abs();
                    assert!(
                        (got[k] - want[k]).abs() <= tol,
                        "{kind} ρ^({k})({z}) = {} want {}",
                        got[k],
                        want[k]
                    );
                }
            }
        }
    }

    #[test]
    fn derivatives_match_central_differences() {
        // ρ' and ρ'' against central differences of ρ and ρ' (h = 1e-5 z: error ~ h²).
        for kind in LossKind::ALL {
            for z in [0.3, 0.7, 1.7, 4.0, 25.0] {
                let h = 1e-5 * z;
                let d1 = (kind.rho(z + h)[0] - kind.rho(z - h)[0]) / (2.0 * h);
                let d2 = (kind.rho(z + h)[1] - kind.rho(z - h)[1]) / (2.0 * h);
                let [_, r1, r2] = kind.rho(z);
                assert!(
                    (d1 - r1).abs() <= 1e-8 * r1.abs().max(1e-3),
                    "{kind} ρ' at {z}"
                );
                assert!(
                    (d2 - r2).abs() <= 1e-6 * r2.abs().max(1e-3),
                    "{kind} ρ'' at {z}"
                );
            }
        }
    }

    #[test]
    fn every_loss_is_least_squares_near_zero() {
        // ρ(z) = z − O(z²): small residuals cost what they cost in least squares.
        for kind in LossKind::ALL {
            let [r, d1, _] = kind.rho(1e-8);
            assert!((r / 1e-8 - 1.0).abs() < 1e-7, "{kind}");
            assert!((d1 - 1.0).abs() < 1e-7, "{kind}");
        }
    }

    #[test]
    fn correction_gives_the_exact_cost_gradient_and_gauss_newton_curvature() {
        let loss = Loss::new(LossKind::SoftL1, 0.5).unwrap();
        for f in [-3.0, -0.2, 0.0, 0.1, 0.5, 4.0, 100.0] {
            let c = loss.correct(f);
            let z = (f / 0.5f64).powi(2);
            let [rho, d1, d2] = closed(LossKind::SoftL1, z);
            // ½ s² is the cost term ½ C² ρ.
            assert!((c.cost_residual.powi(2) - 0.25 * rho).abs() <= 1e-14 * (1.0 + rho));
            assert!(c.cost_residual * f >= 0.0);
            // gradient factor and curvature: J̃ᵀf̃ ∝ ρ' f, J̃ᵀJ̃ ∝ ρ' + 2ρ''z.
            assert!((c.jacobian_scale * c.step_residual - d1 * f).abs() <= 1e-14 * f.abs());
            assert!((c.jacobian_scale.powi(2) - (d1 + 2.0 * d2 * z)).abs() <= 1e-15);
        }
        // Huber beyond its corner has no curvature: floored at ε, the gradient stays exact.
        let h = Loss::new(LossKind::Huber, 1.0).unwrap().correct(3.0);
        assert_eq!(h.jacobian_scale, f64::EPSILON.sqrt());
        assert!((h.jacobian_scale * h.step_residual - 3.0 / 3.0).abs() < 1e-12);
        assert!((h.cost_residual.powi(2) - (2.0 * 3.0 - 1.0)).abs() < 1e-12);
    }

    /// Robust location and slope: residuals fᵢ = a + b tᵢ − yᵢ under a loss, through the
    /// solver's step-residual path.
    struct Line {
        t: Vec<f64>,
        y: Vec<f64>,
        loss: Loss,
    }

    impl Line {
        fn eval(&self, x: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>, Option<DVector<f64>>) {
            let n = self.t.len();
            let mut r = DVector::from_fn(n, |i, _| x[0] + x[1] * self.t[i] - self.y[i]);
            let mut j = DMatrix::from_fn(n, 2, |i, k| if k == 0 { 1.0 } else { self.t[i] });
            let step = self.loss.correct_in_place(&mut r, &mut j);
            (r, j, step)
        }
    }

    impl goniofit_lm::LeastSquaresProblem for Line {
        fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
            self.eval(x).0
        }
        fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
            self.eval(x).1
        }
        fn step_residuals(&self, x: &DVector<f64>) -> Option<DVector<f64>> {
            self.eval(x).2
        }
    }

    /// ψ(f) = ρ'(f²/C²) f, the derivative of ½C²ρ(f²/C²) in f.
    fn psi(loss: &Loss, f: f64) -> f64 {
        loss.kind.rho((f / loss.f_scale).powi(2))[1] * f
    }

    #[test]
    fn the_solver_finds_the_robust_optimum_of_a_line_with_outliers() {
        // y = 1 + 2t + small wiggle, every 5th sample 10 high.
        let t: Vec<f64> = (0..40).map(|i| i as f64 / 39.0).collect();
        let y: Vec<f64> = t
            .iter()
            .enumerate()
            .map(|(i, &t)| {
                1.0 + 2.0 * t + 0.01 * (i as f64 * 1.7).sin() + if i % 5 == 0 { 10.0 } else { 0.0 }
            })
            .collect();
        for kind in [
            LossKind::SoftL1,
            LossKind::Huber,
            LossKind::Cauchy,
            LossKind::Arctan,
        ] {
            let loss = Loss::new(kind, 0.05).unwrap();
            let p = Line {
                t: t.clone(),
                y: y.clone(),
                loss,
            };
            let config = goniofit_lm::LmConfig::default();
            let rep = goniofit_lm::minimize(&p, DVector::from_vec(vec![1.2, 1.7]), &config);
            assert!(rep.termination.converged(), "{kind}: {:?}", rep.termination);
            // Stationarity of the robust cost: Σ ψ(fᵢ) ∂fᵢ/∂x = 0 (relative to Σ|ψ|).
            let f: Vec<f64> = (0..t.len())
                .map(|i| rep.x[0] + rep.x[1] * t[i] - y[i])
                .collect();
            let g0: f64 = f.iter().map(|&f| psi(&loss, f)).sum();
            let g1: f64 = f.iter().zip(&t).map(|(&f, &t)| psi(&loss, f) * t).sum();
            let scale: f64 = f.iter().map(|&f| psi(&loss, f).abs()).sum();
            // (ftol = 1e-10 on a cost ~4 leaves a gradient of a few 1e-9 on a curvature ~30.)
            assert!(
                g0.abs() < 1e-7 * scale && g1.abs() < 1e-7 * scale,
                "{kind}: {g0} {g1}"
            );
            // The reported cost is the robust one, and the outliers are ignored.
            let cost: f64 = 0.5 * f.iter().map(|&f| loss.term(f)).sum::<f64>();
            assert!((rep.cost - cost).abs() <= 1e-12 * cost, "{kind}");
            assert!(
                (rep.x[0] - 1.0).abs() < 0.05 && (rep.x[1] - 2.0).abs() < 0.05,
                "{kind}: {}",
                rep.x
            );
        }
    }

    #[test]
    fn linear_is_plain_least_squares_and_bad_scales_are_refused() {
        let l = Loss::default();
        assert!(l.is_linear());
        assert_eq!(l.term(3.0), 9.0);
        let c = l.correct(-2.5);
        assert_eq!(
            (c.cost_residual, c.step_residual, c.jacobian_scale),
            (-2.5, -2.5, 1.0)
        );
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Loss::new(LossKind::Cauchy, bad).is_err());
        }
        assert_eq!(LossKind::from_name("SOFT_L1"), Some(LossKind::SoftL1));
        assert_eq!(LossKind::from_name("l2"), None);
        for k in LossKind::ALL {
            assert_eq!(LossKind::from_name(k.name()), Some(k));
        }
    }
}
