//! Geometry of a measurement (Peters 2000, eq. 1–8) and the per-sample quantities the
//! models need, computed once per dataset.
//!
//! Conventions (docs/conventions.md): θi, θr from the surface normal, θi ∈ [0, π/2), θr ∈ [0, π/2];
//! φr from the plane of incidence, **φr = 0 is the forward (specular) side**. All angles
//! here are radians. Lengths (σ, T, X, Y, λ) share one unit; only ratios to λ enter.
//!
//! Measurement layouts, the sets of directions a data set is measured at, are [`layout`].

mod column;
pub(crate) mod layout;

pub(crate) use column::Column;
pub use column::PerSample;

use crate::error::{Error, Result};
use nalgebra::Vector3;
use std::sync::{Arc, OnceLock};

/// The smallest and largest length accepted for a wavelength or a patch half-size (any
/// unit): beyond them the model's (T/λ)², (σ/λ)² and 4XY/λ² overflow or underflow.
pub(crate) const LENGTH_RANGE: (f64, f64) = (1e-30, 1e30);

/// One measurement direction pair, in radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Polar angle of incidence from the surface normal, in [0, π/2).
    pub theta_i: f64,
    /// Polar angle of view from the surface normal, in [0, π/2].
    pub theta_r: f64,
    /// Azimuth of view from the plane of incidence: 0 on the forward side (the mirror
    /// direction is θr = θi, φr = 0), π back towards the source (docs/conventions.md).
    pub phi_r: f64,
}

impl Sample {
    /// A sample from angles in degrees.
    pub fn from_degrees(theta_i: f64, theta_r: f64, phi_r: f64) -> Self {
        Sample {
            theta_i: theta_i.to_radians(),
            theta_r: theta_r.to_radians(),
            phi_r: phi_r.to_radians(),
        }
    }

    /// Local angles from global unit vectors (eq. 2–8): `source` ŝ points from the surface
    /// to the light, `normal` n̂ is the surface normal, `view` k̂2 points from the surface to
    /// the viewer. At normal incidence û_x is undefined and φr is reported relative to an
    /// arbitrary perpendicular (the models do not depend on φr there). Inputs need not be
    /// normalised; zero vectors give NaN.
    pub fn from_vectors(source: &Vector3<f64>, normal: &Vector3<f64>, view: &Vector3<f64>) -> Self {
        let s = source.normalize();
        let n = normal.normalize();
        let k2 = view.normalize();
        let k1 = -s;
        let cos_i = s.dot(&n).clamp(-1.0, 1.0);
        let cos_r = k2.dot(&n).clamp(-1.0, 1.0);
        let in_plane = k1 - n * n.dot(&k1);
        let u_x = if in_plane.norm() > 1e-12 {
            in_plane.normalize()
        } else {
            // Normal incidence: any perpendicular serves.
            let trial = if n.x.abs() < 0.9 {
                Vector3::x()
            } else {
                Vector3::y()
            };
            (trial - n * n.dot(&trial)).normalize()
        };
        let u_y = n.cross(&u_x);
        let phi_r = k2.dot(&u_y).atan2(k2.dot(&u_x));
        Sample {
            theta_i: cos_i.acos(),
            theta_r: cos_r.acos(),
            phi_r,
        }
    }

    /// Check the valid domain: θi ∈ [0, 90°), θr ∈ [0, 90°], |φr| ≤ 360°, all finite.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let half_pi = std::f64::consts::FRAC_PI_2;
        if !(self.theta_i.is_finite() && self.theta_r.is_finite() && self.phi_r.is_finite()) {
            return Err("angles must be finite".into());
        }
        if !(0.0..half_pi).contains(&self.theta_i) {
            return Err(format!(
                "theta_i = {}° is outside [0°, 90°)",
                self.theta_i.to_degrees()
            ));
        }
        if !(0.0..=half_pi).contains(&self.theta_r) {
            return Err(format!(
                "theta_r = {}° is outside [0°, 90°]",
                self.theta_r.to_degrees()
            ));
        }
        if self.phi_r.abs() > 2.0 * std::f64::consts::PI + 1e-12 {
            return Err(format!(
                "phi_r = {}° is outside [-360°, 360°]",
                self.phi_r.to_degrees()
            ));
        }
        Ok(())
    }
}

