//! Contour maps: a value grid, iso-lines by marching squares, a heatmap drawn as one bitmap
//! under the lines, and a colour bar. plotters has no contour primitive.

use super::{font, heat_color, DrawError};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::HashMap;

/// Values z on a rectangular grid: `z[j * xs.len() + i]` at `(xs[i], ys[j])`; `xs`, `ys`
/// strictly increasing.
#[derive(Debug, Clone)]
pub(crate) struct Grid {
    /// The columns' x, in data units, strictly increasing.
    pub xs: Vec<f64>,
    /// The rows' y, in data units, strictly increasing.
    pub ys: Vec<f64>,
    /// The values, row after row: `xs.len() * ys.len()` of them, `z[j * xs.len() + i]` at
    /// `(xs[i], ys[j])`; non-finite values are left out of [`Grid::range`].
    pub z: Vec<f64>,
}

/// A straight piece of an iso-line, in data coordinates.
#[cfg(test)]
pub(crate) type Segment = ((f64, f64), (f64, f64));

/// `n` evenly spaced values from `a` to `b` inclusive (n ≥ 2).
pub(crate) fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
    let n = n.max(2);
    (0..n)
        .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
        .collect()
}

impl Grid {
    /// Evaluate `f(x, y)` on the grid.
    #[cfg(test)]
    pub(crate) fn from_fn(xs: Vec<f64>, ys: Vec<f64>, f: impl Fn(f64, f64) -> f64) -> Grid {
        let mut z = Vec::with_capacity(xs.len() * ys.len());
        for &y in &ys {
            for &x in &xs {
                z.push(f(x, y));
            }
        }
        Grid { xs, ys, z }
    }

    /// z at grid node (i, j).
    pub(crate) fn at(&self, i: usize, j: usize) -> f64 {
        self.z[j * self.xs.len() + i]
    }

