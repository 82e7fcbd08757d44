//! Adequacy: whether the fitted model describes the data and whether the weights match the
//! noise, from the residuals at the reported point (no I/O). `converged` says the optimum
//! was found; this says whether that optimum is a description of the surface.
//!
//! Every test is a significance test whose null hypothesis is "the model is right and each
//! weighted residual √wᵢ rᵢ is independent noise of one spread" (rᵢ = model − data in the
//! fitted space: the value, its relative deviation, or its logarithm):
//!
//! | test | statistic | null distribution | flags |
//! |---|---|---|---|
//! | `chi2` | χ² = Σ wᵢ rᵢ² (weights 1/σ_L², linear loss) | χ²(n − p), two-sided | misfit or σ_L too small; σ_L too large |
//! | `runs` | sign runs along each scan | Wald–Wolfowitz, normal, one-sided (too few) | a systematic misfit |
//! | `spread` | Spearman ρ of the local spread with L (absolute residuals) | √(m − 1)·ρ ~ N(0, 1), one-sided | proportional noise |
//! | `grazing` | signs where θi or θr > 70° | binomial(n, ½), two-sided | Fresnel rise, shadowing |
//! | `peak` | signs where the model is above half its peak at that θi | binomial, two-sided | clipped peak, sharper specular |
//! | `far` | signs more than 45° from the mirror direction | binomial, two-sided | a missing diffuse floor |
//!
//! A scan is the samples of one channel sharing θi and a φ-plane (φ and φ + 180°), ordered
//! by the signed angle θr (negative on the far side of the plane). The local spread is
//! |second difference| of the weighted residuals over disjoint triples of neighbours along
//! a scan, which a smooth misfit barely enters. Each test needs [`MIN_SAMPLES`] samples
//! (runs: signs in scans of two or more; regions: samples inside and outside).
//!
//! The verdict rejects the model when a test's p-value is below [`ALPHA`] / k, k the number
//! of tests run (Bonferroni: the chance that a correct model with correct weights is
//! flagged at all is at most [`ALPHA`]).

pub(crate) mod distributions;
mod wording;

use crate::fit::problem::channels::Channels;
use crate::fit::problem::ResidualKind;
use crate::geometry::{Geometry, PerSample};
use distributions::{chi2_sf, normal_sf, sign_test, slope, spearman, Runs};
use rayon::prelude::*;
use rustc_hash::FxHashMap;
use std::borrow::Cow;

/// Family-wise significance level of the adequacy tests (Bonferroni-corrected).
pub(crate) const ALPHA: f64 = 1e-3;
/// Incidence or reflection angle beyond which a sample is grazing, degrees.
pub(crate) const GRAZING_DEG: f64 = 70.0;
/// Angular distance from the mirror direction beyond which a sample is far from it, degrees.
pub(crate) const FAR_DEG: f64 = 45.0;
/// Fewest samples (signs, triples, region members) a test is run on.
pub(crate) const MIN_SAMPLES: usize = 10;

/// The verdict on a fit's adequacy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AdequacyVerdict {
    /// No test rejects the model or its weights.
    Adequate,
    /// The model does not describe the data (a systematic misfit).
    Misfit,
    /// The model follows the data, but the weights do not match the noise.
    Noise,
    /// Not assessed: no residuals at the reported point, or too few samples for any test.
    NotComputed,
    /// The model meets every sample to rounding error: the values look computed from the
    /// model, not measured, and carry no noise to test.
    Exact,
}

impl AdequacyVerdict {
    /// Lower-case name, as in JSON and CSV.
    pub fn name(self) -> &'static str {
        match self {
            AdequacyVerdict::Adequate => "adequate",
            AdequacyVerdict::Misfit => "misfit",
            AdequacyVerdict::Noise => "noise",
            AdequacyVerdict::NotComputed => "not_computed",
            AdequacyVerdict::Exact => "exact",
        }
    }

    /// Whether the verdict flags the fit (misfit or noise).
    pub fn flagged(self) -> bool {
        matches!(self, AdequacyVerdict::Misfit | AdequacyVerdict::Noise)
    }
}