/// Whether the measured value is a radiance L (eq. 28) or a BRDF (L / cos θi).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Quantity {
    /// The reflected radiance L for a unit incident irradiance (the paper's eq. 28).
    #[default]
    Radiance,
    /// The BRDF, L / cos θi, in sr⁻¹.
    Brdf,
}

/// Per-sample quantities for a batch of samples, computed once per dataset. Columns are
/// indexed by sample (`Column`: shared storage). Quantities written `/k` are the wave-vector components divided by
/// k = 2π/λ, so they depend on angles only.
#[derive(Debug, Clone)]
pub struct Geometry {
    /// θi of each sample, radians.
    pub theta_i: Column,
    /// θr of each sample, radians.
    pub theta_r: Column,
    /// φr wrapped to (−π, π].
    pub phi_r: Column,
    /// cos θi of each sample.
    pub cos_i: Column,
    /// Wavelength of each sample (unit of σ, T): one value for all, or a column.
    pub wavelength: PerSample,
    /// c = cos θi + cos θr = |v_z|/k (cos θr itself is not stored: nothing needs it).
    pub c: Column,
    /// v_xy²/k², computed without cancellation near the mirror direction.
    pub vxy2: Column,
    /// Whether the samples' values are radiances or BRDF values (the models evaluate the
    /// same quantity).
    pub quantity: Quantity,
    /// The columns of the Fresnel and shadowing factors, computed on first use
    /// ([`Geometry::factor_columns`]): a fit without factors does not hold them.
    factors: OnceLock<Arc<FactorColumns>>,
}

/// Per-sample quantities of the KBS lobe's Fresnel and shadowing factors that depend on
/// the angles only: cos θ_loc = √(h/2), and (cot θ, tan θ) of each direction
/// ([`cot_tan`]) per sample, or per distinct polar angle when the samples share them.
#[derive(Debug, Clone)]
pub struct FactorColumns {
    /// cos θ_loc = √(h/2) of each sample: the cosine of the local incidence angle on the
    /// facet that mirrors the source into the view.
    pub cos_loc: Vec<f64>,
    /// (cot θi, tan θi) and (cot θr, tan θr) of each sample; empty when `polar` holds them.
    pub incidence: Vec<(f64, f64)>,
    /// See `incidence`.
    pub view: Vec<(f64, f64)>,
    /// The distinct polar angles of incidence and view, when there are at most a quarter
    /// as many as samples (a gonioreflectometer measures a few incidence and view angles:
    /// Cornell's paints, 1439 samples, have 18): the shadowing factor, a function of each
    /// direction's polar angle, is then evaluated once per distinct angle.
    pub polar: Option<PolarAngles>,
}

/// The distinct polar angles of a geometry's directions ([`FactorColumns::polar`]).
#[derive(Debug, Clone)]
pub struct PolarAngles {
    /// (cot θ, tan θ) of each distinct polar angle ([`cot_tan`]).
    pub cot_tan: Vec<(f64, f64)>,
    /// Per sample: the index of θi in `cot_tan`.
    pub incidence: Vec<u32>,
    /// Per sample: the index of θr in `cot_tan`.
    pub view: Vec<u32>,
}

