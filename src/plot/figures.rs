//! The paper's Figures 4–7 (Peters 2000), regenerated from the models.
//!
//! - Figure 4: spheres lit from 45°, KBS rough approximation with T/σ = 3, 4, 5, 7, 10 and a
//!   Lambertian sphere, as negatives with the view (+), light (×) and specular (○) marks.
//! - Figure 5: the intensity along the line through the marks (the sphere's y = 0 row),
//!   over the normal's angle θ from the view direction, −90°…90°, each curve normalised.
//! - Figure 6: θi = 45°, T/σ = 5, rough approximation: L over θr ∈ [0°, 90°] for
//!   φr = 0, π/16, …, π/2.
//! - Figure 7: contours of L over (θr, φr) for the same surface.
//!
//! The data each figure shows come from public functions ([`figure5_curves`],
//! [`figure6_curves`], [`figure7_grid`]) so tests can hold them to the paper's facts.

use super::contour::{draw_colorbar, draw_contours, draw_heatmap, linspace, Grid};
use super::legend::{self, Entry, Glyph, Marker};
use super::sphere::{draw_caption, draw_sphere, sphere_radiance, SphereImage};
use super::xy::{draw_titles, Kind, Series, XyPlot};
use super::{font, series_color, write_png_svg, DrawError, Picture};
use crate::error::Result;
use crate::geometry::{Geometry, Quantity, Sample};
use crate::model::{by_name, Model, ModelOptions};
use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// The correlation-length-to-roughness ratios of Figures 4 and 5.
pub(crate) const T_OVER_SIGMA: [f64; 5] = [3.0, 4.0, 5.0, 7.0, 10.0];
/// Light angle from the view direction in Figures 4 and 5, degrees.
pub(crate) const LIGHT_DEG: f64 = 45.0;
/// θi of Figures 6 and 7, degrees.
pub(crate) const FIG6_THETA_I_DEG: f64 = 45.0;
/// T/σ of Figures 6 and 7.
pub(crate) const FIG6_T_OVER_SIGMA: f64 = 5.0;

/// One curve of a figure: a label, the parameter that distinguishes it (T/σ, or φr in
/// radians; NaN for the Lambertian curve) and its (x, y) points.
#[derive(Debug, Clone)]
pub(crate) struct Curve {
    /// The legend text, e.g. `KBS rough, T/σ = 5` or `φr = π/4 (45°)`.
    pub label: String,
    /// T/σ (Figure 5), φr in radians (Figure 6), or NaN for the Lambertian curve (drawn
    /// dashed black).
    pub param: f64,
    /// (angle in degrees, normalised L): θ of the normal from the view for Figure 5, θr for
    /// Figure 6; L is 0 where the geometry is outside the model's domain.
    pub points: Vec<(f64, f64)>,
}

impl Curve {
    /// The point with the largest y.
    pub(crate) fn peak(&self) -> (f64, f64) {
        self.points
            .iter()
            .copied()
            .filter(|p| p.1.is_finite())
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap_or((f64::NAN, f64::NAN))
    }

