//! Validate: whether the data can be fitted at all (before the fit), and what the
//! optimum's report must say about points that are not a usable optimum (after it).

use super::config::FitConfig;
use super::lm::Termination;
use super::problem::{FitInput, FitParam, ParamLayout, LINEAR};
use super::reduce::Solved;
use super::result::Verdict;
use super::stats;
use crate::error::{Error, Result};
use crate::geometry::Geometry;
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
    layout.set_amplitude_units(&input.y, &input.channel);
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
    if rough_by_construction(model, config) {
        hold_rough_sigma(&mut layout, &mut given, input);
    }
    Ok((layout, given))
}

/// Whether the fit is in the rough approximation's own parameters by construction: the
/// `kbs-rough` model (eq. 43, ⟨|ρ|²⟩ ≈ πT²F²/(A g) · e^{−a/g}) depends on σ and T only
/// through T/σ (g ∝ σ², a ∝ T²), so σ and T cannot both be fitted; unless the user fixes
/// σ, the fit holds it (see [`hold_rough_sigma`]) and reports T/σ, the amplitude s(T/σ)²
/// and s, with σ and T not determined.
pub(super) fn rough_by_construction(model: &dyn Model, config: &FitConfig) -> bool {
    model.name() == "kbs-rough"
        && !config
            .fix
            .iter()
            .any(|(name, _)| name.eq_ignore_ascii_case("sigma"))
}

/// Hold σ of a `kbs-rough` fit at its `--init` value, or else at the median wavelength
/// (any value gives the same model values at the same T/σ; σ = λ keeps g ≈ 40–160, well
/// inside the fit's domain). T then carries T/σ.
fn hold_rough_sigma(layout: &mut ParamLayout, given: &mut [Option<f64>], input: &FitInput) {
    let Some(&ks) = layout.find("sigma").first() else {
        return;
    };
    let held = given[ks].unwrap_or_else(|| input.geo.wavelength.median());
    layout.params[ks].fixed = Some(held);
    given[ks] = Some(held);
}