impl PolarAngles {
    /// The distinct angles of `theta_i` and `theta_r` (radians, equal by value), with their
    /// cotangents and tangents ([`cot_tan`]); None when there are more than a quarter as
    /// many as samples.
    fn of(theta_i: &[f64], theta_r: &[f64]) -> Option<PolarAngles> {
        let n = theta_i.len();
        let most = n / 4;
        let mut index: std::collections::HashMap<u64, u32> = std::collections::HashMap::new();
        let mut cot_tan = Vec::new();
        let mut id = |t: f64| -> Option<u32> {
            let next = cot_tan.len() as u32;
            let k = *index.entry(t.to_bits()).or_insert(next);
            if k == next {
                cot_tan.push(self::cot_tan(t));
            }
            (cot_tan.len() <= most).then_some(k)
        };
        let mut at_i = Vec::with_capacity(n);
        let mut at_r = Vec::with_capacity(n);
        for i in 0..n {
            at_i.push(id(theta_i[i])?);
            at_r.push(id(theta_r[i])?);
        }
        Some(PolarAngles {
            cot_tan,
            incidence: at_i,
            view: at_r,
        })
    }
}

/// (cot θ, tan θ) of a polar angle θ ∈ [0, π/2]: cot θ = cos θ/sin θ (∞ at 0; clamped at
/// 0 against rounding) and tan θ = 1/cot θ (0 at 0, ∞ where cot θ = 0), each to a few ulps.
#[inline]
pub(crate) fn cot_tan(theta: f64) -> (f64, f64) {
    let (s, c) = theta.sin_cos();
    let cot = (c / s).max(0.0);
    (cot, 1.0 / cot)
}

/// The columns of a [`Geometry`] while they are computed.
struct Columns {
    theta_i: Vec<f64>,
    theta_r: Vec<f64>,
    phi_r: Vec<f64>,
    cos_i: Vec<f64>,
    c: Vec<f64>,
    vxy2: Vec<f64>,
}

impl Columns {
    /// The columns of `samples`, computed in parts on the pool's threads.
    fn of(samples: &[Sample]) -> Self {
        use rayon::prelude::*;
        const PART: usize = 1 << 13;
        let n = samples.len();
        let v = || vec![0.0; n];
        let mut g = Columns {
            theta_i: v(),
            theta_r: v(),
            phi_r: v(),
            cos_i: v(),
            c: v(),
            vxy2: v(),
        };
        let parts = (
            samples.par_chunks(PART),
            g.theta_i.par_chunks_mut(PART),
            g.theta_r.par_chunks_mut(PART),
            g.phi_r.par_chunks_mut(PART),
            g.cos_i.par_chunks_mut(PART),
            g.c.par_chunks_mut(PART),
            g.vxy2.par_chunks_mut(PART),
        );
        parts
            .into_par_iter()
            .for_each(|(part, ti, tr, ph, ci, c, v)| {
                // A gonioreflectometer's samples repeat their polar angles from one row to
                // the next (an azimuth or view scan at fixed angles): their sines and
                // cosines are computed when an angle changes.
                let (mut inc, mut view) = (Trig::default(), Trig::default());
                for (j, s) in part.iter().enumerate() {
                    let phi = wrap_phi(s.phi_r);
                    let (sin_i, cos_i) = inc.of(s.theta_i);
                    let (sin_r, cos_r) = view.of(s.theta_r);
                    let half_sin2 = (0.5 * phi).sin().powi(2);
                    (ti[j], tr[j], ph[j], ci[j]) = (s.theta_i, s.theta_r, phi, cos_i);
                    c[j] = cos_i + cos_r;
                    // (sinθi − sinθr)² + 4 sinθi sinθr sin²(φ/2): exact zero at the mirror.
                    v[j] = (sin_i - sin_r).powi(2) + 4.0 * sin_i * sin_r * half_sin2;
                }
            });
        g
    }
}

/// The sine and cosine of the last angle asked for, computed again only when the angle
/// changes (the same bits as `sin_cos` of every angle).
#[derive(Default)]
struct Trig {
    angle: Option<f64>,
    sin_cos: (f64, f64),
}

impl Trig {
    fn of(&mut self, angle: f64) -> (f64, f64) {
        if self.angle.map(f64::to_bits) != Some(angle.to_bits()) {
            self.angle = Some(angle);
            self.sin_cos = angle.sin_cos();
        }
        self.sin_cos
    }
}

