//! Validate: whether the data can be fitted at all (before the fit), and what the
//! optimum's report must say about points that are not a usable optimum (after it).

use super::config::FitConfig;
use super::lm::Termination;
use super::problem::{FitInput, FitParam, ParamLayout, Transform, LINEAR};
use super::reduce::Solved;
use super::stats;
use crate::error::{Error, Result};
use crate::model::{Model, ParamSpec};

/// The parameter layout of the fit with the `--fix` values held, and the values the user
/// gave (`--fix` and `--init`, layout order). Refuses data that cannot be fitted: no more
/// samples than free parameters, or every value zero.
pub(super) fn prepare(
    model: &dyn Model,
    input: &FitInput,
    config: &FitConfig,
) -> Result<(ParamLayout, Vec<Option<f64>>)> {
    let n = input.geo.len();
    let mut layout = ParamLayout::new(model, &input.channel_names);
    let mut fixed = vec![None; layout.len()];
    assign(&layout, &config.fix, &mut fixed)?;
    for (k, f) in fixed.iter().enumerate() {
        layout.params[k].fixed = *f;
    }
    let n_free = layout.free().len();
    if n <= n_free {
        return Err(Error::Usage(format!(
            "{n} samples for {n_free} free parameters: a fit needs more samples than free parameters"
        )));
    }
    if input.y.iter().all(|&v| v == 0.0) {
        return Err(Error::Usage(
            "every measured value is zero: nothing to fit".into(),
        ));
    }
    let mut given = fixed;
    assign(&layout, &config.init, &mut given)?;
    Ok((layout, given))
}

/// Whether a free non-negative parameter at `value` with standard error `se` sits at its
/// lower bound 0 (within 10⁻³ standard errors, or exactly 0).
pub(super) fn at_lower_bound(fp: &FitParam, value: f64, se: Option<f64>) -> bool {
    fp.fixed.is_none()
        && fp.transform == Transform::NonNegative
        && se.is_some_and(|e| value <= 1e-3 * e.max(f64::MIN_POSITIVE) || value == 0.0)
}

/// The note for a parameter at its lower bound.
pub(super) fn lower_bound_note(fp: &FitParam) -> String {
    format!(
        "{} is at its lower bound 0: the data shows no such component",
        fp.name
    )
}

/// The note for a solver that stopped without converging, if it did.
pub(super) fn termination_note(termination: Termination) -> Option<String> {
    // A degenerate fit's note says why in plain words already.
    (!termination.converged() && termination != Termination::Degenerate).then(|| {
        format!(
            "the solver stopped without converging: {}",
            termination.describe()
        )
    })
}

