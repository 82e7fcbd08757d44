//! The scenes of a recovery run a reader should look at: every scene whose truth lies
//! outside ±[`super::COVERAGE_K`] reported standard errors of a scored quantity, each with the
//! commands that reproduce it — the run restricted to that scene (`recover --only`), and
//! its data as a file (`synth`, the scene's truth, layout, noise and seed) with the fit a
//! user would run on it. Among them, the *confidently wrong* scenes: converged, yet a
//! determined quantity is off by more than [`WRONG_SE`] standard errors and [`WRONG_REL`]
//! of its truth (a wrong optimum reported as a usable one).

use super::{RecoverConfig, Regime, SceneResult};
use crate::fit::driver::Verdict;
use serde::Serialize;

/// Standard errors past which a converged scene's miss counts as confidently wrong.
pub(crate) const WRONG_SE: f64 = 10.0;

/// Relative error past which a converged scene's miss counts as confidently wrong.
pub(crate) const WRONG_REL: f64 = 0.2;

/// One scored quantity whose truth lies outside ±k standard errors.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct Miss {
    /// Report name of the quantity (see [`super::Check::name`]).
    pub name: String,
    /// (value − truth)/stderr.
    pub z: f64,
    /// |value − truth|/truth.
    pub rel_error: f64,
}

/// A scene with at least one [`Miss`], and how to reproduce it.
#[derive(Debug, Clone, Serialize)]
pub(crate) struct Outlier {
    /// The scene's id (pass it to `recover --only`).
    pub id: usize,
    /// The scene's regime.
    pub regime: Regime,
    /// The scene's layout, as [`crate::geometry::layout::Layout::describe`] writes it.
    pub layout: String,
    /// The fit's verdict (None when the fit returned an error).
    pub verdict: Option<Verdict>,
    /// Whether the scene's fit converged.
    pub converged: bool,
    /// Every scored quantity whose truth lies outside ±[`super::COVERAGE_K`] standard errors.
    pub misses: Vec<Miss>,
    /// Converged with a miss beyond [`WRONG_SE`] standard errors and [`WRONG_REL`].
    pub wrong: bool,
    /// This scene alone, fitted as in the run.
    pub recover_command: String,
    /// The scene's data as a CSV with its sigma_L column (truth beside it as JSON).
    pub synth_command: String,
    /// The fit of that CSV a user would run (weights 1/sigma_L²).
    pub fit_command: String,
}

/// The scenes of `results` with a truth outside ±[`super::COVERAGE_K`] s.e., in scene order.
pub(crate) fn outliers(results: &[SceneResult], config: &RecoverConfig) -> Vec<Outlier> {
    results
        .iter()
        .filter_map(|r| {
            let misses: Vec<Miss> = r
                .checks
                .iter()
                .filter(|c| c.covered == Some(false))
                .filter_map(|c| {
                    let z = (c.value - c.truth) / c.stderr?;
                    Some(Miss {
                        name: c.name.clone(),
                        z,
                        rel_error: c.rel_error,
                    })
                })
                .collect();
            if misses.is_empty() {
                return None;
            }
            let wrong = r.converged
                && misses
                    .iter()
                    .any(|m| m.z.abs() > WRONG_SE && m.rel_error > WRONG_REL);
            let s = &r.scene;
            let file = format!("scene-{}-{}.csv", config.seed, s.id);
            let factors = crate::model::ModelOptions {
                fresnel: s.fresnel,
                shadowing: s.shadowing,
                ..Default::default()
            }
            .factors_label();
            let index = s.n.map(|n| format!(",n={n}")).unwrap_or_default()
                + &s.kappa.map(|k| format!(",kappa={k}")).unwrap_or_default();
            Some(Outlier {
                id: s.id,
                regime: s.regime,
                layout: s.layout.clone(),
                verdict: r.verdict,
                converged: r.converged,
                misses,
                wrong,
                recover_command: format!(
                    "goniofit recover --scenes {} --seed {} --noise {} --only {}{factors}",
                    config.scenes, config.seed, config.noise, s.id
                ),
                synth_command: format!(
                    "goniofit synth --model kbs{factors} --params sigma={},T={},scale={}{index} --wavelength {} --layout '{}' --noise {} --noise-kind {} --seed {} --write-sigma --out {file}",
                    s.sigma,
                    s.corr_len,
                    s.scale,
                    s.wavelength,
                    s.layout,
                    s.noise.level,
                    s.noise.kind.name(),
                    s.noise.seed
                ),
                fit_command: format!("goniofit fit --model kbs{factors} {file}"),
            })
        })
        .collect()
}

/// The outliers as text: one line per scene (its misses in standard errors and percent,
/// the confidently wrong ones marked), then its three commands.
pub(crate) fn table(outliers: &[Outlier]) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    for o in outliers {
        let misses = o
            .misses
            .iter()
            .map(|m| format!("{} {:+.1} s.e. ({:.2} %)", m.name, m.z, 100.0 * m.rel_error))
            .collect::<Vec<_>>()
            .join(", ");
        let _ = writeln!(
            s,
            "scene {} ({}, {}, {}{}): {misses}",
            o.id,
            o.regime.name(),
            o.layout,
            o.verdict.map_or("no verdict", Verdict::name),
            if o.wrong {
                "; CONFIDENTLY WRONG"
            } else if o.converged {
                ""
            } else {
                "; not converged"
            }
        );
        let _ = writeln!(s, "    {}", o.recover_command);
        let _ = writeln!(s, "    {} && {}", o.synth_command, o.fit_command);
    }
    s
}