/// cos θ_loc = √(h/2), the cosine of the local incidence angle on the specular facet, of
/// a sample from the geometry column h = 1 + ŝ·k̂₂ (clamped to [0, 1] against rounding).
#[inline]
pub(crate) fn cos_local(h: f64) -> f64 {
    (0.5 * h).sqrt().min(1.0)
}

/// Wrap an angle in radians to (−π, π].
pub(crate) fn wrap_phi(phi: f64) -> f64 {
    use std::f64::consts::PI;
    if phi > -PI && phi <= PI {
        // Already wrapped: what the remainder below would return, without its cost.
        return phi;
    }
    let two_pi = 2.0 * PI;
    let mut p = phi % two_pi;
    if p <= -PI {
        p += two_pi;
    } else if p > PI {
        p -= two_pi;
    }
    p
}

impl Geometry {
    /// Prepare a batch. `wavelength` has one entry (used for every sample) or one per
    /// sample; it must be finite and positive. Samples must satisfy [`Sample::validate`].
    pub fn new(samples: &[Sample], wavelength: &[f64], quantity: Quantity) -> Result<Self> {
        if wavelength.len() != 1 && wavelength.len() != samples.len() {
            return Err(Error::Usage(format!(
                "{} wavelengths for {} samples",
                wavelength.len(),
                samples.len()
            )));
        }
        if let Some(bad) = wavelength.iter().find(|l| !(l.is_finite() && **l > 0.0)) {
            return Err(Error::Usage(format!(
                "wavelength {bad} must be finite and positive"
            )));
        }
        for (i, s) in samples.iter().enumerate() {
            s.validate()
                .map_err(|m| Error::Usage(format!("sample {}: {m}", i + 1)))?;
        }
        let n = samples.len();
        let g = Columns::of(samples);
        Ok(Geometry {
            theta_i: g.theta_i.into(),
            theta_r: g.theta_r.into(),
            phi_r: g.phi_r.into(),
            cos_i: g.cos_i.into(),
            wavelength: match wavelength {
                [first, ..] if wavelength.iter().all(|l| l.to_bits() == first.to_bits()) => {
                    PerSample::One {
                        value: *first,
                        len: n,
                    }
                }
                each => PerSample::Each(each.to_vec().into()),
            },
            c: g.c.into(),
            vxy2: g.vxy2.into(),
            quantity,
            factors: OnceLock::new(),
        })
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.theta_i.len()
    }

    /// h = |v|²/(2k²) = 1 + cos θi cos θr − sin θi sin θr cos φr of sample `i`, as
    /// (v_xy²/k² + c²)/2: a sum of two terms ≥ 0, so within a few ulps (relative) of the
    /// exact value down to h = 0 (grazing, retro-reflection), without the cancellation of
    /// the cosine form.
    #[inline]
    pub fn h(&self, i: usize) -> f64 {
        0.5 * (self.vxy2[i] + self.c[i] * self.c[i])
    }

    /// Whether the batch is empty.
    pub fn is_empty(&self) -> bool {
        self.theta_i.is_empty()
    }

    /// (v_x/k, v_y/k) = (sin θi − sin θr cos φr, −sin θr sin φr) of sample i: only the
    /// coherent (patch) term needs them, so they are computed when asked, not stored.
    #[inline]
    pub fn v_xy(&self, i: usize) -> (f64, f64) {
        let sin_i = self.theta_i[i].sin();
        let sin_r = self.theta_r[i].sin();
        let (sin_p, cos_p) = self.phi_r[i].sin_cos();
        (sin_i - sin_r * cos_p, -sin_r * sin_p)
    }

    /// The factor that turns a radiance into the measured quantity at sample i: 1 for a
    /// radiance, 1/cos θi for a BRDF.
    #[inline]
    pub fn out_factor(&self, i: usize) -> f64 {
        match self.quantity {
            Quantity::Radiance => 1.0,
            Quantity::Brdf => 1.0 / self.cos_i[i],
        }
    }

    /// g = (2πσ/λ)² (cos θi + cos θr)² of sample i (eq. 36).
    #[inline]
    pub fn g(&self, i: usize, sigma: f64) -> f64 {
        (2.0 * std::f64::consts::PI * sigma / self.wavelength[i] * self.c[i]).powi(2)
    }

