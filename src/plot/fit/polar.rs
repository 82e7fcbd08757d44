//! The fitted lobe in the plane of incidence as a polar plot.

use super::{
    busiest, checked_groups, eval_group, plane_curve_samples, plane_samples, signed_theta_r_deg,
    FitPlotInput,
};
use crate::error::Result;
use crate::plot::legend::{Entry, Glyph};
use crate::plot::marks::Beyond;
use crate::plot::stroke::{draw_data_polyline, Pen, PixelMap};
use crate::plot::xy::Kind;
use crate::plot::{fmt_num, font, series_color, DrawError, Picture};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

/// The fitted lobe in the plane of incidence at one θi, in polar form: radius L / L_max at
/// the signed view angle from the normal.
#[derive(Debug, Clone)]
pub(crate) struct PolarPlot {
    /// The first title line: the fit's title, θi and (for a joint fit) the channel.
    pub title: String,
    /// A second title line; empty for none.
    pub subtitle: String,
    /// The incidence angle shown, radians; the source (−θi) and mirror (+θi) directions are
    /// drawn as dashed spokes.
    pub theta_i: f64,
    /// (signed θr in degrees, L / L_max) of the fitted model.
    pub curve: Vec<(f64, f64)>,
    /// (signed θr in degrees, measured / L_max) of the in-plane samples.
    pub measured: Vec<(f64, f64)>,
    /// The fitted maximum used to normalise, in data units.
    pub l_max: f64,
}

/// The radius (in L / L_max) of the polar plot's rim: values beyond it are drawn there as
/// arrows pointing outwards, counted in the legend.
pub(crate) const POLAR_RIM: f64 = 1.15;
/// The radius of the spoke labels (0°, ±30°, …): just outside the L_max ring, inside the
/// arrows at the rim (the 60° label touched them).
const POLAR_LABEL_R: f64 = 1.035;
/// The length (pixels) of the rim arrows: with about 340 px per unit of L / L_max they
/// reach in to r ≈ 1.09, clear of the spoke labels.
const POLAR_ARROW_PX: f64 = 20.0;

const POLAR_SOURCE: RGBColor = RGBColor(200, 120, 0);
const POLAR_MIRROR: RGBColor = RGBColor(120, 120, 120);

impl PolarPlot {
    /// The measured points beyond [`POLAR_RIM`]: (how many, the largest L / L_max).
    #[cfg(test)]
    pub(crate) fn clipped(&self) -> (usize, f64) {
        let b = Beyond::above(self.measured.iter().map(|p| p.1), POLAR_RIM);
        (b.count, b.worst)
    }

    /// The legend's lines (drawn in rows above the plot).
    pub(crate) fn legend_entries(&self) -> Vec<Entry> {
        let line = |color, dash| Glyph::Line {
            color,
            width: 2,
            dash,
        };
        let ti = fmt_num(self.theta_i.to_degrees());
        let mut out = vec![
            Entry {
                glyph: line(POLAR_SOURCE, Some((8, 5))),
                label: format!("source direction (−{ti}°)"),
            },
            Entry {
                glyph: line(POLAR_MIRROR, Some((8, 5))),
                label: format!("mirror direction ({ti}°)"),
            },
            Entry {
                glyph: line(series_color(0), None),
                label: format!("fitted model (L_max = {})", fmt_num(self.l_max)),
            },
            Entry {
                glyph: Kind::Points(4).glyph(series_color(3)),
                label: "measured (in-plane samples)".into(),
            },
        ];
        let b = Beyond::above(self.measured.iter().map(|p| p.1), POLAR_RIM);
        if b.count > 0 {
            out.push(Entry {
                glyph: Glyph::Arrow {
                    color: series_color(3),
                },
                label: format!(
                    "{}, drawn at {POLAR_RIM}",
                    b.label("beyond the rim", "× L_max")
                ),
            });
        }
        out
    }
}

/// The polar plot of the fit at the θi with the most samples.
pub(crate) fn polar_plot(input: &FitPlotInput) -> Result<PolarPlot> {
    let gs = checked_groups(input)?;
    let geo = input.geo;
    let g = busiest(&gs);
    let (xs, samples) = plane_curve_samples(g.theta_i, 361);
    let ys = eval_group(input, g, &samples)?;
    let l_max = ys
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(0.0, f64::max);
    let norm = if l_max > 0.0 { 1.0 / l_max } else { 0.0 };
    let (idx, _) = plane_samples(geo, g);
    let measured = idx
        .iter()
        .map(|&k| {
            (
                signed_theta_r_deg(geo.theta_r[k], geo.phi_r[k]),
                input.measured[k] * norm,
            )
        })
        .collect();
    Ok(PolarPlot {
        title: format!(
            "{} — fitted lobe in the plane of incidence, θi = {}°{}",
            input.title,
            fmt_num(g.theta_i.to_degrees()),
            input.channel_note(g.channel)
        ),
        subtitle: input.subtitle.clone(),
        theta_i: g.theta_i,
        curve: xs.into_iter().zip(ys.iter().map(|v| v * norm)).collect(),
        measured,
        l_max,
    })
}

