//! The least-squares problem of a reflectance fit: a model, a dataset split into blocks
//! (per channel, and in chunks for parallel evaluation), residuals of a chosen kind, and
//! the mapping between the model's parameters and the solver's free variables.
//!
//! The parameters and their solver variables are [`layout`]'s (re-exported here).
//! Residuals are weighted,
//! r̃ᵢ = √wᵢ rᵢ, so the solver's cost ½‖r̃‖² is the fit cost ½ Σ wᵢ rᵢ².
//!
//! With a robust loss ([`loss`]) the solver sees the cost residuals, the corrected
//! Jacobian and the step residuals of [`loss::Loss::correct`] instead.
//!
//! Beside the problem: the channel index of every sample ([`channels`]), the weights from
//! the data's uncertainty ([`weights`]), the active set of amplitudes at their bound 0
//! (`bounds.rs`) and the edges of the physical domain a point can run to (`edges.rs`).

pub(crate) mod channels;
pub(crate) mod layout;
pub(crate) mod loss;
pub(crate) mod weights;

pub(super) mod bounds;
mod domain;
pub(super) mod edges;
mod reduced;

use crate::error::{Error, Result};
use crate::geometry::{Column, Geometry, PerSample};
use crate::model::{Mode, Model};
pub use channels::Channels;
use domain::width_floor;
pub(crate) use domain::G_FIT_MAX;
use goniofit_lm::{LeastSquaresProblem, Stop};
pub(crate) use layout::{FitParam, ParamLayout, Transform, LINEAR};
use loss::Loss;
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

/// Samples per evaluation block: large enough to amortise scheduling, small enough to
/// spread a 10k-sample fit over both cores.
const BLOCK: usize = 1024;
/// Blocks evaluated in parallel before their results are gathered (64k samples): enough
/// work for every thread, few enough that the per-block results stay small.
const PARALLEL_GROUP: usize = 64;

/// What a residual measures.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ResidualKind {
    /// rᵢ = fᵢ − yᵢ.
    #[default]
    Absolute,
    /// rᵢ = (fᵢ − yᵢ)/max(|yᵢ|, floor).
    Relative,
    /// rᵢ = ln max(fᵢ, floor) − ln max(yᵢ, floor).
    Log,
}

/// The data of a fit.
#[derive(Debug, Clone)]
pub struct FitInput {
    /// The samples' directions (radians) and wavelengths, and the measured quantity.
    pub geo: Geometry,
    /// Measured values (shared storage: a problem built on them refers to them).
    pub y: Column,
    /// Weights wᵢ > 0 (one value when they are all the same).
    pub weight: PerSample,
    /// Channel index per sample into `channel_names` (a single channel stores none).
    pub channel: Channels,
    /// Channel names; one entry (possibly empty) for a single channel.
    pub channel_names: Vec<String>,
}

impl FitInput {
    /// The samples at the given indices.
    pub fn subset(&self, idx: &[usize]) -> FitInput {
        FitInput {
            geo: self.geo.subset(idx),
            y: idx.iter().map(|&i| self.y[i]).collect(),
            weight: self.weight.subset(idx),
            channel: self.channel.subset(idx),
            channel_names: self.channel_names.clone(),
        }
    }
}

/// A contiguous block of samples of one channel, with its prepared geometry.
#[derive(Debug, Clone)]
struct Block {
    geo: Geometry,
    /// Global sample indices.
    idx: Rows,
    channel: usize,
    /// The largest c/λ and v_xy²/λ² of the block's samples: g and a of every sample are at
    /// most (2πσ c/λ)² and (2πT)² v_xy²/(4λ²) of these.
    reach: (f64, f64),
}

impl Block {
    fn new(geo: Geometry, idx: Rows, channel: usize) -> Block {
        let reach = (0..geo.len()).fold((0.0f64, 0.0f64), |(g, a), i| {
            let l = geo.wavelength[i];
            (g.max((geo.c[i] / l).abs()), a.max(geo.vxy2[i] / (l * l)))
        });
        Block {
            geo,
            idx,
            channel,
            reach,
        }
    }
}

/// The global indices of a block's samples: a run of consecutive samples (a one-channel
/// fit), or a list.
#[derive(Debug, Clone)]
enum Rows {
    Run(std::ops::Range<usize>),
    List(Vec<usize>),
}