    /// Smallest and largest finite z.
    pub(crate) fn range(&self) -> (f64, f64) {
        self.z
            .iter()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            })
    }

    /// Bilinear interpolation at (x, y), clamped to the grid.
    pub(crate) fn interpolate(&self, x: f64, y: f64) -> f64 {
        let locate = |v: &[f64], t: f64| -> (usize, f64) {
            let n = v.len();
            if n < 2 || t <= v[0] {
                return (0, 0.0);
            }
            if t >= v[n - 1] {
                return (n - 2, 1.0);
            }
            let k = v.partition_point(|&p| p <= t).saturating_sub(1).min(n - 2);
            (k, (t - v[k]) / (v[k + 1] - v[k]))
        };
        if self.xs.len() < 2 || self.ys.len() < 2 {
            return self.z.first().copied().unwrap_or(f64::NAN);
        }
        let (i, fx) = locate(&self.xs, x);
        let (j, fy) = locate(&self.ys, y);
        let z00 = self.at(i, j);
        let z10 = self.at(i + 1, j);
        let z01 = self.at(i, j + 1);
        let z11 = self.at(i + 1, j + 1);
        (1.0 - fy) * ((1.0 - fx) * z00 + fx * z10) + fy * ((1.0 - fx) * z01 + fx * z11)
    }

    /// Where the iso-line z = `level` crosses grid edge `e` (linear interpolation between
    /// the edge's two nodes, always taken in the same order so shared edges agree).
    fn crossing(&self, e: Edge, level: f64) -> (f64, f64) {
        let (i, j, vertical) = e;
        let (i1, j1) = if vertical { (i, j + 1) } else { (i + 1, j) };
        let (za, zb) = (self.at(i, j), self.at(i1, j1));
        let t = (level - za) / (zb - za);
        (
            self.xs[i] + t * (self.xs[i1] - self.xs[i]),
            self.ys[j] + t * (self.ys[j1] - self.ys[j]),
        )
    }

    /// The iso-line z = `level` as pairs of crossed grid edges (marching squares; saddles
    /// are split by the cell's mean value). Cells with a non-finite corner are skipped.
    fn contour_edges(&self, level: f64) -> Vec<(Edge, Edge)> {
        let mut out = Vec::new();
        let (nx, ny) = (self.xs.len(), self.ys.len());
        if nx < 2 || ny < 2 {
            return out;
        }
        for j in 0..ny - 1 {
            for i in 0..nx - 1 {
                // Corners counter-clockwise from bottom-left; edge k joins corners k, k+1.
                let z = [
                    self.at(i, j),
                    self.at(i + 1, j),
                    self.at(i + 1, j + 1),
                    self.at(i, j + 1),
                ];
                if z.iter().any(|v| !v.is_finite()) {
                    continue;
                }
                let edge: [Edge; 4] = [
                    (i, j, false),
                    (i + 1, j, true),
                    (i, j + 1, false),
                    (i, j, true),
                ];
                let above = z.map(|v| v > level);
                let cut: Vec<usize> = (0..4).filter(|&k| above[k] != above[(k + 1) % 4]).collect();
                match cut.len() {
                    2 => out.push((edge[cut[0]], edge[cut[1]])),
                    4 => {
                        // Saddle: join edges so the centre's side stays connected.
                        let centre_above = z.iter().sum::<f64>() / 4.0 > level;
                        if centre_above == above[0] {
                            out.push((edge[0], edge[1]));
                            out.push((edge[2], edge[3]));
                        } else {
                            out.push((edge[3], edge[0]));
                            out.push((edge[1], edge[2]));
                        }
                    }
                    _ => {}
                }
            }
        }
        out
    }

    /// The iso-line z = `level` as straight segments.
    #[cfg(test)]
    pub(crate) fn contour(&self, level: f64) -> Vec<Segment> {
        self.contour_edges(level)
            .into_iter()
            .map(|(a, b)| (self.crossing(a, level), self.crossing(b, level)))
            .collect()
    }

    /// The iso-line z = `level` as polylines: the segments joined end to end (closed loops
    /// repeat their first point at the end).
    pub(crate) fn contour_lines(&self, level: f64) -> Vec<Vec<(f64, f64)>> {
        let segs = self.contour_edges(level);
        let mut at_edge: HashMap<Edge, Vec<usize>> = HashMap::new();
        for (k, (a, b)) in segs.iter().enumerate() {
            at_edge.entry(*a).or_default().push(k);
            at_edge.entry(*b).or_default().push(k);
        }
        let mut used = vec![false; segs.len()];
        // Walk from edge `from` through unused segments, collecting the edges passed.
        let walk = |start: usize, from: Edge, used: &mut [bool]| -> Vec<Edge> {
            let mut path = Vec::new();
            let mut edge = from;
            let mut seg = start;
            loop {
                let (a, b) = segs[seg];
                edge = if a == edge { b } else { a };
                path.push(edge);
                let next = at_edge[&edge].iter().copied().find(|&s| !used[s]);
                match next {
                    Some(s) => {
                        used[s] = true;
                        seg = s;
                    }
                    None => break,
                }
            }
            path
        };
        let mut lines = Vec::new();
        for k in 0..segs.len() {
            if used[k] {
                continue;
            }
            used[k] = true;
            let (a, b) = segs[k];
            let forward = walk(k, a, &mut used); // a → b → …
            let mut backward = walk(k, b, &mut used); // b → a → …
            backward.reverse();
            let edges: Vec<Edge> = backward.into_iter().chain(forward).collect();
            lines.push(edges.into_iter().map(|e| self.crossing(e, level)).collect());
        }
        lines
    }
}

/// A grid edge: (i, j, vertical) is the edge from node (i, j) to (i, j + 1) when vertical,
/// to (i + 1, j) otherwise.
type Edge = (usize, usize, bool);

/// Draw `grid` as a heatmap filling the chart's plotting area, colour `heat_color((z − lo) /
/// (hi − lo))`, as one bitmap (one embedded image in SVG).
pub(crate) fn draw_heatmap<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    grid: &Grid,
    (lo, hi): (f64, f64),
) -> Result<(), DrawError<DB>> {
    let area = chart.plotting_area();
    let (w, h) = area.dim_in_pixel();
    if w == 0 || h == 0 {
        return Ok(());
    }
    let xr = area.get_x_range();
    let yr = area.get_y_range();
    let span = if hi > lo { hi - lo } else { 1.0 };
    let mut buf = vec![0u8; w as usize * h as usize * 3];
    for py in 0..h as usize {
        let y = yr.end - (py as f64 + 0.5) / h as f64 * (yr.end - yr.start);
        for px in 0..w as usize {
            let x = xr.start + (px as f64 + 0.5) / w as f64 * (xr.end - xr.start);
            let c = heat_color((grid.interpolate(x, y) - lo) / span);
            let k = (py * w as usize + px) * 3;
            buf[k] = c.0;
            buf[k + 1] = c.1;
            buf[k + 2] = c.2;
        }
    }
    if let Some(img) = BitMapElement::with_owned_buffer((xr.start, yr.end), (w, h), buf) {
        area.draw(&img)?;
    }
    Ok(())
}