fn polar_xy(theta_deg: f64, r: f64) -> (f64, f64) {
    let t = theta_deg.to_radians();
    (r * t.sin(), r * t.cos())
}

impl Picture for PolarPlot {
    fn size(&self) -> (u32, u32) {
        (900, 620)
    }

    fn draw<DB: crate::plot::stroke::Canvas>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError<DB>> {
        let root = crate::plot::xy::draw_titles(root, &self.title, &self.subtitle)?;
        let (w0, _) = root.dim_in_pixel();
        let entries = self.legend_entries();
        let rows = crate::plot::legend::rows(&entries, w0.saturating_sub(40)).len() as u32;
        let (top, root) = root.split_vertically(rows * crate::plot::legend::LINE_H + 4);
        crate::plot::legend::draw_rows(&top, &entries)?;
        let (w, h) = root.dim_in_pixel();
        // Equal scales on both axes: the plotting area is (w − 2·16 − 70) × (h − 2·16 − 55).
        let (pw, ph) = (w as f64 - 102.0, h as f64 - 87.0);
        let x_half = 1.18;
        let y_span = 2.0 * x_half * ph / pw;
        let y0 = -0.08;
        let mut chart = ChartBuilder::on(&root)
            .margin(16)
            .x_label_area_size(55)
            .y_label_area_size(70)
            .build_cartesian_2d(-x_half..x_half, y0..y0 + y_span)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_desc("(L / L_max) · sin θr  (signed θr; < 0 toward the source)")
            .y_desc("(L / L_max) · cos θr")
            .x_label_formatter(&|v| crate::plot::fmt_tick(*v))
            .y_label_formatter(&|v| crate::plot::fmt_tick(*v))
            .label_style(font(14.0))
            .axis_desc_style(font(16.0))
            .draw()?;
        self.draw_grid(&mut chart)?;
        let map = PixelMap::of_linear(&chart);
        let ti = self.theta_i.to_degrees();
        for (angle, color) in [(-ti, POLAR_SOURCE), (ti, POLAR_MIRROR)] {
            let ray = [(0.0, 0.0), polar_xy(angle, 1.0)];
            draw_data_polyline(
                chart.plotting_area(),
                &map,
                &ray,
                Pen::dashed(color, 2.0, 8.0, 5.0),
            )?;
        }
        let curve: Vec<(f64, f64)> = self
            .curve
            .iter()
            .filter(|p| p.1.is_finite())
            .map(|&(t, r)| polar_xy(t, r.clamp(0.0, POLAR_RIM)))
            .collect();
        draw_data_polyline(
            chart.plotting_area(),
            &map,
            &curve,
            Pen::solid(series_color(0), 2.0),
        )?;
        let red = series_color(3);
        chart.draw_series(
            self.measured
                .iter()
                .filter(|p| p.1.is_finite() && p.1 <= POLAR_RIM)
                .map(|&(t, r)| Circle::new(polar_xy(t, r.max(0.0)), 4, red.filled())),
        )?;
        // Each point beyond the rim: a radial arrow ending at the rim (equal scales, so the
        // radial direction on screen is (sin θ, −cos θ)).
        chart.draw_series(
            self.measured
                .iter()
                .filter(|p| p.1.is_finite() && p.1 > POLAR_RIM)
                .map(|&(t, _)| {
                    let a = t.to_radians();
                    EmptyElement::at(polar_xy(t, POLAR_RIM))
                        + PathElement::new(
                            crate::plot::marks::arrow((a.sin(), -a.cos()), POLAR_ARROW_PX, 8.0),
                            red.stroke_width(2),
                        )
                }),
        )?;
        Ok(())
    }
}

impl PolarPlot {
    /// The rings at L / L_max = 0.25 … 1 and the spokes every 15° (labelled every 30°).
    fn draw_grid<DB: crate::plot::stroke::Canvas>(
        &self,
        chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    ) -> std::result::Result<(), DrawError<DB>> {
        let grey = Pen::solid(RGBColor(200, 200, 200), 1.0);
        let map = PixelMap::of_linear(chart);
        for r in [0.25, 0.5, 0.75, 1.0] {
            let arc: Vec<(f64, f64)> = (0..=180).map(|d| polar_xy(d as f64 - 90.0, r)).collect();
            draw_data_polyline(chart.plotting_area(), &map, &arc, grey)?;
        }
        for d in (-90..=90).step_by(15) {
            let spoke = [(0.0, 0.0), polar_xy(d as f64, 1.0)];
            draw_data_polyline(chart.plotting_area(), &map, &spoke, grey)?;
            if d % 30 == 0 {
                let p = polar_xy(d as f64, POLAR_LABEL_R);
                chart.draw_series(std::iter::once(Text::new(
                    format!("{d}°"),
                    p,
                    font(13.0).color(&RGBColor(100, 100, 100)).pos(
                        plotters::style::text_anchor::Pos::new(
                            plotters::style::text_anchor::HPos::Center,
                            plotters::style::text_anchor::VPos::Center,
                        ),
                    ),
                )))?;
            }
        }
        Ok(())
    }
}
