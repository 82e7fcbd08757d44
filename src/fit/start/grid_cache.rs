//! The model side of the starting-value grid, computed once per angular layout.
//!
//! At a grid point (σ, T or w, with the linear amplitudes set to 1) the grid needs the
//! model's values on the grid subsample split into the part that does not come from the
//! linear parameters and ∂f/∂p_k of each linear parameter k ([`PointBasis`]). None of this
//! depends on the measured values, weights or residual kind: it is a function of the
//! subsample's geometry, the model and its options, and the grid's axes. Many small fits of
//! one layout (a texel batch: thousands of scans at the same angles) therefore share it,
//! and [`basis`] keeps the last few layouts' grids ([`CACHE_ENTRIES`]), keyed by the exact
//! bits of everything they depend on (no hash collisions: the key is compared in full).
//! A fit whose layout is new computes the same basis, so a cache hit changes nothing but
//! the time (the texel batch's 2,000 fits give the same bits with and without it).

use crate::fit::problem::FitProblem;
use crate::geometry::Geometry;
use std::sync::{Arc, Mutex};

/// Grids kept (the most recently used first).
pub(crate) const CACHE_ENTRIES: usize = 8;

/// The model at one grid point: f = rest + Σ_k p_k · column_k over the linear parameters.
#[derive(Debug)]
pub(crate) struct PointBasis {
    /// The part of f that does not come from the linear parameters (0 for every goniofit
    /// model, kept for generality).
    pub rest: Vec<f64>,
    /// ∂f/∂p_k of each linear parameter, column-major (samples × linear parameters).
    pub columns: Vec<f64>,
}

/// The model side of a whole grid: one entry per flat grid index (None where the model is
/// not finite).
#[derive(Debug)]
pub(crate) struct GridBasis {
    /// The basis of each grid point, by flat index; None where the model is not finite.
    pub points: Vec<Option<PointBasis>>,
}

/// What a grid's basis depends on, as exact bits: the model name and options, the problem
/// layout, the samples' geometry and channels, the grid's axes and the given values.
#[derive(Debug, PartialEq)]
pub(crate) struct Key(Vec<u64>);

impl Key {
    /// The key of a grid over `axes` for a model (by name) on samples `geo` with channel
    /// indices `channel`; [`Key::push`] adds what else the grid's points depend on (given
    /// values, parameter indices, model options).
    pub(crate) fn new(
        model_name: &str,
        geo: &Geometry,
        channel: &crate::fit::problem::Channels,
        axes: &[Vec<f64>],
    ) -> Self {
        let mut k: Vec<u64> = Vec::with_capacity(16 + 9 * geo.len());
        k.extend(model_name.bytes().map(u64::from));
        k.push(u64::MAX);
        k.push(geo.quantity as u64);
        for col in [
            &geo.theta_i,
            &geo.theta_r,
            &geo.phi_r,
            &geo.cos_i,
            &geo.c,
            &geo.vxy2,
        ] {
            k.push(col.len() as u64);
            k.extend(col.iter().map(|v| v.to_bits()));
        }
        k.push(geo.wavelength.len() as u64);
        k.extend(geo.wavelength.iter().map(f64::to_bits));
        k.extend(channel.iter().map(|c| c as u64));
        for axis in axes {
            k.push(axis.len() as u64);
            k.extend(axis.iter().map(|v| v.to_bits()));
        }
        Key(k)
    }

    /// Append more words (options, indices, given values) to the key.
    pub(crate) fn push(&mut self, words: impl IntoIterator<Item = u64>) {
        self.0.push(u64::MAX - 1);
        self.0.extend(words);
    }
}

type Cache = Vec<(Arc<Key>, Arc<GridBasis>)>;

fn cache() -> &'static Mutex<Cache> {
    static CACHE: std::sync::OnceLock<Mutex<Cache>> = std::sync::OnceLock::new();
    CACHE.get_or_init(|| Mutex::new(Vec::new()))
}

/// The grid basis for `key`: from the cache, or computed by `compute` and cached. Two
/// threads asking for a new key at once may both compute it (the results are identical).
/// `compute` returns None when it was stopped before every point was computed: nothing is
/// cached then (a later fit of the layout computes the whole grid), and None is returned.
pub(crate) fn basis(
    key: Key,
    compute: impl FnOnce() -> Option<GridBasis>,
) -> Option<Arc<GridBasis>> {
    if let Ok(mut c) = cache().lock() {
        if let Some(pos) = c.iter().position(|(k, _)| **k == key) {
            let hit = c.remove(pos);
            let b = hit.1.clone();
            c.insert(0, hit);
            return Some(b);
        }
    }
    let b = Arc::new(compute()?);
    if let Ok(mut c) = cache().lock() {
        c.insert(0, (Arc::new(key), b.clone()));
        c.truncate(CACHE_ENTRIES);
    }
    Some(b)
}

/// The basis at full parameters `p` (the linear parameters' values are ignored: they are
/// set to 1), from one model pass with the Jacobian; None when the model is not finite.
/// A rest within rounding of the model value (|rest| ≤ [`REST_ROUNDING`] · |f|) is exactly
/// 0: it is the rounding of f − Σ columns, on the scale of the model at unit amplitudes,
/// and the amplitude solve would otherwise fit data in a small unit (10⁻³⁰ of these
/// values) to that rounding instead of to the data.
pub(crate) fn point_basis(problem: &FitProblem, p: &[f64], linear: &[usize]) -> Option<PointBasis> {
    let mut p = p.to_vec();
    for &k in linear {
        p[k] = 1.0;
    }
    let (f, jac) = problem.model_values(&p, !linear.is_empty());
    let n = f.len();
    let mut rest = f.clone();
    let mut columns = Vec::with_capacity(n * linear.len());
    if let Some(jac) = jac {
        for &k in linear {
            let col = jac.column(k);
            for (r, j) in rest.iter_mut().zip(col.iter()) {
                *r -= j;
            }
            columns.extend(col.iter());
        }
    }
    for (r, fi) in rest.iter_mut().zip(&f) {
        if r.abs() <= REST_ROUNDING * fi.abs() {
            *r = 0.0;
        }
    }
    (rest.iter().chain(&columns).all(|v| v.is_finite())).then_some(PointBasis { rest, columns })
}

/// Relative size below which the rest of a [`PointBasis`] is rounding (a few ulps of the
/// model value per amplitude).
pub(crate) const REST_ROUNDING: f64 = 1e-12;