    /// Width of the region where y ≥ half the peak (in x units, by grid points).
    #[cfg(test)]
    pub(crate) fn width_at_half_max(&self) -> f64 {
        let half = 0.5 * self.peak().1;
        let xs: Vec<f64> = self
            .points
            .iter()
            .filter(|p| p.1 >= half)
            .map(|p| p.0)
            .collect();
        match (xs.first(), xs.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }
}

fn kbs_rough() -> Result<Box<dyn Model>> {
    by_name("kbs-rough", &ModelOptions::default())
}

fn lambert() -> Result<Box<dyn Model>> {
    by_name("lambert", &ModelOptions::default())
}

/// KBS parameters (σ, T, s) for a ratio T/σ, with σ = λ = 1.
fn kbs_params(t_over_sigma: f64) -> [f64; 3] {
    [1.0, t_over_sigma, 1.0]
}

/// Radiance of `model` at `samples` (wavelength 1); samples outside the domain give 0.
fn radiance_at(model: &dyn Model, params: &[f64], samples: &[Sample]) -> Result<Vec<f64>> {
    let valid: Vec<usize> = (0..samples.len())
        .filter(|&k| samples[k].validate().is_ok())
        .collect();
    let picked: Vec<Sample> = valid.iter().map(|&k| samples[k]).collect();
    let mut out = vec![0.0; samples.len()];
    if !picked.is_empty() {
        let geo = Geometry::new(&picked, &[1.0], Quantity::Radiance)?;
        let mut vals = vec![0.0; picked.len()];
        model.radiance(&geo, params, &mut vals, None);
        for (&k, v) in valid.iter().zip(vals) {
            out[k] = if v.is_finite() { v } else { 0.0 };
        }
    }
    Ok(out)
}

/// The six spheres of Figure 4 (five KBS, one Lambertian) at `size` pixels, with captions.
pub(crate) fn figure4_spheres(size: u32) -> Result<Vec<(SphereImage, String)>> {
    let kbs = kbs_rough()?;
    let mut out = Vec::new();
    for r in T_OVER_SIGMA {
        let img = sphere_radiance(kbs.as_ref(), &kbs_params(r), LIGHT_DEG, 1.0, size)?;
        out.push((img, format!("KBS rough, T/σ = {r}")));
    }
    let img = sphere_radiance(lambert()?.as_ref(), &[1.0], LIGHT_DEG, 1.0, size)?;
    out.push((img, "Lambertian".to_string()));
    Ok(out)
}

/// Figure 5's curves: radiance along the sphere's y = 0 row, the normal at θ (degrees,
/// −90…90, negative toward the light) from the view direction, each normalised to its
/// maximum; five KBS curves (param = T/σ) and the Lambertian one (param = NaN).
pub(crate) fn figure5_curves(n_points: usize) -> Result<Vec<Curve>> {
    let t = LIGHT_DEG.to_radians();
    let source = Vector3::new(-t.sin(), 0.0, t.cos());
    let view = Vector3::z();
    let thetas = linspace(-90.0, 90.0, n_points);
    let samples: Vec<Sample> = thetas
        .iter()
        .map(|th| {
            let a = th.to_radians();
            let normal = Vector3::new(a.sin(), 0.0, a.cos());
            if source.dot(&normal) <= 1e-9 {
                // Unlit: outside the model's domain, shown as 0.
                Sample {
                    theta_i: std::f64::consts::PI,
                    theta_r: 0.0,
                    phi_r: 0.0,
                }
            } else {
                Sample::from_vectors(&source, &normal, &view)
            }
        })
        .collect();
    let normalised = |vals: Vec<f64>| -> Vec<(f64, f64)> {
        let max = vals.iter().fold(0.0f64, |m, &v| m.max(v));
        let s = if max > 0.0 { 1.0 / max } else { 0.0 };
        thetas.iter().zip(vals).map(|(&x, v)| (x, v * s)).collect()
    };
    let kbs = kbs_rough()?;
    let mut curves = Vec::new();
    for r in T_OVER_SIGMA {
        let vals = radiance_at(kbs.as_ref(), &kbs_params(r), &samples)?;
        curves.push(Curve {
            label: format!("KBS rough, T/σ = {r}"),
            param: r,
            points: normalised(vals),
        });
    }
    let vals = radiance_at(lambert()?.as_ref(), &[1.0], &samples)?;
    curves.push(Curve {
        label: "Lambertian".into(),
        param: f64::NAN,
        points: normalised(vals),
    });
    Ok(curves)
}

/// Figure 6's curves: L over θr (degrees, 0…90) at θi = 45°, T/σ = 5 (rough
/// approximation), for φr = kπ/16, k = 0…8 (param = φr in radians), all normalised to the
/// φr = 0 curve's peak.
pub(crate) fn figure6_curves(n_points: usize) -> Result<Vec<Curve>> {
    let kbs = kbs_rough()?;
    let params = kbs_params(FIG6_T_OVER_SIGMA);
    let thetas = linspace(0.0, 90.0, n_points);
    let mut curves = Vec::new();
    for k in 0..=8 {
        let phi = k as f64 * std::f64::consts::PI / 16.0;
        let samples: Vec<Sample> = thetas
            .iter()
            .map(|&tr| Sample::from_degrees(FIG6_THETA_I_DEG, tr, phi.to_degrees()))
            .collect();
        let vals = radiance_at(kbs.as_ref(), &params, &samples)?;
        let label = match k {
            0 => "φr = 0".to_string(),
            8 => "φr = π/2 (90°)".to_string(),
            _ => {
                let (num, den) = reduce(k, 16);
                let num_s = if num == 1 {
                    String::new()
                } else {
                    num.to_string()
                };
                format!(
                    "φr = {num_s}π/{den} ({}°)",
                    super::fmt_num(phi.to_degrees())
                )
            }
        };
        curves.push(Curve {
            label,
            param: phi,
            points: thetas.iter().copied().zip(vals).collect(),
        });
    }
    let max = curves[0].peak().1;
    if max > 0.0 {
        for c in &mut curves {
            for p in &mut c.points {
                p.1 /= max;
            }
        }
    }
    Ok(curves)
}

fn reduce(num: usize, den: usize) -> (usize, usize) {
    let (mut a, mut b) = (num, den);
    while b != 0 {
        (a, b) = (b, a % b);
    }
    (num / a, den / a)
}

/// Figure 7's grid: L at θi = 45°, T/σ = 5 (rough approximation) over x = θr (degrees,
/// 0…90) and y = φr (degrees, −180…180), normalised to its maximum.
pub(crate) fn figure7_grid(nx: usize, ny: usize) -> Result<Grid> {
    let kbs = kbs_rough()?;
    let xs = linspace(0.0, 90.0, nx);
    let ys = linspace(-180.0, 180.0, ny);
    let mut samples = Vec::with_capacity(nx * ny);
    for &phi in &ys {
        for &tr in &xs {
            samples.push(Sample::from_degrees(FIG6_THETA_I_DEG, tr, phi));
        }
    }
    let mut z = radiance_at(kbs.as_ref(), &kbs_params(FIG6_T_OVER_SIGMA), &samples)?;
    let max = z.iter().fold(0.0f64, |m, &v| m.max(v));
    if max > 0.0 {
        z.iter_mut().for_each(|v| *v /= max);
    }
    Ok(Grid { xs, ys, z })
}

/// Contour levels (fractions of the maximum) of Figure 7 and the fit contour plot.
pub(crate) const LEVELS: [f64; 10] = [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];

/// Figure 4: six spheres in a 3×2 grid with captions.
#[derive(Debug, Clone)]
pub(crate) struct Figure4 {
    /// The spheres in reading order (the five KBS ratios of [`T_OVER_SIGMA`], then the
    /// Lambertian one), each with the caption drawn under it.
    pub spheres: Vec<(SphereImage, String)>,
}

const FIG4_SPHERE: u32 = 280;
const FIG4_PANEL: (u32, u32) = (340, 350);
const FIG4_TOP: u32 = 80;
const FIG4_BOTTOM: u32 = 60;

impl Figure4 {
    /// Compute the spheres.
    pub(crate) fn new() -> Result<Self> {
        Ok(Figure4 {
            spheres: figure4_spheres(FIG4_SPHERE)?,
        })
    }
}

impl Picture for Figure4 {
    fn size(&self) -> (u32, u32) {
        (3 * FIG4_PANEL.0, FIG4_TOP + 2 * FIG4_PANEL.1 + FIG4_BOTTOM)
    }