/// One reason of a flagged verdict.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Reason {
    /// Short name: chi2_high, chi2_low, runs, proportional_noise, grazing_above,
    /// grazing_below, peak_below, peak_above, floor, far_above, far_below.
    pub code: Cow<'static, str>,
    /// What it means, in words, with the numbers.
    pub text: String,
    /// The test's p-value.
    #[serde(deserialize_with = "crate::fit::stats::json_number::nan_if_null")]
    pub p: f64,
}

/// The runs test of the residual signs along the scans.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunsTest {
    /// Observed runs (maximal blocks of one residual sign along a scan), summed over the scans.
    pub runs: usize,
    /// Runs expected under independent signs, Σ (1 + 2n₊n₋/n) over the scans.
    #[serde(deserialize_with = "crate::fit::stats::json_number::nan_if_null")]
    pub expected: f64,
    /// Standard deviation of the number of runs under independent signs.
    #[serde(deserialize_with = "crate::fit::stats::json_number::nan_if_null")]
    pub sd: f64,
    /// Signs counted: the scans' samples, those with a residual at rounding error or exactly
    /// fitted ([`EXACT_FIT`]) left out.
    pub signs: usize,
    /// Number of scans the signs were taken along.
    pub scans: usize,
    /// One-sided p-value of too few runs, P(Z ≤ z) with z = (runs − expected)/sd.
    #[serde(deserialize_with = "crate::fit::stats::json_number::nan_if_null")]
    pub p: f64,
}

/// The spread of the weighted residuals against L.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SpreadTest {
    /// Disjoint triples of scan neighbours.
    pub triples: usize,
    /// Spearman ρ of |second difference| with the mean fitted value of the triple.
    #[serde(deserialize_with = "crate::fit::stats::json_number::nan_if_null")]
    pub rho: f64,
    /// Slope of ln |second difference| on ln fitted value: ≈ 0 for constant noise, ≈ 1 for
    /// noise proportional to L (NaN when not computable).
    #[serde(deserialize_with = "crate::fit::stats::json_number::nan_if_null")]
    pub slope: f64,
    /// One-sided p-value of a spread growing with L, from √(m − 1)·ρ ~ N(0, 1), m the triples.
    #[serde(deserialize_with = "crate::fit::stats::json_number::nan_if_null")]
    pub p: f64,
}

/// The sign test of one region of the hemisphere.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RegionTest {
    /// grazing, peak or far.
    pub region: Cow<'static, str>,
    /// Samples in the region with a non-zero residual.
    pub n: usize,
    /// Of which the measured value lies above the model (negative residual).
    pub data_above: usize,
    /// Two-sided binomial(n, ½) p-value of `data_above` (exact sign test).
    #[serde(deserialize_with = "crate::fit::stats::json_number::nan_if_null")]
    pub p: f64,
}

/// The adequacy of a fit: verdict, reasons and the statistics behind them.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Adequacy {
    /// Adequate, misfit, noise, not computed or exact.
    pub verdict: AdequacyVerdict,
    /// The rejecting tests' reasons, in the order the tests ran (empty when adequate).
    pub reasons: Vec<Reason>,
    /// Family-wise significance level; each test is held to `alpha / tests`.
    #[serde(deserialize_with = "crate::fit::stats::json_number::nan_if_null")]
    pub alpha: f64,
    /// Number of tests run.
    pub tests: usize,
    /// R² in the fitted space (None when undefined).
    pub r2: Option<f64>,
    /// χ²/(n − p) when the weights are inverse variances of stated uncertainties.
    pub reduced_chi2: Option<f64>,
    /// Two-sided p-value of χ² against χ²(n − p).
    pub chi2_p: Option<f64>,
    /// The runs test (None when not run: fewer than [`MIN_SAMPLES`] signs or no variance).
    pub runs: Option<RunsTest>,
    /// The spread test (None when not run: residuals not absolute, fewer than [`MIN_SAMPLES`]
    /// triples, or ρ undefined).
    pub spread: Option<SpreadTest>,
    /// The sign tests of the grazing, peak and far regions that were run.
    pub regions: Vec<RegionTest>,
}

impl Adequacy {
    /// Not assessed (no residuals at the reported point).
    pub fn not_computed(r2: f64) -> Adequacy {
        Adequacy {
            verdict: AdequacyVerdict::NotComputed,
            reasons: Vec::new(),
            alpha: ALPHA,
            tests: 0,
            r2: r2.is_finite().then_some(r2),
            reduced_chi2: None,
            chi2_p: None,
            runs: None,
            spread: None,
            regions: Vec::new(),
        }
    }

