//! The picture of a design ([`crate::design`]): every candidate geometry coloured by what
//! it alone would add to the measured data (on a log scale, relative to the best), the
//! chosen ones ringed, those out of the instrument's dynamic range in grey.
//!
//! Left: the viewing direction on the projected hemisphere (x = sin θr cos φr,
//! y = sin θr |sin φr|: φr and −φr, which an isotropic surface cannot tell apart, share a
//! point; φr = 0 the specular side, to the right), each point the best over θi.
//! Right: θi against the signed θr (< 0 on the back side, |φr| > 90°), each point the best
//! over φr.

use super::legend::{draw_color_key, ColorKey, COLORBAR_H};
use super::{font, wrap, DrawError, Picture};
use crate::design::{target_label, Design, Scene};
use crate::error::Result;
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;
use std::collections::BTreeMap;

/// The stem of the picture's files (`design.png`, `design.svg`).
pub(crate) const PICTURE: &str = "design";

/// Decades of gain the colour scale spans below the best candidate.
const DECADES: f64 = 4.0;

/// One point of a panel: its position, its colour value (log10 gain relative to the best,
/// in [−4, 0]: the colour scale spans four decades; None: out of reach), and whether it is
/// chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Point {
    /// Position in the panel's data coordinates: on the projected hemisphere
    /// (sin θr cos φr, sin θr |sin φr|), unitless, the two sides of the plane of incidence
    /// folded together; in the incidence panel (θi, signed θr) in degrees, θr negative
    /// where |φr| > 90°.
    pub xy: (f64, f64),
    /// log10 of the gain relative to the best reachable candidate, clamped to [−4, 0] (0:
    /// the best; −4 also for no gain); None: out of the instrument's dynamic range, drawn
    /// grey.
    pub level: Option<f64>,
    /// Whether the design chose this geometry (ringed in red); for a merged position, true
    /// if any geometry there was chosen.
    pub chosen: bool,
}

/// The design's picture, its data computed when built.
#[derive(Debug, Clone)]
pub(crate) struct DesignPlot {
    /// The first title line: how many geometries were chosen, for which target, model and
    /// wavelength.
    pub title: String,
    /// The second title line: the target's relative standard error before → after the
    /// chosen geometries.
    pub subtitle: String,
    /// The design's sentence, in lines that fit above the hemisphere.
    pub sentence: Vec<String>,
    /// The projected hemisphere (best over θi).
    pub hemisphere: Vec<Point>,
    /// θi against signed θr (best over φr).
    pub incidence: Vec<Point>,
    /// The colour bar drawn right of the panels: log10 gain relative to the best, over
    /// [−4, 0].
    pub key: ColorKey,
}

/// Merge points at the same position: the best level, chosen if any is.
fn merge(points: impl Iterator<Item = Point>) -> Vec<Point> {
    let mut at: BTreeMap<(i64, i64), Point> = BTreeMap::new();
    for p in points {
        let k = ((p.xy.0 * 1e6).round() as i64, (p.xy.1 * 1e6).round() as i64);
        at.entry(k)
            .and_modify(|q| {
                q.level = match (q.level, p.level) {
                    (Some(a), Some(b)) => Some(a.max(b)),
                    (a, b) => a.or(b),
                };
                q.chosen |= p.chosen;
            })
            .or_insert(p);
    }
    at.into_values().collect()
}

impl DesignPlot {
    /// The picture of `d` for `scene`.
    pub(crate) fn new(d: &Design, scene: &Scene) -> Result<DesignPlot> {
        let best = d
            .candidates
            .iter()
            .filter(|c| c.reachable && c.gain.is_finite())
            .fold(0.0f64, |m, c| m.max(c.gain));
        let level = |c: &crate::design::Candidate| -> Option<f64> {
            if !c.reachable {
                return None;
            }
            Some(if best > 0.0 && c.gain > 0.0 {
                (c.gain / best).log10().max(-DECADES)
            } else {
                -DECADES
            })
        };
        let point = |c: &crate::design::Candidate, xy| Point {
            xy,
            level: level(c),
            chosen: c.chosen,
        };
        let hemisphere = merge(d.candidates.iter().map(|c| {
            let (tr, phi) = (c.angles[1].to_radians(), c.angles[2].to_radians());
            point(c, (tr.sin() * phi.cos(), tr.sin() * phi.sin().abs()))
        }));
        let incidence = merge(d.candidates.iter().map(|c| {
            let signed = if c.angles[2].abs() > 90.0 {
                -c.angles[1]
            } else {
                c.angles[1]
            };
            point(c, (c.angles[0], signed))
        }));
        let unit = scene.unit.as_deref().unwrap_or("");
        Ok(DesignPlot {
            title: format!(
                "{} next geometries for {} — {} at λ = {}{}{}",
                d.chosen.len(),
                target_label(&d.target),
                scene.model.name(),
                super::fmt_num(scene.wavelength),
                if unit.is_empty() { "" } else { " " },
                unit
            ),
            subtitle: format!(
                "{}: {} → {} (relative standard error, linearised)",
                target_label(&d.target),
                se_words(d.target_before),
                se_words(d.target_after)
            ),
            sentence: wrap(&d.sentence, SENTENCE_WIDTH),
            hemisphere,
            incidence,
            key: ColorKey {
                label: "log₁₀ gain / best".into(),
                range: (-DECADES, 0.0),
                values: Vec::new(),
            },
        })
    }
}