    fn draw<DB: super::stroke::Canvas>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError<DB>> {
        let (w, h) = self.size();
        let centre = |y: u32, text: &str, size: f64| {
            draw_caption(root, ((w / 2) as i32, y as i32), text, size)
        };
        centre(
            14,
            "Figure 4: spheres lit from 45° (negatives), KBS rough approximation (σ = λ = 1) and Lambertian",
            21.0,
        )?;
        centre(
            44,
            "viewed along +z, light at ŝ = (−sin 45°, 0, cos 45°); darker = more light",
            16.0,
        )?;
        for (k, (img, caption)) in self.spheres.iter().enumerate() {
            let (col, row) = ((k % 3) as u32, (k / 3) as u32);
            let x0 = col * FIG4_PANEL.0 + (FIG4_PANEL.0 - img.size) / 2;
            let y0 = FIG4_TOP + row * FIG4_PANEL.1;
            draw_sphere(root, (x0 as i32, y0 as i32), img, true, true)?;
            draw_caption(
                root,
                (
                    (col * FIG4_PANEL.0 + FIG4_PANEL.0 / 2) as i32,
                    (y0 + img.size + 10) as i32,
                ),
                caption,
                18.0,
            )?;
        }
        // Legend of the marks, drawn with the same shapes as on the spheres.
        let y = (h - FIG4_BOTTOM / 2) as i32;
        let red = RGBColor(220, 0, 0).stroke_width(2);
        let x = (w / 2) as i32 - 330;
        let r = 8;
        root.draw(&PathElement::new(vec![(x - r, y), (x + r, y)], red))?;
        root.draw(&PathElement::new(vec![(x, y - r), (x, y + r)], red))?;
        let label = |x: i32, text: &str| {
            root.draw_text(
                text,
                &font(16.0)
                    .color(&BLACK)
                    .pos(plotters::style::text_anchor::Pos::new(
                        plotters::style::text_anchor::HPos::Left,
                        plotters::style::text_anchor::VPos::Center,
                    )),
                (x, y),
            )
        };
        label(x + 16, "view direction")?;
        let x = x + 190;
        let d = 6;
        root.draw(&PathElement::new(vec![(x - d, y - d), (x + d, y + d)], red))?;
        root.draw(&PathElement::new(vec![(x - d, y + d), (x + d, y - d)], red))?;
        label(x + 16, "light direction")?;
        let x = x + 190;
        root.draw(&Circle::new((x, y), d, red))?;
        label(x + 16, "specular direction (22.5° from view)")?;
        Ok(())
    }
}

/// Figure 5 as a chart.
pub(crate) fn figure5() -> Result<XyPlot> {
    let curves = figure5_curves(241)?;
    let mut plot = XyPlot::new(
        "Figure 5: intensity along the line through the marks (y = 0), light at 45°",
        "θ, angle of the surface normal from the view direction (degrees; light side < 0)",
        "L / L_max (each curve normalised)",
    );
    plot.x_range = (-90.0, 90.0);
    plot.y_range = (0.0, 1.08);
    for (k, c) in curves.into_iter().enumerate() {
        let lambert = c.param.is_nan();
        plot.series.push(Series {
            label: Some(c.label),
            color: if lambert { BLACK } else { series_color(k) },
            kind: if lambert {
                Kind::Dashed(2)
            } else {
                Kind::Line(2)
            },
            points: c.points,
        });
    }
    plot.vlines = vec![
        (-45.0, " × light".into()),
        (-22.5, " ○ specular".into()),
        (0.0, " + view".into()),
    ];
    Ok(plot)
}

/// Figure 6 as a chart.
pub(crate) fn figure6() -> Result<XyPlot> {
    let curves = figure6_curves(181)?;
    let mut plot = XyPlot::new(
        "Figure 6: KBS rough approximation, θi = 45°, T/σ = 5: L over θr for φr = 0 … π/2",
        "θr, view angle from the surface normal (degrees)",
        "L / L(θr = 45°, φr = 0)",
    );
    plot.x_range = (0.0, 90.0);
    plot.y_range = (0.0, 1.08);
    for (k, c) in curves.into_iter().enumerate() {
        plot.series.push(Series {
            label: Some(c.label),
            color: series_color(k),
            kind: Kind::Line(2),
            points: c.points,
        });
    }
    plot.vlines = vec![(45.0, " mirror θr = θi".into())];
    Ok(plot)
}

/// A set of marked points on a contour map: legend label, (x, y) points, fill colour.
pub(crate) type Marks = (String, Vec<(f64, f64)>, RGBColor);

/// A contour map picture: heatmap, iso-lines, colour bar, marked points, legend.
#[derive(Debug, Clone)]
pub(crate) struct ContourPlot {
    /// The first title line, centred above the legend and map.
    pub title: String,
    /// A second title line; empty for none.
    pub subtitle: String,
    /// The x axis label (under the map), naming the grid's x and its unit.
    pub x_desc: String,
    /// The y axis label (left of the map), naming the grid's y and its unit.
    pub y_desc: String,
    /// The colour bar's label: what z is, in which unit.
    pub z_desc: String,
    /// The picture's width and height, pixels.
    pub size: (u32, u32),
    /// The values mapped; the axes span its first to last x and y, the colours run from the
    /// smaller of 0 and its lowest finite z to its highest.
    pub grid: Grid,
    /// Absolute contour levels (z units).
    pub levels: Vec<f64>,
    /// Legend text for the contour lines.
    pub levels_label: String,
    /// Marked points, each set with its legend label and colour.
    pub marks: Vec<Marks>,
}

impl ContourPlot {
    /// The legend's lines: the contour levels and each set of marks.
    pub(crate) fn legend_entries(&self) -> Vec<Entry> {
        let mut out = vec![Entry {
            glyph: Glyph::Line {
                color: BLACK,
                width: 2,
                dash: None,
            },
            label: self.levels_label.clone(),
        }];
        out.extend(self.marks.iter().map(|(label, _, color)| Entry {
            glyph: Glyph::Point {
                color: *color,
                marker: Marker::Filled,
                r: 5,
            },
            label: label.clone(),
        }));
        out
    }
}

impl Picture for ContourPlot {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: super::stroke::Canvas>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError<DB>> {
        let root = draw_titles(root, &self.title, &self.subtitle)?;
        // The legend in rows above the map, never over it.
        let (w, _) = root.dim_in_pixel();
        let entries = self.legend_entries();
        let rows = legend::rows(&entries, w.saturating_sub(40)).len() as u32;
        let (top, root) = root.split_vertically(rows * legend::LINE_H + 4);
        legend::draw_rows(&top, &entries)?;
        let (main, bar) = root.split_horizontally(w.saturating_sub(160));
        let (x0, x1) = (self.grid.xs[0], *self.grid.xs.last().unwrap_or(&1.0));
        let (y0, y1) = (self.grid.ys[0], *self.grid.ys.last().unwrap_or(&1.0));
        let mut chart = ChartBuilder::on(&main)
            .margin(12)
            .x_label_area_size(55)
            .y_label_area_size(80)
            .build_cartesian_2d(x0..x1, y0..y1)?;
        let (lo, hi) = self.grid.range();
        let (lo, hi) = (lo.min(0.0), hi);
        draw_heatmap(&mut chart, &self.grid, (lo, hi))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc(self.x_desc.as_str())
            .y_desc(self.y_desc.as_str())
            .x_labels(10)
            .y_labels(9)
            .x_label_formatter(&|v| super::fmt_tick(*v))
            .y_label_formatter(&|v| super::fmt_tick(*v))
            .label_style(font(15.0))
            .axis_desc_style(font(18.0))
            .draw()?;
        draw_contours(
            &mut chart,
            &self.grid,
            &self.levels,
            super::stroke::Pen::solid(BLACK, 1.0),
        )?;
        for (_, pts, color) in &self.marks {
            let color = *color;
            chart.draw_series(pts.iter().map(move |&p| {
                EmptyElement::at(p)
                    + Circle::new((0, 0), 5, color.filled())
                    + Circle::new((0, 0), 5, BLACK.stroke_width(1))
            }))?;
        }
        draw_colorbar(&bar, (lo, hi), &self.levels, &self.z_desc)
    }
}

/// Figure 7 as a contour map.
pub(crate) fn figure7() -> Result<ContourPlot> {
    let grid = figure7_grid(181, 361)?;
    Ok(ContourPlot {
        title: "Figure 7: KBS rough approximation, θi = 45°, T/σ = 5: contours of L over (θr, φr)"
            .into(),
        subtitle: String::new(),
        x_desc: "θr, view angle from the surface normal (degrees)".into(),
        y_desc: "φr, azimuth from the plane of incidence (degrees)".into(),
        z_desc: "L / L_max".into(),
        size: (1000, 700),
        grid,
        levels: LEVELS.to_vec(),
        levels_label: "L / L_max = 0.05, 0.1, 0.2, …, 0.9".into(),
        marks: vec![(
            "mirror direction (45°, 0°)".into(),
            vec![(45.0, 0.0)],
            RGBColor(40, 110, 255),
        )],
    })
}

/// The names of the figures' files without the extension (each as `.png` and `.svg`).
pub(crate) const FIGURES: [&str; 4] = ["figure4", "figure5", "figure6", "figure7"];

/// Write Figures 4–7 into `dir` as PNG and SVG (`figure4.png`, `figure4.svg`, …, named
/// by [`FIGURES`]); the folder is created if needed. Returns the written paths.
pub(crate) fn write_all(dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|source| crate::error::Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let [f4, f5, f6, f7] = FIGURES;
    let mut paths = write_png_svg(&Figure4::new()?, dir, f4)?;
    paths.extend(write_png_svg(&figure5()?, dir, f5)?);
    paths.extend(write_png_svg(&figure6()?, dir, f6)?);
    paths.extend(write_png_svg(&figure7()?, dir, f7)?);
    Ok(paths)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn figure6_labels_reduce() {
        assert_eq!(reduce(4, 16), (1, 4));
        assert_eq!(reduce(6, 16), (3, 8));
    }

    #[test]
    fn figure5_peaks_are_at_the_marks() {
        let curves = figure5_curves(721).unwrap();
        for c in &curves[..5] {
            assert!(
                (c.peak().0 + 22.5).abs() <= 0.25,
                "{}: {:?}",
                c.label,
                c.peak()
            );
        }
        assert!((curves[5].peak().0 + 45.0).abs() <= 0.25);
    }
}