    /// The verdict in words (one line).
    pub fn headline(&self) -> String {
        wording::headline(self)
    }

    /// The reason codes, comma-separated ("" when none).
    pub fn codes(&self) -> String {
        let codes: Vec<&str> = self.reasons.iter().map(|r| r.code.as_ref()).collect();
        codes.join(",")
    }
}

/// What the tests need of a finished fit.
pub(crate) struct FitResiduals<'a> {
    /// rᵢ = model − data in the fitted space (value, relative deviation or logarithm).
    pub residuals: &'a [f64],
    /// √wᵢ.
    pub sqrt_weight: &'a PerSample,
    /// The model's values (the measured quantity).
    pub fitted: &'a [f64],
    /// The samples' geometry (angles, wavelength), for the scans and the regions.
    pub geo: &'a Geometry,
    /// The channel of every sample (scans do not mix channels).
    pub channel: &'a Channels,
    /// The space the residuals are in (absolute, relative or logarithmic).
    pub kind: ResidualKind,
    /// Whether the weights are 1/σ_L² of stated uncertainties (then χ² is tested).
    pub absolute_weights: bool,
    /// Whether the loss is plain least squares (a robust loss expects outliers: no χ² test).
    pub linear_loss: bool,
    /// Whether the model has a diffuse (Lambertian) term.
    pub has_diffuse: bool,
    /// Number of free parameters p (the degrees of freedom of χ² are n − p).
    pub n_free: usize,
    /// χ² = Σ wᵢ rᵢ².
    pub chi2: f64,
    /// R² in the fitted space.
    pub r2: f64,
}

/// One test's outcome: its p-value and the reason it gives when it rejects.
struct Outcome {
    p: f64,
    reason: Option<(&'static str, String)>,
}

/// The adequacy of a fit from its residuals (see the module doc).
pub(crate) fn assess(fr: &FitResiduals) -> Adequacy {
    let n = fr.residuals.len();
    if n == 0 || fr.fitted.len() != n || fr.geo.len() != n {
        return Adequacy::not_computed(fr.r2);
    }
    let mut out = Adequacy::not_computed(fr.r2);
    let w = Weighted::of(fr);
    if w.n_used == 0 && w.rounding > 0 {
        out.verdict = AdequacyVerdict::Exact;
        return out;
    }
    let mut outcomes = Vec::new();
    if let Some(o) = chi2_test(fr, &w, &mut out) {
        outcomes.push(o);
    }
    let scans = scans(fr.geo, fr.channel, &w.used);
    if let Some(o) = runs_test(&w, &scans, &mut out) {
        outcomes.push(o);
    }
    if fr.kind == ResidualKind::Absolute {
        if let Some(o) = spread_test(fr, &w, &scans, &mut out) {
            outcomes.push(o);
        }
    }
    drop(scans);
    outcomes.extend(region_tests(fr, &w, &mut out));
    out.tests = outcomes.len();
    if outcomes.is_empty() {
        return out;
    }
    let level = ALPHA / outcomes.len() as f64;
    for o in outcomes {
        if let (true, Some((code, text))) = (o.p < level, o.reason) {
            out.reasons.push(Reason {
                code: code.into(),
                text,
                p: o.p,
            });
        }
    }
    // Weights that do not follow the noise come first: they also bend the fit, so the
    // misfit reasons that remain may follow from them.
    out.reasons
        .sort_by_key(|r| (r.code != "proportional_noise", wording::is_misfit(&r.code)));
    out.verdict = if out.reasons.iter().any(|r| wording::is_misfit(&r.code)) {
        AdequacyVerdict::Misfit
    } else if out.reasons.is_empty() {
        AdequacyVerdict::Adequate
    } else {
        AdequacyVerdict::Noise
    };
    out
}

/// The weighted residuals zᵢ = √wᵢ rᵢ, and which samples the tests use: those with a
/// finite zᵢ at least [`EXACT_FIT`] of the rms of z, and a residual above rounding error
/// ([`ROUNDING`] of the model's value for absolute residuals; of 1 for relative and log
/// residuals, which are relative already). A sample the model meets far more closely than
/// the noise allows carries no noise to test (a value that underflowed to 0, a stated σ_L
/// that was capped, a value computed from the model); its sign would be the model's
/// rounding.
struct Weighted<'a> {
    /// zᵢ; the residuals themselves when every weight is 1 (no copy of a big fit's
    /// residuals).
    z: Cow<'a, [f64]>,
    used: Vec<bool>,
    n_used: usize,
    /// Finite residuals at rounding error.
    rounding: usize,
}