    /// a = v_xy² T²/4 of sample i (eq. 37).
    #[inline]
    pub fn a(&self, i: usize, corr_len: f64) -> f64 {
        self.vxy2[i] * (2.0 * std::f64::consts::PI * corr_len / self.wavelength[i]).powi(2) * 0.25
    }

    /// The factors' columns (`FactorColumns`), computed on the first call and kept.
    pub fn factor_columns(&self) -> &FactorColumns {
        self.factors.get_or_init(|| {
            let polar = PolarAngles::of(&self.theta_i, &self.theta_r);
            let per_sample = |theta: &Column| match polar {
                Some(_) => Vec::new(),
                None => theta.iter().map(|&t| cot_tan(t)).collect(),
            };
            Arc::new(FactorColumns {
                cos_loc: (0..self.len()).map(|i| cos_local(self.h(i))).collect(),
                incidence: per_sample(&self.theta_i),
                view: per_sample(&self.theta_r),
                polar,
            })
        })
    }

    /// The samples `range`, sharing this geometry's storage (no copy).
    pub fn slice(&self, range: std::ops::Range<usize>) -> Geometry {
        let s = |c: &Column| c.slice(range.clone());
        Geometry {
            theta_i: s(&self.theta_i),
            theta_r: s(&self.theta_r),
            phi_r: s(&self.phi_r),
            cos_i: s(&self.cos_i),
            wavelength: self.wavelength.slice(range.clone()),
            c: s(&self.c),
            vxy2: s(&self.vxy2),
            quantity: self.quantity,
            factors: OnceLock::new(),
        }
    }

    /// The sub-batch of the given sample indices (used for per-channel fits); a contiguous
    /// ascending run of indices is a [`Geometry::slice`] (no copy).
    pub fn subset(&self, idx: &[usize]) -> Geometry {
        if let Some(&first) = idx.first() {
            if idx.iter().enumerate().all(|(k, &i)| i == first + k) {
                return self.slice(first..first + idx.len());
            }
        }
        let pick = |v: &Column| idx.iter().map(|&i| v[i]).collect::<Column>();
        Geometry {
            theta_i: pick(&self.theta_i),
            theta_r: pick(&self.theta_r),
            phi_r: pick(&self.phi_r),
            cos_i: pick(&self.cos_i),
            wavelength: self.wavelength.subset(idx),
            c: pick(&self.c),
            vxy2: pick(&self.vxy2),
            quantity: self.quantity,
            factors: OnceLock::new(),
        }
    }
}

/// Fewest samples on the flank of a Gaussian lobe (between e^{-8} and e^{-1/8} of its
/// peak) for its width w to count as resolved by the angular sampling.
pub(crate) const MIN_FLANK_SAMPLES: usize = 3;

/// The angular sampling's resolution: which Gaussian lobe widths the samples measure, and
/// the median roughness g the samples see.
impl Geometry {
    /// The offset √q = √((θr − θi)² + φr²/4) (rad) of sample i from the mirror direction, in
    /// the metric of the Gaussian lobe's exponent (eq. 34: the lobe is exp(−½ q/w²)).
    fn lobe_offset(&self, i: usize) -> f64 {
        ((self.theta_r[i] - self.theta_i[i]).powi(2) + 0.25 * self.phi_r[i].powi(2)).sqrt()
    }

    /// How many samples lie on the flank of a Gaussian lobe of width `w` (rad): between e^{-8}
    /// and e^{-1/8} of its peak, i.e. at an offset √q between w/2 and 4w.
    pub fn flank_samples(&self, w: f64) -> usize {
        (0..self.len())
            .filter(|&i| (0.5 * w..=4.0 * w).contains(&self.lobe_offset(i)))
            .count()
    }

