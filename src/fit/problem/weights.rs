//! The weights of a fit's residuals, from the data's stated uncertainty, transformed with
//! the residual kind.
//!
//! A `sigma_L` column is the standard uncertainty of L. The residual's uncertainty follows to
//! first order: absolute r = f − y has σ_r = σ_L; relative r = (f − y)/ŷ and log
//! r = ln f − ln ŷ (ŷ = max(|y|, floor) resp. max(y, floor)) both have σ_r = σ_L/ŷ. The
//! weight is 1/σ_r², so reduced χ² ≈ 1 when σ_L is right, whatever the residual kind. A
//! `weight` column is taken as given (it states the weight of the residual itself).

use super::ResidualKind;
use crate::geometry::PerSample;

/// Where the weights came from, and how they were transformed.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WeightsInfo {
    /// `sigma_L column`, `weight column` or `none`.
    pub source: String,
    /// The weight of a residual, as a formula (`1/sigma_L²`, `max(|L|, floor)²/sigma_L²`, …).
    pub transform: String,
}

/// The weights wᵢ of the residuals of kind `kind` (see the module doc), and their
/// description. `weight`: a weight column (used as given); `sigma_l`: an uncertainty column;
/// neither: all weights 1 (one value for every sample). `floor` is the residual floor (relative, log).
pub(crate) fn residual_weights(
    weight: Option<&[f64]>,
    sigma_l: Option<&[f64]>,
    y: &[f64],
    kind: ResidualKind,
    floor: f64,
) -> (PerSample, WeightsInfo) {
    let info = |source: &str, transform: &str| WeightsInfo {
        source: source.into(),
        transform: transform.into(),
    };
    match (sigma_l, weight) {
        (Some(s), _) => {
            let scale = |i: usize| match kind {
                ResidualKind::Absolute => 1.0,
                ResidualKind::Relative => y[i].abs().max(floor),
                ResidualKind::Log => y[i].max(floor),
            };
            let w: PerSample = (0..y.len()).map(|i| (scale(i) / s[i]).powi(2)).collect();
            let transform = match kind {
                ResidualKind::Absolute => "1/sigma_L²",
                ResidualKind::Relative => {
                    "max(|L|, floor)²/sigma_L² (the uncertainty of (f − L)/|L|)"
                }
                ResidualKind::Log => "max(L, floor)²/sigma_L² (the uncertainty of ln f − ln L)",
            };
            (w, info("sigma_L column", transform))
        }
        (None, Some(w)) => (w.to_vec().into(), info("weight column", "as given")),
        (None, None) => (
            PerSample::One {
                value: 1.0,
                len: y.len(),
            },
            info("none", "1 for every sample"),
        ),
    }
}

/// How many measured values the floor raises: |y| < floor for relative residuals, y < floor
/// for log residuals, none for absolute ones.
pub(crate) fn floor_raised(y: &[f64], kind: ResidualKind, floor: f64) -> usize {
    match kind {
        ResidualKind::Absolute => 0,
        ResidualKind::Relative => y.iter().filter(|v| v.abs() < floor).count(),
        ResidualKind::Log => y.iter().filter(|&&v| v < floor).count(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_and_log_weights_are_the_inverse_variance_of_the_residual() {
        let y = [2.0, 0.5, 0.0];
        let s = [0.02, 0.01, 0.01];
        let (w, info) = residual_weights(None, Some(&s), &y, ResidualKind::Relative, 0.1);
        // σ_r = σ_L/ŷ: 0.01, 0.02, 0.1 (the last ŷ is the floor).
        assert_eq!(w.iter().collect::<Vec<_>>(), vec![1e4, 2500.0, 100.0]);
        assert_eq!(info.source, "sigma_L column");
        let (w, _) = residual_weights(None, Some(&s), &y, ResidualKind::Absolute, 0.1);
        assert_eq!(w.iter().collect::<Vec<_>>(), vec![2500.0, 1e4, 1e4]);
        let (w, _) = residual_weights(Some(&[3.0, 1.0, 2.0]), None, &y, ResidualKind::Log, 0.1);
        assert_eq!(w.iter().collect::<Vec<_>>(), vec![3.0, 1.0, 2.0]);
        let (w, info) = residual_weights(None, None, &y, ResidualKind::Log, 0.1);
        assert_eq!(
            w,
            PerSample::One { value: 1.0, len: 3 },
            "none stored per sample"
        );
        assert_eq!((w[2], info.source.as_str()), (1.0, "none"));
        assert_eq!(floor_raised(&y, ResidualKind::Log, 0.1), 1);
        assert_eq!(floor_raised(&[-0.05, 0.2], ResidualKind::Relative, 0.1), 1);
        assert_eq!(floor_raised(&[-0.05, 0.2], ResidualKind::Log, 0.1), 1);
        assert_eq!(floor_raised(&y, ResidualKind::Absolute, 0.1), 0);
    }
}