impl Rows {
    fn len(&self) -> usize {
        match self {
            Rows::Run(r) => r.len(),
            Rows::List(l) => l.len(),
        }
    }

    /// The global indices in block order.
    fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        let (run, list) = match self {
            Rows::Run(r) => (Some(r.clone()), None),
            Rows::List(l) => (None, Some(l.iter().copied())),
        };
        run.into_iter().flatten().chain(list.into_iter().flatten())
    }
}

/// The fit's least-squares problem.
pub(crate) struct FitProblem<'a> {
    /// The model evaluated at every sample.
    pub model: &'a dyn Model,
    /// The map from the solver's free variables to the model's parameters per channel.
    pub layout: ParamLayout,
    blocks: Vec<Block>,
    /// The input's measured values (shared, not a second copy of a big file's).
    y: Column,
    /// √wᵢ (one value when the weights are all the same: a fit without weights holds no
    /// per-sample weight).
    sqrt_w: PerSample,
    kind: ResidualKind,
    /// Floor for relative and log residuals (in the unit of y).
    pub floor: f64,
    n: usize,
    /// The robust loss on the weighted residuals (linear: plain least squares).
    loss: Loss,
    /// The Gaussian lobe's width: (model parameter index of `w`, its lower bound from the
    /// angular sampling, [`Geometry::width_floor`]); None without a lobe.
    w_floor: Option<(usize, f64)>,
    /// The Jacobian (and with a robust loss the step residuals) computed alongside the last
    /// residual evaluation: the models produce derivatives at little extra cost, and LM asks
    /// for the Jacobian at the point it just accepted, so one model pass serves both.
    cache: std::sync::Mutex<Option<Cached>>,
    /// Residuals the solver is done with ([`FitProblem::keep_spare`], at most
    /// [`reduced::SPARES`]), whose storage the next reduced evaluations fill rather than
    /// new memory.
    spare: std::sync::Mutex<Vec<DVector<f64>>>,
}

/// What one residual evaluation leaves for the solver's next requests at the same point.
struct Cached {
    x: DVector<f64>,
    jac: Option<DMatrix<f64>>,
    step: Option<DVector<f64>>,
    /// The Jacobian reduced block by block, in place of `jac` for a problem that
    /// [`FitProblem::reduces`].
    reduced: Option<goniofit_lm::Reduced>,
}

/// Weighted residuals at a point, as the solver sees them.
pub(crate) struct Evaluated {
    /// The weighted residuals √wᵢ rᵢ, or under a robust loss the cost residuals (½‖·‖² is
    /// the cost).
    pub residuals: DVector<f64>,
    /// Their Jacobian with respect to the solver variables (robust loss: corrected, J̃).
    pub jacobian: DMatrix<f64>,
    /// The step residuals f̃ under a robust loss (None for linear).
    pub step: Option<DVector<f64>>,
}

impl<'a> FitProblem<'a> {
    /// Build the problem. `floor` is used by relative and log residuals.
    pub(crate) fn new(
        model: &'a dyn Model,
        layout: ParamLayout,
        input: &FitInput,
        kind: ResidualKind,
        floor: f64,
    ) -> Result<Self> {
        let FitInput {
            geo,
            y,
            weight,
            channel,
            ..
        } = input;
        let n = geo.len();
        if y.len() != n || weight.len() != n || channel.len() != n {
            return Err(Error::Numerical("inconsistent fit data lengths".into()));
        }
        let n_ch = layout.index.len();
        let blocks = if channel.is_single() {
            // One channel: blocks are runs of consecutive samples, their geometry a view of
            // the input's (nothing per sample is copied).
            (0..n)
                .step_by(BLOCK)
                .map(|first| {
                    let run = first..(first + BLOCK).min(n);
                    Block::new(geo.slice(run.clone()), Rows::Run(run), 0)
                })
                .collect()
        } else {
            let mut blocks = Vec::new();
            for c in 0..n_ch {
                let idx: Vec<usize> = (0..n).filter(|&i| channel[i] == c).collect();
                for chunk in idx.chunks(BLOCK) {
                    blocks.push(Block::new(geo.subset(chunk), Rows::List(chunk.to_vec()), c));
                }
            }
            blocks
        };
        Ok(FitProblem {
            model,
            layout,
            blocks,
            y: y.clone(),
            sqrt_w: weight.sqrt(),
            kind,
            floor,
            n,
            loss: Loss::default(),
            w_floor: width_floor(model, geo),
            cache: std::sync::Mutex::new(None),
            spare: std::sync::Mutex::new(Vec::new()),
        })
    }