/// Characters per line of the sentence drawn above the hemisphere.
const SENTENCE_WIDTH: usize = 62;

fn se_words(r: Option<f64>) -> String {
    match r {
        Some(r) if r <= 1.0 => crate::design::percent(r),
        Some(_) => "> ±100 %".into(),
        None => "not determined".into(),
    }
}

const OUT_OF_REACH: RGBColor = RGBColor(215, 215, 215);

/// Draw one panel's points: out of reach first, then by level, the chosen ringed on top.
fn draw_points<DB: DrawingBackend>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>,
    points: &[Point],
    key: &ColorKey,
    radius: i32,
) -> std::result::Result<(), DrawError<DB>> {
    let mut order: Vec<&Point> = points.iter().collect();
    order.sort_by(|a, b| {
        let l = |p: &Point| p.level.unwrap_or(-1e9);
        l(a).total_cmp(&l(b))
    });
    chart.draw_series(order.iter().map(|p| {
        let color = p.level.map_or(OUT_OF_REACH, |l| key.color(l));
        Circle::new(p.xy, radius, color.filled())
    }))?;
    chart.draw_series(
        points
            .iter()
            .filter(|p| p.chosen)
            .map(|p| Circle::new(p.xy, radius + 4, RGBColor(220, 30, 30).stroke_width(2))),
    )?;
    Ok(())
}

impl Picture for DesignPlot {
    fn size(&self) -> (u32, u32) {
        (1300, 620)
    }

    fn draw<DB: super::stroke::Canvas>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), DrawError<DB>> {
        let root = super::xy::draw_titles(root, &self.title, &self.subtitle)?;
        let (root, legend) = root.split_horizontally(1090);
        let (left, right) = root.split_horizontally(540);
        // Equal scales: the plotting area is (w − 2·16 − 60) px wide; its height, 1.1/2.1
        // of that, sits at the bottom of the panel.
        let (w, h) = left.dim_in_pixel();
        let plot_h = (f64::from(w) - 92.0).max(1.0) * 1.1 / 2.1;
        let top = (f64::from(h) - 82.0 - plot_h).max(0.0) as i32 + 16;
        let mut hemi = ChartBuilder::on(&left)
            .caption("viewing direction (each point: the best θi)", font(15.0))
            .margin(16)
            .margin_top(top)
            .x_label_area_size(50)
            .y_label_area_size(60)
            .build_cartesian_2d(-1.05..1.05, -0.05..1.05)?;
        hemi.configure_mesh()
            .disable_mesh()
            .x_desc("sin θr cos φr   (φr = 0: specular side)")
            .y_desc("sin θr |sin φr|")
            .label_style(font(14.0))
            .axis_desc_style(font(15.0))
            .x_label_formatter(&|v| super::fmt_tick(*v))
            .y_label_formatter(&|v| super::fmt_tick(*v))
            .draw()?;
        let rim: Vec<(f64, f64)> = (0..=180)
            .map(|d| {
                (
                    f64::from(d).to_radians().cos(),
                    f64::from(d).to_radians().sin(),
                )
            })
            .collect();
        hemi.draw_series(std::iter::once(PathElement::new(
            rim,
            RGBColor(150, 150, 150).stroke_width(1),
        )))?;
        draw_points(&mut hemi, &self.hemisphere, &self.key, 4)?;
        let text = font(14.0).color(&BLACK);
        for (k, line) in self.sentence.iter().enumerate() {
            left.draw_text(line, &text, (24, 12 + 20 * k as i32))?;
        }
        let mut inc = ChartBuilder::on(&right)
            .caption("incidence and view (each point: the best φr)", font(15.0))
            .margin(16)
            .x_label_area_size(50)
            .y_label_area_size(60)
            .build_cartesian_2d(-2.0..92.0, -92.0..92.0)?;
        inc.configure_mesh()
            .disable_mesh()
            .x_desc("θi (degrees)")
            .y_desc("signed θr (degrees; < 0: back side)")
            .label_style(font(14.0))
            .axis_desc_style(font(15.0))
            .x_label_formatter(&|v| super::fmt_tick(*v))
            .y_label_formatter(&|v| super::fmt_tick(*v))
            .draw()?;
        draw_points(&mut inc, &self.incidence, &self.key, 4)?;
        draw_color_key(&legend, (10, 40), &self.key)?;
        let note = font(14.0).color(&BLACK);
        let y0 = 40 + COLORBAR_H as i32 + 10;
        legend.draw(&Circle::new(
            (18, y0),
            7,
            RGBColor(220, 30, 30).stroke_width(2),
        ))?;
        legend.draw_text("chosen", &note, (32, y0 - 8))?;
        legend.draw(&Circle::new((18, y0 + 26), 5, OUT_OF_REACH.filled()))?;
        legend.draw_text("out of reach", &note, (32, y0 + 18))?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_breaks_at_spaces_within_the_width() {
        assert_eq!(wrap("aa bb cc dd", 5), vec!["aa bb", "cc dd"]);
        assert_eq!(wrap("abcdefg h", 3), vec!["abcdefg", "h"]);
        assert!(wrap("", 5).is_empty());
    }
}
