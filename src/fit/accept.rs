//! Accept: whether the point a fit reached is a usable optimum (inside the model's physical
//! domain, resolved by the angular sampling, with a full-rank Jacobian), and the notes the
//! report gives on points that are not.

use super::problem::edges::{at_lower_bound, below, MIN_KT, MIN_T_OVER_SIGMA};
use super::problem::{FitInput, FitParam, ParamLayout, LINEAR};
use super::result::{Solved, Verdict};
use super::stats::covariance;
use crate::geometry::{Geometry, MIN_FLANK_SAMPLES};
use crate::model::ParamSpec;
use goniofit_lm::Termination;

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

/// Why the point a fit reached is not a usable optimum, in plain words naming the
/// parameter, or None when it is one. An optimum is usable when it lies inside the model's
/// physical domain (no parameter ran to an edge: σ → 0 or T/σ → 0 or kT → 0 for KBS,
/// w → 0 for the Gaussian lobe, an amplitude → 0, a dielectric's index n → 1 or n → ∞) and every free parameter of the solved
/// problem has a finite variance (the Jacobian has full rank: a declared reduction, the
/// rough or smooth regime, has already removed σ). `p` is in layout order; `unc` belongs
/// to the solved problem's free parameters.
pub(super) fn degeneracy(
    layout: &ParamLayout,
    specs: &[ParamSpec],
    input: &FitInput,
    p: &[f64],
    unc: &covariance::Uncertainty,
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
        let flank = input.geo.flank_samples(w);
        if flank < MIN_FLANK_SAMPLES {
            let resolved = input.geo.resolved_width().map_or(String::new(), |r| {
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
        if name == "n" && at_index_edge(specs[fp.spec].lower, p[k]) {
            return Some("the Fresnel index ran to its lower bound (n − 1 ≤ 1e-6): the data asks for a rise towards grazing steeper than any index gives (the factor's rise F(90°) = 1/R(0) grows without bound as n → 1), so the Fresnel factor does not describe this surface and n is not measured".into());
        }
        if name == "n" && at_index_infinity(specs[fp.spec].lower, p[k]) {
            return Some(format!("the Fresnel index ran to n → ∞ (n = {:.3e}), where the factor is 1: the data shows no rise towards grazing beyond the lobe's own, so the Fresnel factor does not describe this surface, n is not measured, and the lobe is the one without it", p[k]));
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

/// Whether a dielectric's index `n` (lower bound `lower` = 1) sits at that bound, within
/// 10⁻⁶ (where F(90°) = 1/R(0) > 10¹²): the index's edge of the domain.
fn at_index_edge(lower: f64, n: f64) -> bool {
    lower == 1.0 && n - lower <= 1e-6
}

/// Whether a dielectric's index `n` (lower bound `lower` = 1) ran to where the factor is 1
/// ([`FLAT_INDEX`](crate::model::fresnel::FLAT_INDEX)): the index's edge n → ∞.
fn at_index_infinity(lower: f64, n: f64) -> bool {
    lower == 1.0 && n >= crate::model::fresnel::FLAT_INDEX
}

/// Names of the free parameters that take part in the Jacobian's null space.
fn null_space_names(layout: &ParamLayout, unc: &covariance::Uncertainty) -> Vec<String> {
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