/// A residual within this fraction of the model's value is rounding error.
pub(crate) const ROUNDING: f64 = 1e-12;

/// Weighted residuals below this fraction of their rms are exactly fitted: not tested.
pub(crate) const EXACT_FIT: f64 = 1e-6;

impl<'a> Weighted<'a> {
    fn of(fr: &FitResiduals<'a>) -> Weighted<'a> {
        let z = match fr.sqrt_weight {
            PerSample::One { value, .. } if *value == 1.0 => Cow::Borrowed(fr.residuals),
            w => (0..fr.residuals.len())
                .map(|i| fr.residuals[i] * w[i])
                .collect(),
        };
        let finite = || z.iter().filter(|v| v.is_finite());
        let rms = (finite().map(|v| v * v).sum::<f64>() / finite().count().max(1) as f64).sqrt();
        let at_rounding = |i: usize| {
            let scale = match fr.kind {
                ResidualKind::Absolute => fr.fitted[i].abs(),
                _ => 1.0,
            };
            fr.residuals[i].abs() <= ROUNDING * scale
        };
        let rounding = (0..z.len())
            .filter(|&i| z[i].is_finite() && at_rounding(i))
            .count();
        let used: Vec<bool> = (0..z.len())
            .map(|i| z[i].is_finite() && z[i].abs() > EXACT_FIT * rms && !at_rounding(i))
            .collect();
        let n_used = used.iter().filter(|&&u| u).count();
        Weighted {
            z,
            used,
            n_used,
            rounding,
        }
    }
}

/// The χ² test, when the weights are stated uncertainties under the linear loss (the
/// degrees of freedom count the samples tested).
fn chi2_test(fr: &FitResiduals, w: &Weighted, out: &mut Adequacy) -> Option<Outcome> {
    let dof = w.n_used.checked_sub(fr.n_free).filter(|&d| d > 0)? as f64;
    if !(fr.absolute_weights && fr.linear_loss && fr.chi2.is_finite()) {
        return None;
    }
    let upper = chi2_sf(fr.chi2, dof);
    let p = (2.0 * upper.min(1.0 - upper)).min(1.0);
    let reduced = fr.chi2 / dof;
    out.reduced_chi2 = Some(reduced);
    out.chi2_p = Some(p);
    Some(Outcome {
        p,
        reason: Some(wording::chi2(reduced, p, upper < 0.5)),
    })
}

/// The samples grouped into scans (channel, θi, φ-plane), each ordered by signed θr; the
/// scans in the order of their keys, those of one sample left out.
struct Scans {
    /// The samples' indices, scan after scan.
    items: Vec<u32>,
    /// Where each scan ends in `items`.
    ends: Vec<usize>,
}

impl Scans {
    /// The parts of `flat` (laid out as `items`) that belong to each scan.
    fn split<'a, T>(&'a self, flat: &'a [T]) -> impl Iterator<Item = &'a [T]> + 'a {
        let starts = std::iter::once(0).chain(self.ends.iter().copied());
        starts.zip(&self.ends).map(move |(a, &b)| &flat[a..b])
    }

    /// Each scan's sample indices.
    fn iter(&self) -> impl Iterator<Item = &[u32]> + '_ {
        self.split(&self.items)
    }
}