    /// The narrowest Gaussian lobe width (rad) the angular sampling resolves: the smallest w
    /// with at least `MIN_FLANK_SAMPLES` samples on its flank ([`Self::flank_samples`]).
    /// Exact: for the offsets d sorted ascending, three of them fit in [w/2, 4w] first for
    /// some three consecutive ones, at w = d_{j+2}/4 when d_{j+2} ≤ 8 d_j. None when no w
    /// resolves (fewer than three samples off the mirror direction). O(n log n).
    pub fn resolved_width(&self) -> Option<f64> {
        let mut d: Vec<f64> = (0..self.len())
            .map(|i| self.lobe_offset(i))
            .filter(|&d| d > 0.0 && d.is_finite())
            .collect();
        d.sort_by(f64::total_cmp);
        let k = MIN_FLANK_SAMPLES - 1;
        d.windows(MIN_FLANK_SAMPLES)
            .filter(|t| t[k] <= 8.0 * t[0])
            .map(|t| 0.25 * t[k])
            .reduce(f64::min)
    }

    /// The lower bound on a Gaussian lobe's width w in a fit: half of
    /// [`Self::resolved_width`]. A solver step to a narrower lobe is rejected (as a step
    /// outside the models' domain), so a lobe the sampling does not resolve ends at this
    /// bound, where fewer than `MIN_FLANK_SAMPLES` samples lie on its flank and the fit's
    /// acceptance says so, instead of running w to 1e-100. None (no bound) when no width is
    /// resolved at all.
    pub fn width_floor(&self) -> Option<f64> {
        self.resolved_width().map(|w| 0.5 * w)
    }

    /// Median of g ([`Self::g`]) over the samples at σ = `sigma` (NaN without samples).
    pub fn median_g(&self, sigma: f64) -> f64 {
        let g: Vec<f64> = (0..self.len()).map(|i| self.g(i, sigma)).collect();
        median(&g)
    }
}