    /// The same problem under a robust loss on its weighted residuals.
    pub(crate) fn with_loss(mut self, loss: Loss) -> Self {
        self.loss = loss;
        self
    }

    /// The robust loss (linear: plain least squares).
    pub(crate) fn loss(&self) -> Loss {
        self.loss
    }

    /// The fit cost ½ Σ C² ρ(wᵢ rᵢ²/C²) of unweighted residuals `r` (½ Σ wᵢ rᵢ² for linear).
    pub(crate) fn cost_of(&self, r: &[f64]) -> f64 {
        0.5 * r
            .iter()
            .zip(self.sqrt_w.iter())
            .map(|(r, s)| self.loss.term(r * s))
            .sum::<f64>()
    }

    /// Number of samples.
    pub(crate) fn len(&self) -> usize {
        self.n
    }

    /// Every block's model values and, on request, its model Jacobian (column-major,
    /// block rows × model parameters), evaluated in parallel; `finish(block, f, jac)` runs
    /// on each block's result in the same task, then `sink(block, f, jac)` on the calling
    /// thread, block by block in order. Blocks are evaluated [`PARALLEL_GROUP`] at a time,
    /// so the per-block results held at once stay bounded (not a second copy of a big
    /// fit's residuals and Jacobian).
    ///
    /// With `stop`, a block that starts after the stop was requested is not evaluated: its
    /// values (and Jacobian) are NaN, so the evaluation ends within one block's time
    /// ([`BLOCK`] samples) of the request and the solver rejects the point. Returns
    /// whether every block was evaluated (false: the stop cut the evaluation).
    fn eval_blocks<T: Send>(
        &self,
        p: &[f64],
        want_jac: bool,
        stop: Option<&Stop>,
        finish: impl Fn(&Block, &mut [f64], &mut [f64]) -> T + Sync,
        mut sink: impl FnMut(&Block, &[f64], &[f64], T),
    ) -> bool {
        let n_spec = self.model.params().len();
        let cut = std::sync::atomic::AtomicBool::new(false);
        let run = |b: &Block| {
            let m = b.geo.len();
            let jac_len = if want_jac { m * n_spec } else { 0 };
            let (mut f, mut jac) = if stop.is_some_and(Stop::is_requested) {
                cut.store(true, std::sync::atomic::Ordering::Relaxed);
                (vec![f64::NAN; m], vec![f64::NAN; jac_len])
            } else {
                let mp = self.layout.model_params(p, b.channel);
                let mut f = vec![0.0; m];
                let mut jac = vec![0.0; jac_len];
                self.model
                    .eval(&b.geo, &mp, &mut f, want_jac.then_some(&mut jac[..]));
                (f, jac)
            };
            let t = finish(b, &mut f, &mut jac);
            (f, jac, t)
        };
        // One block (a small fit) runs on the calling thread: no task to schedule.
        if let [b] = &self.blocks[..] {
            let (f, jac, t) = run(b);
            sink(b, &f, &jac, t);
        } else {
            for group in self.blocks.chunks(PARALLEL_GROUP) {
                let parts: Vec<_> = group.par_iter().map(run).collect();
                for (b, (f, jac, t)) in group.iter().zip(parts) {
                    sink(b, &f, &jac, t);
                }
            }
        }
        !cut.into_inner()
    }

    /// Model values at full parameters `p`, and on request ∂f/∂p (n × full params).
    pub(crate) fn model_values(
        &self,
        p: &[f64],
        want_jac: bool,
    ) -> (Vec<f64>, Option<DMatrix<f64>>) {
        let n_spec = self.model.params().len();
        let mut f = vec![0.0; self.n];
        let mut jac = want_jac.then(|| DMatrix::zeros(self.n, self.layout.len()));
        self.eval_blocks(
            p,
            want_jac,
            None,
            |_, _, _| {},
            |b, out, bj, ()| {
                let m = b.idx.len();
                for (r, i) in b.idx.iter().enumerate() {
                    f[i] = out[r];
                }
                if let Some(j) = jac.as_mut() {
                    for s in 0..n_spec {
                        let col = self.layout.index[b.channel][s];
                        for (r, i) in b.idx.iter().enumerate() {
                            j[(i, col)] = bj[s * m + r];
                        }
                    }
                }
            },
        );
        (f, jac)
    }