/// The used samples' scans (see [`Scans`]): a counting pass numbers each sample's scan,
/// then the indices are placed into their scans' exact places in one vector.
fn scans(geo: &Geometry, channel: &Channels, used: &[bool]) -> Scans {
    let plane_of = |i: usize| {
        let phi = geo.phi_r[i].to_degrees();
        (phi, phi.rem_euclid(180.0))
    };
    let key_of = |i: usize| {
        let (_, plane) = plane_of(i);
        (
            channel[i],
            (geo.theta_i[i].to_degrees() * 100.0).round() as i64,
            (plane * 100.0).round() as i64 % 18_000,
        )
    };
    // The positive side of the plane is the azimuth `plane` itself.
    let signed_theta_r = |i: u32| {
        let (phi, plane) = plane_of(i as usize);
        let side = if (phi - plane).abs() < 90.0 {
            1.0
        } else {
            -1.0
        };
        side * geo.theta_r[i as usize]
    };
    let mut keys = Keys::default();
    let mut counts: Vec<usize> = Vec::new();
    let group: Vec<u32> = (0..geo.len())
        .map(|i| {
            if !used[i] {
                return u32::MAX;
            }
            let g = keys.group(key_of(i));
            if g == counts.len() {
                counts.push(0);
            }
            counts[g] += 1;
            distributions::index_u32(g)
        })
        .collect();
    let mut order: Vec<usize> = (0..counts.len()).filter(|&g| counts[g] > 1).collect();
    order.sort_by_key(|&g| keys.keys[g]);
    let (mut next, mut ends) = (
        vec![usize::MAX; counts.len()],
        Vec::with_capacity(order.len()),
    );
    let mut end = 0;
    for &g in &order {
        next[g] = end;
        end += counts[g];
        ends.push(end);
    }
    let mut items = vec![0u32; end];
    for (i, &g) in group.iter().enumerate() {
        if let Some(at) = next.get_mut(g as usize).filter(|at| **at != usize::MAX) {
            items[*at] = distributions::index_u32(i);
            *at += 1;
        }
    }
    drop(group);
    let mut parts: Vec<&mut [u32]> = Vec::with_capacity(ends.len());
    let (mut rest, mut start) = (items.as_mut_slice(), 0);
    for &e in &ends {
        let (part, tail) = rest.split_at_mut(e - start);
        parts.push(part);
        (rest, start) = (tail, e);
    }
    parts
        .par_iter_mut()
        .for_each(|s| s.sort_by(|&a, &b| signed_theta_r(a).total_cmp(&signed_theta_r(b))));
    Scans { items, ends }
}

/// Keys numbered in the order they first came; a run of one key (the usual order of a
/// measurement's file) finds its number without a lookup.
struct Keys<K> {
    index: FxHashMap<K, usize>,
    keys: Vec<K>,
    last: Option<(K, usize)>,
}

impl<K> Default for Keys<K> {
    fn default() -> Self {
        Keys {
            index: FxHashMap::default(),
            keys: Vec::new(),
            last: None,
        }
    }
}

impl<K: Copy + Eq + std::hash::Hash> Keys<K> {
    /// The number of `key`.
    fn group(&mut self, key: K) -> usize {
        match self.last {
            Some((k, g)) if k == key => g,
            _ => {
                let keys = &mut self.keys;
                let g = *self.index.entry(key).or_insert_with(|| {
                    keys.push(key);
                    keys.len() - 1
                });
                self.last = Some((key, g));
                g
            }
        }
    }
}

/// The runs test of the residual signs along the scans.
fn runs_test(w: &Weighted, scans: &Scans, out: &mut Adequacy) -> Option<Outcome> {
    let signs: Vec<bool> = scans.items.iter().map(|&i| w.z[i as usize] > 0.0).collect();
    let runs = Runs::of(scans.split(&signs));
    let z = runs.z();
    if runs.signs < MIN_SAMPLES || !z.is_finite() {
        return None;
    }
    let p = normal_sf(-z);
    let test = RunsTest {
        runs: runs.runs,
        expected: runs.expected,
        sd: runs.variance.sqrt(),
        signs: runs.signs,
        scans: scans.ends.len(),
        p,
    };
    let reason = wording::runs(&test);
    out.runs = Some(test);
    Some(Outcome {
        p,
        reason: Some(reason),
    })
}