/// Median of the values that are not NaN: the middle one, or the mean of the two middle
/// ones for an even count; NaN when there are none. Linear time.
pub(crate) fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| !x.is_nan()).collect();
    let n = s.len();
    if n == 0 {
        return f64::NAN;
    }
    let (lower, &mut upper, _) = s.select_nth_unstable_by(n / 2, f64::total_cmp);
    if n % 2 == 1 {
        upper
    } else {
        0.5 * (lower.iter().copied().fold(f64::NEG_INFINITY, f64::max) + upper)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_empty_and_nan() {
        assert!(median(&[]).is_nan());
        assert!(median(&[f64::NAN]).is_nan());
        assert_eq!(median(&[3.0]), 3.0);
        assert_eq!(median(&[4.0, 1.0]), 2.5);
        assert_eq!(median(&[5.0, -1.0, f64::NAN, 2.0, 2.0, 9.0]), 2.0);
        let v: Vec<f64> = (0..1001)
            .map(|i| ((i * 7919) % 1001) as f64 * 0.5)
            .collect();
        assert_eq!(median(&v), 250.0);
        assert_eq!(median(&v[..1000]), {
            let mut s = v[..1000].to_vec();
            s.sort_by(f64::total_cmp);
            0.5 * (s[499] + s[500])
        });
    }

    #[test]
    fn vectors_round_trip_to_angles() {
        // Source in the xz-plane at 30° on the −x side... ŝ points to the light.
        let ti = 30f64.to_radians();
        let s = Vector3::new(-ti.sin(), 0.0, ti.cos());
        let n = Vector3::z();
        // Mirror direction: k̂2 = reflection of k̂1 = −ŝ about n.
        let mirror = Vector3::new(ti.sin(), 0.0, ti.cos());
        let smp = Sample::from_vectors(&s, &n, &mirror);
        assert!((smp.theta_i - ti).abs() < 1e-14);
        assert!((smp.theta_r - ti).abs() < 1e-14);
        assert!(smp.phi_r.abs() < 1e-14, "mirror is at phi_r = 0");
        // Backscatter: view = source, phi_r = ±180°.
        let back = Sample::from_vectors(&s, &n, &s);
        assert!((back.phi_r.abs() - std::f64::consts::PI).abs() < 1e-14);
        // Normal incidence is defined.
        let ni = Sample::from_vectors(&n, &n, &mirror);
        assert!(ni.theta_i.abs() < 1e-7 && ni.phi_r.is_finite());
    }

    #[test]
    fn stable_forms_match_the_definitions() {
        let samples: Vec<Sample> = [(10.0, 20.0, 30.0), (45.0, 45.0, 0.0), (80.0, 5.0, 170.0)]
            .iter()
            .map(|&(a, b, c)| Sample::from_degrees(a, b, c))
            .collect();
        let g = Geometry::new(&samples, &[1.0], Quantity::Radiance).unwrap();
        for (i, s) in samples.iter().enumerate() {
            let (si, ci) = s.theta_i.sin_cos();
            let (sr, cr) = s.theta_r.sin_cos();
            let h = 1.0 + ci * cr - si * sr * s.phi_r.cos();
            assert!((g.h(i) - h).abs() < 1e-14);
            let (vx, vy) = g.v_xy(i);
            let vxy2 = vx.powi(2) + vy.powi(2);
            assert!((g.vxy2[i] - vxy2).abs() < 1e-14);
        }
        assert_eq!(g.vxy2[1], 0.0, "exact zero at the mirror");
    }

    #[test]
    fn wrapped_azimuths_are_returned_as_given_and_others_wrapped() {
        use std::f64::consts::PI;
        for phi in [0.0, -0.0, 1.0, -3.0, PI, -PI + 1e-15, 3.0] {
            assert_eq!(wrap_phi(phi).to_bits(), phi.to_bits());
        }
        // −π and values beyond ±π move by 2π into (−π, π].
        assert_eq!(wrap_phi(-PI), PI);
        assert!((wrap_phi(1.5 * PI) + 0.5 * PI).abs() < 1e-15);
        assert!((wrap_phi(-1.5 * PI) - 0.5 * PI).abs() < 1e-15);
        assert!((wrap_phi(7.0 * PI + 0.25) - (-PI + 0.25)).abs() < 1e-14);
        assert!(wrap_phi(f64::NAN).is_nan());
    }

    #[test]
    fn repeated_polar_angles_give_the_columns_of_each_sample_alone() {
        // Runs of equal θi and θr (an azimuth scan), changes of either, a return to an
        // earlier angle, and grazing angles where h is near 0.
        let deg = [
            (30.0, 10.0, 0.0),
            (30.0, 10.0, 45.0),
            (30.0, 10.0, 90.0),
            (30.0, 60.0, 90.0),
            (70.0, 60.0, 180.0),
            (30.0, 10.0, -30.0),
            (89.9, 89.9, 179.9),
            (89.9, 89.9, 180.0),
            (89.99, 89.99, 0.0),
        ];
        let samples: Vec<Sample> = deg
            .iter()
            .map(|&(a, b, c)| Sample::from_degrees(a, b, c))
            .collect();
        let g = Geometry::new(&samples, &[1.0], Quantity::Radiance).unwrap();
        for (i, s) in samples.iter().enumerate() {
            let one = Geometry::new(&[*s], &[1.0], Quantity::Radiance).unwrap();
            let bits = |v: f64| v.to_bits();
            assert_eq!(bits(g.cos_i[i]), bits(one.cos_i[0]), "sample {i}");
            assert_eq!(bits(g.c[i]), bits(one.c[0]), "sample {i}");
            assert_eq!(bits(g.vxy2[i]), bits(one.vxy2[0]), "sample {i}");
            assert_eq!(bits(g.h(i)), bits(one.h(0)), "sample {i}");
            // h = (v_xy² + c²)/2 against the cosine form, where that form does not cancel.
            let (si, ci) = s.theta_i.sin_cos();
            let (sr, cr) = s.theta_r.sin_cos();
            let h = 1.0 + ci * cr - si * sr * s.phi_r.cos();
            if h > 1e-3 {
                assert!(
                    (g.h(i) - h).abs() <= 1e-12 * h,
                    "sample {i}: {} {h}",
                    g.h(i)
                );
            }
            // Against the other form without cancellation, 2 cos²((θi+θr)/2) + 2 sin θi sin θr
            // sin²(φ/2) (both terms ≥ 0): the two agree to a few ulps wherever h is.
            let half = (0.5 * (s.theta_i + s.theta_r)).cos();
            let stable = 2.0 * half * half + 2.0 * si * sr * (0.5 * s.phi_r).sin().powi(2);
            let ulps = (g.h(i) - stable).abs() / (f64::EPSILON * stable);
            assert!(
                ulps <= 8.0,
                "sample {i}: h {} against {stable}: {ulps} ulps",
                g.h(i)
            );
        }
    }

    #[test]
    fn slices_share_storage_and_equal_copied_subsets() {
        let samples: Vec<Sample> = (0..7)
            .map(|k| Sample::from_degrees(10.0 + k as f64, 20.0, 15.0 * k as f64))
            .collect();
        let g = Geometry::new(&samples, &[0.5], Quantity::Brdf).unwrap();
        let part = g.slice(2..5);
        assert_eq!(part.len(), 3);
        assert!(std::ptr::eq(&part.vxy2[0], &g.vxy2[2]), "no copy");
        let picked = g.subset(&[2, 3, 4]);
        assert!(
            std::ptr::eq(&picked.c[0], &g.c[2]),
            "a contiguous subset is a slice"
        );
        let copied = g.subset(&[4, 2]);
        assert_eq!(*copied.vxy2, [g.vxy2[4], g.vxy2[2]]);
        assert_eq!(part.slice(1..3).theta_i[1], g.theta_i[4]);
        let direct = Geometry::new(&samples[2..5], &[0.5], Quantity::Brdf).unwrap();
        assert!(part.c == direct.c && (0..3).all(|i| part.out_factor(i) == direct.out_factor(i)));
    }

    #[test]
    fn one_wavelength_or_weight_is_stored_once_and_read_as_given() {
        let samples: Vec<Sample> = (0..5)
            .map(|k| Sample::from_degrees(10.0 + k as f64, 20.0, 30.0))
            .collect();
        let one = Geometry::new(&samples, &[0.5; 5], Quantity::Radiance).unwrap();
        assert_eq!(one.wavelength, PerSample::One { value: 0.5, len: 5 });
        let each = [0.5, 0.6, 0.5, 0.7, 0.5];
        let g = Geometry::new(&samples, &each, Quantity::Radiance).unwrap();
        assert_eq!(g.wavelength.iter().collect::<Vec<_>>(), each);
        assert_eq!((g.wavelength.median(), one.wavelength.median()), (0.5, 0.5));
        assert_eq!(g.slice(1..4).wavelength[2], 0.7);
        assert_eq!(
            g.subset(&[3, 1]).wavelength.iter().collect::<Vec<_>>(),
            [0.7, 0.6]
        );
        assert_eq!(
            one.subset(&[4, 0]).wavelength,
            PerSample::One { value: 0.5, len: 2 }
        );
        // Bits decide: −0 and 0 are not one value.
        let w: PerSample = vec![0.0, -0.0].into();
        assert!(matches!(w, PerSample::Each(_)) && w[1].is_sign_negative());
        let w: PerSample = vec![4.0; 3].into();
        assert_eq!(w.sqrt(), PerSample::One { value: 2.0, len: 3 });
    }

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
        let w = geo.resolved_width().unwrap();
        assert!((w - 0.075).abs() < 1e-15, "{w}");
        assert_eq!(geo.flank_samples(w), 3);
        assert_eq!(geo.flank_samples(w * (1.0 - 1e-12)), 2);
        assert_eq!(geo.width_floor(), Some(0.5 * w));
        // Offsets 0.01, 0.1, 1 rad: no three within a factor 8 of each other, so none.
        assert_eq!(in_plane(&[0.01, 0.1, 1.0]).resolved_width(), None);
    }
}