    /// Model values and each sample's evaluation mode at full parameters `p` (one
    /// evaluation), or None when `stop` was requested before every block was evaluated (a
    /// block that starts after the request is skipped).
    pub(crate) fn values_modes_until(
        &self,
        p: &[f64],
        stop: Option<&Stop>,
    ) -> Option<(Vec<f64>, Vec<Mode>)> {
        let run = |b: &Block| {
            if stop.is_some_and(Stop::is_requested) {
                return None;
            }
            let mut f = vec![0.0; b.geo.len()];
            let mp = self.layout.model_params(p, b.channel);
            let modes = self.model.eval_modes(&b.geo, &mp, &mut f);
            Some((f, modes))
        };
        // One block (a small fit) runs on the calling thread, as in `eval_blocks`.
        let parts: Vec<Option<(Vec<f64>, Vec<Mode>)>> = match &self.blocks[..] {
            [b] => vec![run(b)],
            blocks => blocks.par_iter().map(run).collect(),
        };
        let mut values = vec![0.0; self.n];
        let mut modes = vec![Mode::Closed; self.n];
        for (b, part) in self.blocks.iter().zip(parts) {
            let (f, m) = part?;
            for (r, i) in b.idx.iter().enumerate() {
                values[i] = f[r];
                modes[i] = m[r];
            }
        }
        Some((values, modes))
    }

    /// Unweighted residuals rᵢ of the chosen kind for model values f.
    pub(crate) fn raw_residuals(&self, f: &[f64]) -> Vec<f64> {
        f.iter()
            .enumerate()
            .map(|(i, &fi)| self.residual(i, fi))
            .collect()
    }

    /// The unweighted residual of sample i for model value fi.
    #[inline]
    pub(super) fn residual(&self, i: usize, fi: f64) -> f64 {
        let yi = self.y[i];
        match self.kind {
            ResidualKind::Absolute => fi - yi,
            ResidualKind::Relative => (fi - yi) / yi.abs().max(self.floor),
            ResidualKind::Log => fi.max(self.floor).ln() - yi.max(self.floor).ln(),
        }
    }

    /// ∂rᵢ/∂fᵢ for the chosen residual kind.
    #[inline]
    fn dr_df(&self, i: usize, fi: f64) -> f64 {
        match self.kind {
            ResidualKind::Absolute => 1.0,
            ResidualKind::Relative => 1.0 / self.y[i].abs().max(self.floor),
            ResidualKind::Log => {
                if fi > self.floor {
                    1.0 / fi
                } else {
                    0.0
                }
            }
        }
    }

    /// Weighted residuals at full parameters.
    pub(crate) fn weighted_residuals(&self, p: &[f64]) -> DVector<f64> {
        let (f, _) = self.model_values(p, false);
        let r = self.raw_residuals(&f);
        DVector::from_iterator(self.n, r.iter().zip(self.sqrt_w.iter()).map(|(r, s)| r * s))
    }

    /// Measured values.
    pub(crate) fn y(&self) -> &[f64] {
        &self.y
    }

    /// √wᵢ.
    pub(crate) fn sqrt_weight(&self) -> &PerSample {
        &self.sqrt_w
    }

    /// Residual kind.
    pub(crate) fn kind(&self) -> ResidualKind {
        self.kind
    }
}

