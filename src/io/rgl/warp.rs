//! The marginal–conditional 2-D warp of the RGL loader, with linear interpolation in one
//! parameter (the incidence elevation θi).
//!
//! A warp holds, per parameter value ("slice"), a density on an `nx × ny` grid over the
//! unit square, bilinearly interpolated. Sampling maps the unit square onto that density
//! by inverting a marginal CDF over rows and then a conditional CDF over columns (both
//! exact for the bilinear density: a quadratic per cell); [`Warp::invert`] is the inverse
//! map. Between two slices every table (density and CDFs) is linearly interpolated, as the
//! reference loader does. A warp built without CDFs is a plain bilinear interpolant.
//!
//! Arithmetic is f32 in the loader's order of operations (its fused multiply-adds
//! included), so that goniofit's points and values are the loader's to a few f32 rounding
//! steps; CDF sums run in f64 as the loader's do.

/// Clamp of a sample away from 0 and 1 (the loader's `1 − 2⁻²⁴`).
const ONE_MINUS_EPSILON: f32 = 0.999_999_94;

/// One slice's tables.
#[derive(Debug, Clone)]
struct Slice {
    data: Vec<f32>,
    marginal: Vec<f32>,
    conditional: Vec<f32>,
}

/// A 2-D density on an `nx × ny` grid (x contiguous), per value of a parameter.
#[derive(Debug, Clone)]
pub(crate) struct Warp {
    nx: usize,
    ny: usize,
    params: Vec<f32>,
    slices: Vec<Slice>,
    /// (nx − 1)(ny − 1): the cells' density scale, applied after interpolation.
    cells: f32,
}

/// Two slices and their weights at one parameter value.
struct Blend<'a> {
    a: &'a Slice,
    b: &'a Slice,
    wa: f32,
    wb: f32,
}

impl Blend<'_> {
    fn mix(&self, x: f32, y: f32) -> f32 {
        x.mul_add(self.wa, y * self.wb)
    }
    fn data(&self, i: usize) -> f32 {
        self.mix(self.a.data[i], self.b.data[i])
    }
    fn marginal(&self, i: usize) -> f32 {
        self.mix(self.a.marginal[i], self.b.marginal[i])
    }
    fn conditional(&self, i: usize) -> f32 {
        self.mix(self.a.conditional[i], self.b.conditional[i])
    }
}

/// The index `i` in `[0, size − 2]` with `pred(i)` true and `pred(i + 1)` false, by
/// bisection over a monotone predicate (clamped at both ends, as the loader's
/// `find_interval`). `size` ≥ 2.
pub(crate) fn find_interval(size: usize, pred: impl Fn(usize) -> bool) -> usize {
    let mut first = 1usize;
    let mut len = size as isize - 2;
    while len > 0 {
        let half = (len as usize) >> 1;
        let middle = first + half;
        if pred(middle) {
            first = middle + 1;
            len -= half as isize + 1;
        } else {
            len = half as isize;
        }
    }
    (first as isize - 1).clamp(0, size as isize - 2) as usize
}

impl Warp {
    fn new(nx: usize, ny: usize, params: Vec<f32>, slices: Vec<Slice>) -> Warp {
        let cells = (nx - 1) as f32 * (ny - 1) as f32;
        Warp {
            nx,
            ny,
            params,
            slices,
            cells,
        }
    }

    /// A plain bilinear interpolant per parameter value: `data` holds `params.len()`
    /// slices of `nx × ny` values. `nx, ny ≥ 2`, `params` ascending and non-empty.
    pub(crate) fn plain(nx: usize, ny: usize, params: Vec<f32>, data: &[f32]) -> Warp {
        let norm = 1.0 / ((nx - 1) as f32 * (ny - 1) as f32);
        let slices = data
            .chunks_exact(nx * ny)
            .map(|d| Slice {
                data: d.iter().map(|v| v * norm).collect(),
                marginal: Vec::new(),
                conditional: Vec::new(),
            })
            .collect();
        Warp::new(nx, ny, params, slices)
    }