/// Whether a free non-negative parameter at `value` with standard error `se` sits at its
/// lower bound 0 (within 10⁻³ standard errors, or exactly 0).
pub(super) fn at_lower_bound(fp: &FitParam, value: f64, se: Option<f64>) -> bool {
    fp.fixed.is_none()
        && fp.transform.is_non_negative()
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
                || (fp.transform.is_log() && *v <= fp.transform.lower())
                || *v < 0.0 && fp.transform.is_non_negative()
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

/// T/σ below which a KBS lobe is not a surface's specular lobe: Beckmann's α = 2σ/T > 20
/// is far outside the paper's domain, and the lobe then only mimics a diffuse term.
pub const MIN_T_OVER_SIGMA: f64 = 0.1;

/// k·T = 2πT/λ below which a KBS lobe is wider than the hemisphere (its angular width in
/// v_xy is ~2/(kT) ≫ the largest v_xy ≈ 2): flat, so again only a second diffuse term.
pub const MIN_KT: f64 = 0.1;

/// Fewest samples on the flank of a Gaussian lobe (between e^{-8} and e^{-1/8} of its
/// peak) for its width w to count as resolved by the angular sampling.
pub const MIN_FLANK_SAMPLES: usize = 3;

/// The offset √q = √((θr − θi)² + φr²/4) (rad) of sample i from the mirror direction, in
/// the metric of the Gaussian lobe's exponent (eq. 34: the lobe is exp(−½ q/w²)).
fn lobe_offset(geo: &Geometry, i: usize) -> f64 {
    ((geo.theta_r[i] - geo.theta_i[i]).powi(2) + 0.25 * geo.phi_r[i].powi(2)).sqrt()
}

/// How many samples lie on the flank of a Gaussian lobe of width `w` (rad): between e^{-8}
/// and e^{-1/8} of its peak, i.e. at an offset √q between w/2 and 4w.
pub(super) fn flank_samples(geo: &Geometry, w: f64) -> usize {
    (0..geo.len())
        .filter(|&i| (0.5 * w..=4.0 * w).contains(&lobe_offset(geo, i)))
        .count()
}

/// The narrowest Gaussian lobe width (rad) the angular sampling resolves: the smallest w
/// with at least [`MIN_FLANK_SAMPLES`] samples on its flank ([`flank_samples`]). Exact: for
/// the offsets d sorted ascending, three of them fit in [w/2, 4w] first for some three
/// consecutive ones, at w = d_{j+2}/4 when d_{j+2} ≤ 8 d_j. None when no w resolves (fewer
/// than three samples off the mirror direction). O(n log n).
pub fn resolved_width(geo: &Geometry) -> Option<f64> {
    let mut d: Vec<f64> = (0..geo.len())
        .map(|i| lobe_offset(geo, i))
        .filter(|&d| d > 0.0 && d.is_finite())
        .collect();
    d.sort_by(f64::total_cmp);
    let k = MIN_FLANK_SAMPLES - 1;
    d.windows(MIN_FLANK_SAMPLES)
        .filter(|t| t[k] <= 8.0 * t[0])
        .map(|t| 0.25 * t[k])
        .reduce(f64::min)
}

/// The lower bound on a Gaussian lobe's width w in a fit: half of [`resolved_width`]. A
/// solver step to a narrower lobe is rejected (as a step outside the models' domain), so a
/// lobe the sampling does not resolve ends at this bound, where fewer than
/// [`MIN_FLANK_SAMPLES`] samples lie on its flank and [`degeneracy`] says so, instead of
/// running w to 1e-100. None (no bound) when no width is resolved at all.
pub fn width_floor(geo: &Geometry) -> Option<f64> {
    resolved_width(geo).map(|w| 0.5 * w)
}

/// Whether a KBS point (layout order) lies at an edge of the physical domain:
/// T/σ < [`MIN_T_OVER_SIGMA`] or 2πT/λ < [`MIN_KT`] (λ: the median wavelength of `input`).
/// The start search rejects such refined starts; false for models without σ and T.
pub(super) fn at_kbs_edge(layout: &ParamLayout, input: &FitInput, p: &[f64]) -> bool {
    let first = |name: &str| layout.find(name).first().copied();
    let (Some(ks), Some(kt)) = (first("sigma"), first("T")) else {
        return false;
    };
    let lambda = input.geo.wavelength.median();
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
        let lambda = input.geo.wavelength.median();
        if below(t / sigma, MIN_T_OVER_SIGMA) {
            return Some(format!(
                "the data shows no specular lobe beyond the diffuse term: T/σ ran below {MIN_T_OVER_SIGMA} (T/σ = {:.3e}, Beckmann's α = 2σ/T = {:.3e}), far outside the surfaces KBS describes",
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
        if let Some(why) = narrow_kbs_lobe(&input.geo, sigma, t) {
            return Some(why);
        }
    }
    if let Some(kw) = first("w") {
        let w = p[kw];
        let flank = flank_samples(&input.geo, w);
        if flank < MIN_FLANK_SAMPLES {
            let resolved = resolved_width(&input.geo).map_or(String::new(), |r| {
                format!(" (the sampling resolves lobes of w ≥ {r:.3e} rad)")
            });
            return Some(format!(
                "the specular lobe is narrower than the angular sampling: its width w ran to {w:.3e} rad and only {flank} samples lie on its flank, so w is not measured{resolved}"
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
/// [`Termination::Degenerate`], with the reason as a note; a verdict that said every
/// parameter is determined becomes [`Verdict::Partial`] (the point does not determine
/// them). Interrupted and timed-out fits keep their termination (they say why they stopped
/// already).
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
        solved.notes.push(reason.clone());
        solved.unusable = Some(reason);
        if solved.verdict == Verdict::Full {
            solved.verdict = Verdict::Partial;
        }
    }
}

/// Why a KBS lobe is unresolved, if it is: narrower than the angular sampling. Each
/// sample's lobe factor f (its attenuation off the mirror direction at its own g: ln f =
/// −a/max(g, 1), the rough limit e^{−a/g} for g ≥ 1 and the smooth one e^{−a} below; the
/// intermediate regime's mixture of the two is between them) places it inside the lobe
/// (f > e^{−1/8}), on its flank (e^{−8} ≤ f ≤ e^{−1/8}, the flank of the Gaussian lobe's
/// test) or beyond it; the lobe is unresolved when fewer than [`MIN_FLANK_SAMPLES`] lie on
/// its flank and more lie beyond it than inside (a lobe flatter than the hemisphere is
/// T → 0, caught before). Its width, T/σ (T in the smooth regime), and its scale are then
/// not measured separately: only the level of the samples nearest the mirror direction
/// (synthetic Gaussian lobe w = 0.002 rad, 1° sampling, fitted by kbs+lambert: T/σ ≈ 900
/// ± 6500 %, corr(T, scale) = −1).
fn narrow_kbs_lobe(geo: &Geometry, sigma: f64, t: f64) -> Option<String> {
    let (mut inside, mut flank, mut beyond) = (0usize, 0usize, 0usize);
    for i in 0..geo.len() {
        let ln_f = -geo.a(i, t) / geo.g(i, sigma).max(1.0);
        if ln_f > -0.125 {
            inside += 1;
        } else if ln_f >= -8.0 {
            flank += 1;
        } else {
            beyond += 1;
        }
    }
    (flank < MIN_FLANK_SAMPLES && beyond > inside).then(|| {
        format!(
            "the specular lobe is narrower than the angular sampling: {inside} samples lie inside it, {flank} on its flank ({MIN_FLANK_SAMPLES} are needed to measure its width) and {beyond} beyond it, so its width (T/σ = {:.3e}) and its scale are not measured, only the level of the samples nearest the mirror direction",
            t / sigma
        )
    })
}

/// Whether `v` is below `limit` or not a number (NaN counts as past the edge).
fn below(v: f64, limit: f64) -> bool {
    v.partial_cmp(&limit) != Some(std::cmp::Ordering::Greater)
        && v.partial_cmp(&limit) != Some(std::cmp::Ordering::Equal)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Quantity, Sample};

    /// In-plane samples at θi = 0.2 rad and θr = θi + each offset (rad).
    fn in_plane(offsets: &[f64]) -> Geometry {
        let theta_i = 0.2;
        let s: Vec<Sample> = offsets
            .iter()
            .map(|d| Sample {
                theta_i,
                theta_r: theta_i + d,
                phi_r: 0.0,
            })
            .collect();
        Geometry::new(&s, &[1.0], Quantity::Radiance).unwrap()
    }

    #[test]
    fn resolved_width_is_the_narrowest_lobe_with_three_flank_samples() {
        // Offsets 0, 0.1, 0.2, 0.3, 1.2 rad: the first three off the mirror fit in
        // [w/2, 4w] from w = 0.3/4 on.
        let geo = in_plane(&[0.0, 0.1, 0.2, 0.3, 1.2]);
        let w = resolved_width(&geo).unwrap();
        assert!((w - 0.075).abs() < 1e-15, "{w}");
        assert_eq!(flank_samples(&geo, w), 3);
        assert_eq!(flank_samples(&geo, w * (1.0 - 1e-12)), 2);
        assert_eq!(width_floor(&geo), Some(0.5 * w));
        // Offsets 0.01, 0.1, 1 rad: no three within a factor 8 of each other, so none.
        assert_eq!(resolved_width(&in_plane(&[0.01, 0.1, 1.0])), None);
    }
}