impl FitProblem<'_> {
    /// Weighted residuals and their Jacobian with respect to the solver variables x, in one
    /// model pass per block (blocks in parallel): r̃ᵢ = √wᵢ rᵢ and
    /// ∂r̃ᵢ/∂x_j = √wᵢ (∂rᵢ/∂fᵢ) (∂fᵢ/∂p_k) (dp_k/dx_j) for the free parameter k of column j.
    /// Under a robust loss: the cost residuals and the corrected Jacobian (see
    /// [`Self::evaluate`] for the step residuals that go with them).
    pub(crate) fn residuals_and_jacobian(&self, x: &DVector<f64>) -> (DVector<f64>, DMatrix<f64>) {
        let e = self.evaluate(x, None);
        (e.residuals, e.jacobian)
    }

    /// Residuals, Jacobian and (robust loss) step residuals at x, cut short once `stop` is
    /// requested (the rows of blocks not evaluated are NaN).
    pub(crate) fn evaluate(&self, x: &DVector<f64>, stop: Option<&Stop>) -> Evaluated {
        let (mut r, mut j) = self.weighted_and_jacobian(x, stop);
        let step = self.loss.correct_in_place(&mut r, &mut j);
        Evaluated {
            residuals: r,
            jacobian: j,
            step,
        }
    }

    /// The weighted residuals √wᵢ rᵢ and their Jacobian, cut short once `stop` is requested.
    fn weighted_and_jacobian(
        &self,
        x: &DVector<f64>,
        stop: Option<&Stop>,
    ) -> (DVector<f64>, DMatrix<f64>) {
        let p = self.layout.from_x(x);
        let free = self.layout.free();
        if !self.in_domain(&p) {
            return (
                DVector::from_element(self.n, f64::NAN),
                DMatrix::from_element(self.n, free.len(), f64::NAN),
            );
        }
        let column = self.solver_columns(x);
        let n_spec = self.model.params().len();
        if let Some(direct) = self.weighted_in_place(&p, &column, free.len(), stop) {
            return direct;
        }
        let mut rw = DVector::zeros(self.n);
        let mut out = DMatrix::zeros(self.n, free.len());
        let finish = |b: &Block, f: &mut [f64], jac: &mut [f64]| self.weigh_block(b, f, jac);
        self.eval_blocks(&p, true, stop, finish, |b, r, bj, ()| {
            let m = b.idx.len();
            for (row, i) in b.idx.iter().enumerate() {
                rw[i] = r[row];
            }
            for s in 0..n_spec {
                if let Some((col, chain)) = column[self.layout.index[b.channel][s]] {
                    for (row, i) in b.idx.iter().enumerate() {
                        out[(i, col)] = bj[s * m + row] * chain;
                    }
                }
            }
        });
        (rw, out)
    }
}