/// Draw the iso-lines of `grid` at `levels` with `pen`, at sub-pixel positions.
pub(crate) fn draw_contours<DB: super::stroke::Canvas>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    grid: &Grid,
    levels: &[f64],
    pen: super::stroke::Pen,
) -> Result<(), DrawError<DB>> {
    let map = super::stroke::PixelMap::of_linear(chart);
    for &level in levels {
        for line in grid.contour_lines(level) {
            super::stroke::draw_data_polyline(chart.plotting_area(), &map, &line, pen)?;
        }
    }
    Ok(())
}

/// A vertical colour bar for values `lo..hi` in `area`, with tick labels and `label`, and
/// black marks at the contour `levels`.
pub(crate) fn draw_colorbar<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (lo, hi): (f64, f64),
    levels: &[f64],
    label: &str,
) -> Result<(), DrawError<DB>> {
    let hi = if hi > lo { hi } else { lo + 1.0 };
    let mut chart = ChartBuilder::on(area)
        .margin_top(50)
        .margin_bottom(60)
        .margin_left(10)
        .margin_right(12)
        .right_y_label_area_size(80)
        .build_cartesian_2d(0.0..1.0, lo..hi)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .disable_y_mesh()
        .disable_x_axis()
        .y_labels(6)
        .y_label_formatter(&|v| super::fmt_tick(*v))
        .y_desc(label)
        .label_style(font(14.0))
        .axis_desc_style(font(16.0))
        .draw()?;
    let n = 200;
    chart.draw_series((0..n).map(|k| {
        let a = lo + (hi - lo) * k as f64 / n as f64;
        let b = lo + (hi - lo) * (k + 1) as f64 / n as f64;
        let c = heat_color((0.5 * (a + b) - lo) / (hi - lo));
        Rectangle::new([(0.0, a), (1.0, b)], c.filled())
    }))?;
    chart.draw_series(
        levels
            .iter()
            .map(|&l| PathElement::new(vec![(0.0, l), (1.0, l)], BLACK.stroke_width(1))),
    )?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_contour_has_the_right_radius() {
        let xs = linspace(-1.0, 1.0, 81);
        let ys = linspace(-1.0, 1.0, 81);
        let g = Grid::from_fn(xs, ys, |x, y| x * x + y * y);
        let segs = g.contour(0.25);
        assert!(segs.len() > 40);
        for (a, b) in segs {
            for p in [a, b] {
                let r = (p.0 * p.0 + p.1 * p.1).sqrt();
                assert!((r - 0.5).abs() < 0.01, "r = {r}");
            }
        }
    }

    #[test]
    fn contour_lines_join_into_one_closed_loop() {
        let xs = linspace(-1.0, 1.0, 41);
        let ys = linspace(-1.0, 1.0, 41);
        let g = Grid::from_fn(xs, ys, |x, y| x * x + y * y);
        let lines = g.contour_lines(0.25);
        assert_eq!(lines.len(), 1);
        let line = &lines[0];
        assert_eq!(line.len(), g.contour(0.25).len() + 1);
        let (a, b) = (line[0], line[line.len() - 1]);
        assert!(
            (a.0 - b.0).abs() < 1e-12 && (a.1 - b.1).abs() < 1e-12,
            "closed"
        );
        // Two separate bumps give two loops; an open line touching the border stays open.
        let g2 = Grid::from_fn(linspace(-2.0, 2.0, 81), linspace(-1.0, 1.0, 41), |x, y| {
            (-(x - 1.0).powi(2) * 8.0 - y * y * 8.0).exp()
                + (-(x + 1.0).powi(2) * 8.0 - y * y * 8.0).exp()
        });
        assert_eq!(g2.contour_lines(0.5).len(), 2);
        let g3 = Grid::from_fn(linspace(0.0, 1.0, 11), linspace(0.0, 1.0, 11), |x, _| x);
        let open = g3.contour_lines(0.55);
        assert_eq!(open.len(), 1);
        assert_eq!(open[0].len(), 11);
    }

    #[test]
    fn interpolation_is_exact_for_bilinear_functions() {
        let g = Grid::from_fn(linspace(0.0, 2.0, 5), linspace(0.0, 1.0, 3), |x, y| {
            1.0 + 2.0 * x - y + x * y
        });
        let (x, y) = (1.3, 0.7);
        assert!((g.interpolate(x, y) - (1.0 + 2.0 * x - y + x * y)).abs() < 1e-12);
        assert_eq!(g.range(), (0.0, 6.0));
    }
}