    /// A sampling warp: each slice normalised to integrate to 1 over the unit square's
    /// cells, with its marginal (rows) and conditional (columns) CDFs, summed in f64 and
    /// stored in f32 as the loader does. A slice whose integral is not positive and finite
    /// is refused (the message says which).
    pub(crate) fn sampling(
        nx: usize,
        ny: usize,
        params: Vec<f32>,
        data: &[f32],
    ) -> Result<Warp, String> {
        let mut slices = Vec::new();
        for (k, d) in data.chunks_exact(nx * ny).enumerate() {
            let mut conditional = vec![0.0f32; nx * ny];
            for y in 0..ny {
                let mut sum = 0.0f64;
                for x in 0..nx - 1 {
                    let i = y * nx + x;
                    sum += 0.5 * (d[i] as f64 + d[i + 1] as f64);
                    conditional[i + 1] = sum as f32;
                }
            }
            let mut marginal = vec![0.0f32; ny];
            let mut sum = 0.0f64;
            for y in 0..ny - 1 {
                sum += 0.5
                    * (conditional[(y + 1) * nx - 1] as f64 + conditional[(y + 2) * nx - 1] as f64);
                marginal[y + 1] = sum as f32;
            }
            let total = marginal[ny - 1];
            if !(total.is_finite() && total > 0.0) {
                return Err(format!(
                    "slice {k}: the distribution's integral is {sum}, expected positive and finite"
                ));
            }
            let norm = 1.0 / total;
            conditional.iter_mut().for_each(|v| *v *= norm);
            marginal.iter_mut().for_each(|v| *v *= norm);
            let data = d.iter().map(|v| v * norm).collect();
            slices.push(Slice {
                data,
                marginal,
                conditional,
            });
        }
        Ok(Warp::new(nx, ny, params, slices))
    }

    /// The slices and weights at parameter `p` (clamped to the stored range).
    fn blend(&self, p: f32) -> Blend<'_> {
        if self.params.len() == 1 {
            let a = &self.slices[0];
            return Blend {
                a,
                b: a,
                wa: 1.0,
                wb: 0.0,
            };
        }
        let k = find_interval(self.params.len(), |i| self.params[i] <= p);
        let (p0, p1) = (self.params[k], self.params[k + 1]);
        let wb = ((p - p0) / (p1 - p0)).clamp(0.0, 1.0);
        Blend {
            a: &self.slices[k],
            b: &self.slices[k + 1],
            wa: 1.0 - wb,
            wb,
        }
    }

    /// The cell containing `pos` and the position within it (in cells).
    fn cell(&self, pos: [f32; 2]) -> ([usize; 2], [f32; 2]) {
        let s = [pos[0] * (self.nx - 1) as f32, pos[1] * (self.ny - 1) as f32];
        let cx = (s[0].max(0.0) as usize).min(self.nx - 2);
        let cy = (s[1].max(0.0) as usize).min(self.ny - 2);
        ([cx, cy], [s[0] - cx as f32, s[1] - cy as f32])
    }

    /// The bilinear interpolant at `pos` ∈ [0, 1]² and parameter `p` (for a sampling warp
    /// the normalised density), as the loader's `eval`.
    pub(crate) fn eval(&self, pos: [f32; 2], p: f32) -> f32 {
        let b = self.blend(p);
        let ([cx, cy], w1) = self.cell(pos);
        let i = cx + cy * self.nx;
        let (v00, v10) = (b.data(i), b.data(i + 1));
        let (v01, v11) = (b.data(i + self.nx), b.data(i + self.nx + 1));
        let w0 = [1.0 - w1[0], 1.0 - w1[1]];
        let lo = w0[0].mul_add(v00, w1[0] * v10);
        let hi = w0[0].mul_add(v01, w1[0] * v11);
        w0[1].mul_add(lo, w1[1] * hi) * self.cells
    }

    /// Map a point of the unit square through the warp at parameter `p` (a sampling warp):
    /// the marginal CDF picks the row, the conditional CDF the column, each inverted
    /// exactly for the bilinear density.
    pub(crate) fn sample(&self, u: [f32; 2], p: f32) -> [f32; 2] {
        let lo = 1.0 - ONE_MINUS_EPSILON;
        let mut s = [
            u[0].max(lo).min(ONE_MINUS_EPSILON),
            u[1].max(lo).min(ONE_MINUS_EPSILON),
        ];
        let b = self.blend(p);
        let nx = self.nx;
        let row = find_interval(self.ny, |i| b.marginal(i) < s[1]);
        s[1] -= b.marginal(row);
        let off = row * nx;
        let r0 = b.conditional(off + nx - 1);
        let r1 = b.conditional(off + 2 * nx - 1);
        s[1] = solve_linear_cdf(r0, r1, s[1]);
        s[0] *= (1.0 - s[1]) * r0 + s[1] * r1;
        let cond =
            |i: usize| (1.0 - s[1]) * b.conditional(off + i) + s[1] * b.conditional(off + nx + i);
        let col = find_interval(nx, |i| cond(i) < s[0]);
        s[0] -= cond(col);
        let i = off + col;
        let c0 = (1.0 - s[1]).mul_add(b.data(i), s[1] * b.data(i + nx));
        let c1 = (1.0 - s[1]).mul_add(b.data(i + 1), s[1] * b.data(i + nx + 1));
        s[0] = solve_linear_cdf(c0, c1, s[0]);
        [
            (col as f32 + s[0]) * (1.0 / (nx - 1) as f32),
            (row as f32 + s[1]) * (1.0 / (self.ny - 1) as f32),
        ]
    }

    /// The inverse of [`Warp::sample`] at parameter `p`: the point of the unit square that
    /// maps to `pos`.
    pub(crate) fn invert(&self, pos: [f32; 2], p: f32) -> [f32; 2] {
        let b = self.blend(p);
        let nx = self.nx;
        let ([cx, cy], mut s) = self.cell(pos);
        let i = cx + cy * nx;
        let (v00, v10) = (b.data(i), b.data(i + 1));
        let (v01, v11) = (b.data(i + nx), b.data(i + nx + 1));
        let c0 = (1.0 - s[1]).mul_add(v00, s[1] * v01);
        let c1 = (1.0 - s[1]).mul_add(v10, s[1] * v11);
        s[0] *= c0 + 0.5 * s[0] * (c1 - c0);
        s[0] += (1.0 - s[1]) * b.conditional(i) + s[1] * b.conditional(i + nx);
        let off = cy * nx;
        let r0 = b.conditional(off + nx - 1);
        let r1 = b.conditional(off + 2 * nx - 1);
        s[0] /= (1.0 - s[1]) * r0 + s[1] * r1;
        s[1] *= r0 + 0.5 * s[1] * (r1 - r0);
        s[1] += b.marginal(cy);
        s
    }
}