impl FitProblem<'_> {
    /// The column of each layout parameter in the solver's Jacobian at solver variables
    /// `x`, with its chain factor dp/dx (None for a held parameter).
    fn solver_columns(&self, x: &DVector<f64>) -> Vec<Option<(usize, f64)>> {
        let mut column = vec![None; self.layout.len()];
        for (col, &k) in self.layout.free().iter().enumerate() {
            column[k] = Some((col, self.layout.params[k].transform.dp_dx(x[col])));
        }
        column
    }

    /// A block's model values `f` turned into weighted residuals √wᵢ rᵢ in place, and its
    /// model Jacobian `jac` (column-major, block rows × model parameters) scaled in place
    /// by √wᵢ ∂rᵢ/∂fᵢ (the chain factor dp/dx is the caller's).
    fn weigh_block(&self, b: &Block, f: &mut [f64], jac: &mut [f64]) {
        let m = f.len();
        let n_spec = jac.len() / m.max(1);
        for (r, i) in b.idx.iter().enumerate() {
            let d = self.sqrt_w[i] * self.dr_df(i, f[r]);
            for s in 0..n_spec {
                jac[s * m + r] *= d;
            }
            f[r] = self.sqrt_w[i] * self.residual(i, f[r]);
        }
    }

    /// [`Self::weighted_and_jacobian`] for a problem of one block of every sample in order
    /// whose model parameters are all free, in their layout order (a single-channel fit
    /// with nothing held: every small fit, and every iteration of its start search): the
    /// model writes its values and Jacobian straight into the returned vector and matrix
    /// (whose columns are then the model's), which are scaled in place with the same
    /// arithmetic as the general path, so the result is the same to the bit. None for any
    /// other problem. `column[k]` is the solver column and chain factor of parameter k.
    fn weighted_in_place(
        &self,
        p: &[f64],
        column: &[Option<(usize, f64)>],
        n_free: usize,
        stop: Option<&Stop>,
    ) -> Option<(DVector<f64>, DMatrix<f64>)> {
        let [b] = &self.blocks[..] else {
            return None;
        };
        let n_spec = self.model.params().len();
        let identity = b.idx.len() == self.n
            && b.idx.iter().enumerate().all(|(r, i)| r == i)
            && n_free == n_spec
            && (0..n_spec).all(|s| {
                let k = self.layout.index[b.channel][s];
                column[k].is_some_and(|(col, _)| col == s)
            });
        if !identity || stop.is_some_and(Stop::is_requested) {
            return None;
        }
        let m = self.n;
        let mp = self.layout.model_params(p, b.channel);
        let mut f = DVector::zeros(m);
        let mut jac = DMatrix::zeros(m, n_spec);
        self.model
            .eval(&b.geo, &mp, f.as_mut_slice(), Some(jac.as_mut_slice()));
        for r in 0..m {
            let d = self.sqrt_w[r] * self.dr_df(r, f[r]);
            for s in 0..n_spec {
                jac[(r, s)] *= d;
            }
            f[r] = self.sqrt_w[r] * self.residual(r, f[r]);
        }
        for s in 0..n_spec {
            let (_, chain) = column[self.layout.index[b.channel][s]].expect("every parameter free");
            for v in jac.column_mut(s).iter_mut() {
                *v *= chain;
            }
        }
        Some((f, jac))
    }

    /// Weighted residuals at solver variables `x` (the Jacobian is kept for the solver's
    /// next request at `x`, the one kept before dropped first: a big fit holds one
    /// `n × p` matrix, not two), cut short once `stop` is requested: then some rows are
    /// NaN and the solver rejects the point.
    pub(crate) fn residuals_until(&self, x: &DVector<f64>, stop: Option<&Stop>) -> DVector<f64> {
        self.forget_cached();
        let (residuals, cached) = if self.reduces() {
            let (r, red) = self.weighted_reduced(x, stop);
            (r, (None, None, Some(red)))
        } else {
            let e = self.evaluate(x, stop);
            (e.residuals, (Some(e.jacobian), e.step, None))
        };
        if let Ok(mut c) = self.cache.lock() {
            let (jac, step, reduced) = cached;
            *c = Some(Cached {
                x: x.clone(),
                jac,
                step,
                reduced,
            });
        }
        residuals
    }

    /// The Jacobian at `x` (solver variables) when the last evaluation was at `x` and left
    /// it (handed over once); None otherwise, and then what the last evaluation left is
    /// dropped (the solver asks for the Jacobian only at points it accepted, so one left at
    /// another point is not asked for: a big fit does not hold a second `n × p` matrix
    /// while the one asked for is evaluated).
    pub(crate) fn cached_jacobian(&self, x: &DVector<f64>) -> Option<DMatrix<f64>> {
        let mut c = self.cache.lock().ok()?;
        if c.as_ref().is_some_and(|c| &c.x != x) {
            *c = None;
        }
        c.as_mut()?.jac.take()
    }

    /// Drop what the last evaluation left for the solver (its Jacobian): at the end of a
    /// solve, whose last trial point may have been rejected.
    pub(crate) fn forget_cached(&self) {
        if let Ok(mut c) = self.cache.lock() {
            *c = None;
        }
    }

    /// The Jacobian at `x`: the cached one ([`Self::cached_jacobian`]), else evaluated —
    /// unless `stop` is requested: then nothing is evaluated and every entry is NaN (no
    /// uncertainty can be computed from it).
    pub(crate) fn jacobian_until(&self, x: &DVector<f64>, stop: Option<&Stop>) -> DMatrix<f64> {
        if let Some(j) = self.cached_jacobian(x) {
            return j;
        }
        if stop.is_some_and(Stop::is_requested) {
            return DMatrix::from_element(self.n, self.layout.free().len(), f64::NAN);
        }
        self.residuals_and_jacobian(x).1
    }
}

impl LeastSquaresProblem for FitProblem<'_> {
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
        self.residuals_until(x, None)
    }

    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        // The solver asks once per accepted point: hand the cached matrix over.
        self.jacobian_until(x, None)
    }

    fn reduced_jacobian(&self, x: &DVector<f64>) -> Option<goniofit_lm::Reduced> {
        self.reduces().then(|| self.reduced_until(x, None))
    }

    fn recycle(&self, spent: DVector<f64>) {
        self.keep_spare(spent);
    }

    fn step_residuals(&self, x: &DVector<f64>) -> Option<DVector<f64>> {
        if self.loss.is_linear() {
            return None;
        }
        if let Ok(mut c) = self.cache.lock() {
            if let Some(cached) = c.as_mut().filter(|c| &c.x == x) {
                if let Some(f) = cached.step.take() {
                    return Some(f);
                }
            }
        }
        self.evaluate(x, None).step
    }
}