/// The spread of the weighted residuals against the fitted value: |second difference| of
/// disjoint triples of scan neighbours against their mean fitted value.
fn spread_test(
    fr: &FitResiduals,
    w: &Weighted,
    scans: &Scans,
    out: &mut Adequacy,
) -> Option<Outcome> {
    let z = |i: u32| w.z[i as usize];
    let fitted = |i: u32| fr.fitted[i as usize];
    let triples = scans.iter().map(|s| s.len() / 3).sum();
    let (mut spread, mut level) = (Vec::with_capacity(triples), Vec::with_capacity(triples));
    for s in scans.iter() {
        for t in s.chunks_exact(3) {
            let d = (z(t[1]) - 0.5 * (z(t[0]) + z(t[2]))).abs();
            let f = (fitted(t[0]) + fitted(t[1]) + fitted(t[2])) / 3.0;
            if d.is_finite() && f.is_finite() {
                spread.push(d);
                level.push(f);
            }
        }
    }
    let m = spread.len();
    let rho = spearman(&level, &spread);
    if m < MIN_SAMPLES || !rho.is_finite() {
        return None;
    }
    let p = normal_sf(rho * ((m - 1) as f64).sqrt());
    let (lx, ly): (Vec<f64>, Vec<f64>) = level
        .iter()
        .zip(&spread)
        .filter(|(f, d)| **f > 0.0 && **d > 0.0)
        .map(|(f, d)| (f.ln(), d.ln()))
        .unzip();
    let test = SpreadTest {
        triples: m,
        rho,
        slope: slope(&lx, &ly),
        p,
    };
    let reason = wording::spread(&test, fr.sqrt_weight);
    out.spread = Some(test);
    Some(Outcome {
        p,
        reason: Some(reason),
    })
}

/// The sign tests of the grazing samples, the lobe's core and the samples far from the
/// mirror direction (each where both it and the rest hold [`MIN_SAMPLES`] samples).
fn region_tests(fr: &FitResiduals, w: &Weighted, out: &mut Adequacy) -> Vec<Outcome> {
    let geo = fr.geo;
    let n = geo.len();
    let grazing: Vec<bool> = (0..n)
        .map(|i| geo.theta_i[i].max(geo.theta_r[i]) > GRAZING_DEG.to_radians())
        .collect();
    let far: Vec<bool> = (0..n)
        .into_par_iter()
        .map(|i| mirror_distance(geo, i) > FAR_DEG.to_radians())
        .collect();
    let peak = lobe_core(fr);
    let mut outcomes = Vec::new();
    for (region, members) in [("grazing", grazing), ("peak", peak), ("far", far)] {
        let inside = members.iter().filter(|&&m| m).count();
        if inside < MIN_SAMPLES || n - inside < MIN_SAMPLES {
            continue;
        }
        let signs: Vec<bool> = (0..n)
            .filter(|&i| members[i] && w.used[i])
            .map(|i| w.z[i] < 0.0)
            .collect();
        if signs.len() < MIN_SAMPLES {
            continue;
        }
        let above = signs.iter().filter(|&&a| a).count();
        let test = RegionTest {
            region: region.into(),
            n: signs.len(),
            data_above: above,
            p: sign_test(above, signs.len()),
        };
        outcomes.push(Outcome {
            p: test.p,
            reason: Some(wording::region(&test, fr.has_diffuse)),
        });
        out.regions.push(test);
    }
    outcomes
}

/// Angle between the view direction and the mirror direction of the incidence (radians):
/// cos δ = cos θi cos θr + sin θi sin θr cos φr (φr = 0 forward).
fn mirror_distance(geo: &Geometry, i: usize) -> f64 {
    let (ti, tr, phi) = (geo.theta_i[i], geo.theta_r[i], geo.phi_r[i]);
    (ti.cos() * tr.cos() + ti.sin() * tr.sin() * phi.cos())
        .clamp(-1.0, 1.0)
        .acos()
}

/// Whether each sample lies in the lobe's core: the model above half its largest value
/// among the samples of the same channel and θi.
fn lobe_core(fr: &FitResiduals) -> Vec<bool> {
    let geo = fr.geo;
    let key = |i: usize| {
        (
            fr.channel[i],
            (geo.theta_i[i].to_degrees() * 100.0).round() as i64,
        )
    };
    let mut keys = Keys::default();
    let mut top: Vec<f64> = Vec::new();
    let group: Vec<u32> = (0..geo.len())
        .map(|i| {
            let g = keys.group(key(i));
            if g == top.len() {
                top.push(f64::NEG_INFINITY);
            }
            top[g] = top[g].max(fr.fitted[i]);
            distributions::index_u32(g)
        })
        .collect();
    (0..geo.len())
        .map(|i| {
            let top = top[group[i] as usize];
            top > 0.0 && fr.fitted[i] >= 0.5 * top
        })
        .collect()
}