/// The t ∈ [0, 1] where the integral of the linear density from `f0` (at 0) to `f1`
/// (at 1) reaches `x`: the root of `f0 t + (f1 − f0) t²/2 = x` (as the loader: a
/// near-constant density solves the linear equation).
fn solve_linear_cdf(f0: f32, f1: f32, x: f32) -> f32 {
    if (f0 - f1).abs() < 1e-4 * (f0 + f1) {
        2.0 * x / (f0 + f1)
    } else {
        (f0 - (f0 * f0 - 2.0 * x * (f0 - f1)).max(0.0).sqrt()) / (f0 - f1)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sampling then inverting returns the point, on a non-uniform density and between
    /// two parameter slices.
    #[test]
    fn invert_undoes_sample() {
        let (nx, ny) = (5, 4);
        let mut data = Vec::new();
        for k in 0..2 {
            for y in 0..ny {
                for x in 0..nx {
                    data.push(1.0 + (x * x + 3 * y + k * x) as f32 * 0.3);
                }
            }
        }
        let w = Warp::sampling(nx, ny, vec![0.0, 1.0], &data).unwrap();
        for &p in &[0.0, 0.3, 1.0] {
            for &u in &[[0.1, 0.2], [0.5, 0.5], [0.93, 0.07], [0.33, 0.81]] {
                let m = w.sample(u, p);
                let back = w.invert(m, p);
                assert!(
                    (back[0] - u[0]).abs() < 1e-5 && (back[1] - u[1]).abs() < 1e-5,
                    "{u:?} {p} → {m:?} → {back:?}"
                );
            }
        }
    }

    /// A uniform density maps the square onto itself.
    #[test]
    fn uniform_density_is_the_identity() {
        let w = Warp::sampling(3, 3, vec![0.0], &[2.0; 9]).unwrap();
        let m = w.sample([0.25, 0.7], 0.0);
        assert!((m[0] - 0.25).abs() < 1e-6 && (m[1] - 0.7).abs() < 1e-6);
        assert!((w.eval([0.4, 0.4], 0.0) - 1.0).abs() < 1e-6);
    }
}