/// Resolve (name, value) pairs against a layout: a bare per-channel name applies to every
/// channel.
fn assign(layout: &ParamLayout, pairs: &[(String, f64)], out: &mut [Option<f64>]) -> Result<()> {
    for (name, v) in pairs {
        let ks = layout.find(name);
        if ks.is_empty() {
            return Err(Error::Param {
                name: name.clone(),
                message: format!(
                    "not a parameter of this fit (it has: {})",
                    layout
                        .params
                        .iter()
                        .map(|p| p.name.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            });
        }
        for k in ks {
            let fp = &layout.params[k];
            if !v.is_finite()
                || (fp.transform == Transform::Log && *v <= 0.0)
                || *v < 0.0 && fp.transform == Transform::NonNegative
            {
                return Err(Error::Param {
                    name: name.clone(),
                    message: format!("value {v} is outside its domain"),
                });
            }
            out[k] = Some(*v);
        }
    }
    Ok(())
}

/// T/σ below which a KBS lobe is not a surface's specular lobe: the rms slope 2σ/T > 20
/// is far outside the paper's domain, and the lobe then only mimics a diffuse term.
pub const MIN_T_OVER_SIGMA: f64 = 0.1;

/// k·T = 2πT/λ below which a KBS lobe is wider than the hemisphere (its angular width in
/// v_xy is ~2/(kT) ≫ the largest v_xy ≈ 2): flat, so again only a second diffuse term.
pub const MIN_KT: f64 = 0.1;

/// Fewest samples on the flank of a Gaussian lobe (between e^{-8} and e^{-1/8} of its
/// peak) for its width w to count as resolved by the angular sampling.
pub const MIN_FLANK_SAMPLES: usize = 3;

/// Whether a KBS point (layout order) lies at an edge of the physical domain:
/// T/σ < [`MIN_T_OVER_SIGMA`] or 2πT/λ < [`MIN_KT`] (λ: the median wavelength of `input`).
/// The start search rejects such refined starts; false for models without σ and T.
pub(super) fn at_kbs_edge(layout: &ParamLayout, input: &FitInput, p: &[f64]) -> bool {
    let first = |name: &str| layout.find(name).first().copied();
    let (Some(ks), Some(kt)) = (first("sigma"), first("T")) else {
        return false;
    };
    let lambda = stats::median(&input.geo.wavelength);
    let k_t = 2.0 * std::f64::consts::PI * p[kt] / lambda;
    below(p[kt] / p[ks], MIN_T_OVER_SIGMA) || below(k_t, MIN_KT)
}

/// Why the point a fit reached is not a usable optimum, in plain words naming the
/// parameter, or None when it is one. An optimum is usable when it lies inside the model's
/// physical domain (no parameter ran to an edge: σ → 0 or T/σ → 0 or kT → 0 for KBS,
/// w → 0 for the Gaussian lobe, an amplitude → 0) and every free parameter of the solved
/// problem has a finite variance (the Jacobian has full rank: a declared reduction, the
/// rough or smooth regime, has already removed σ). `p` is in layout order; `unc` belongs
/// to the solved problem's free parameters.
pub(super) fn degeneracy(
    layout: &ParamLayout,
    specs: &[ParamSpec],
    input: &FitInput,
    p: &[f64],
    unc: &stats::Uncertainty,
) -> Option<String> {
    let first = |name: &str| layout.find(name).first().copied();
    if let (Some(ks), Some(kt)) = (first("sigma"), first("T")) {
        let (sigma, t) = (p[ks], p[kt]);
        let lambda = stats::median(&input.geo.wavelength);
        if below(t / sigma, MIN_T_OVER_SIGMA) {
            return Some(format!(
                "the data shows no specular lobe beyond the diffuse term: T/σ ran below {MIN_T_OVER_SIGMA} (T/σ = {:.3e}, rms slope 2σ/T = {:.3e}), far outside the surfaces KBS describes",
                t / sigma,
                2.0 * sigma / t
            ));
        }
        let kt_value = 2.0 * std::f64::consts::PI * t / lambda;
        if below(kt_value, MIN_KT) {
            return Some(format!(
                "the data shows no specular lobe beyond the diffuse term: the correlation length T ran to 0 (2πT/λ = {kt_value:.3e} < {MIN_KT}), so the fitted lobe is flatter than the hemisphere"
            ));
        }
    }
    if let Some(kw) = first("w") {
        let w = p[kw];
        let flank = (0..input.geo.len())
            .filter(|&i| {
                let g = &input.geo;
                let q = (g.theta_r[i] - g.theta_i[i]).powi(2) + 0.25 * g.phi_r[i].powi(2);
                let z = 0.5 * q / (w * w);
                (0.125..=8.0).contains(&z)
            })
            .count();
        if flank < MIN_FLANK_SAMPLES {
            return Some(format!(
                "the specular lobe is narrower than the angular sampling: its width w ran to {w:.3e} rad and only {flank} samples lie on its flank, so w is not measured"
            ));
        }
    }
    let free = layout.free();
    for (i, &k) in free.iter().enumerate() {
        let fp = &layout.params[k];
        let name = specs[fp.spec].name;
        let se_x = unc.covariance[(i, i)].max(0.0).sqrt();
        let se = se_x * fp.transform.dp_dx(fp.transform.to_x(p[k])).abs();
        if LINEAR.contains(&name) && name != "scale_d" && at_lower_bound(fp, p[k], Some(se)) {
            return Some(format!(
                "the data shows no such lobe: its amplitude {} ran to its lower bound 0",
                fp.name
            ));
        }
    }
    if unc.rank < free.len() {
        let names = null_space_names(layout, unc);
        return Some(format!(
            "the Jacobian lost rank: the data does not determine {} (no known regime explains it, so no reduced problem was fitted)",
            names.join(", ")
        ));
    }
    None
}

/// Names of the free parameters that take part in the Jacobian's null space.
fn null_space_names(layout: &ParamLayout, unc: &stats::Uncertainty) -> Vec<String> {
    let free = layout.free();
    let mut names: Vec<String> = free
        .iter()
        .enumerate()
        .filter(|&(i, _)| unc.undetermined.iter().any(|v| v[i].abs() > 0.1 * v.norm()))
        .map(|(_, &k)| layout.params[k].name.clone())
        .collect();
    if names.is_empty() {
        names.push("a combination of the parameters".into());
    }
    names
}

/// Mark a converged (or iteration-limited) fit that is not a usable optimum as
/// [`Termination::Degenerate`], with the reason as a note. Interrupted and timed-out fits
/// keep their termination (they say why they stopped already).
pub(super) fn accept(solved: &mut Solved, input: &FitInput) {
    let t = solved.run.lm.termination;
    if matches!(t, Termination::Interrupted | Termination::Timeout) {
        return;
    }
    let specs = solved.problem.model.params();
    let reason = degeneracy(
        &solved.problem.layout,
        specs,
        input,
        &solved.run.values,
        &solved.unc,
    );
    if let Some(reason) = reason {
        solved.run.lm.termination = Termination::Degenerate;
        solved.notes.push(reason);
    }
}

/// Whether `v` is below `limit` or not a number (NaN counts as past the edge).
fn below(v: f64, limit: f64) -> bool {
    v.partial_cmp(&limit) != Some(std::cmp::Ordering::Greater)
        && v.partial_cmp(&limit) != Some(std::cmp::Ordering::Equal)
}
