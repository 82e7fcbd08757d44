//! Legends drawn outside the data: a column in a panel beside the chart (x–y charts, the
//! polar plot) or a row above it (contour maps), so that no legend box ever hides a point;
//! and a continuous colour scale with its colour bar for charts with more series than the
//! palette has colours.

use super::marks::arrow_glyph;
use super::stroke::{draw_polyline, Canvas, Pen};
use super::{font, DrawError};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// A point marker.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Marker {
    /// A filled circle of radius r.
    Filled,
    /// A circle's outline of radius r, 2 pixels wide, its inside left clear.
    Open,
    /// A filled triangle pointing up, one pixel larger than r each way.
    Triangle,
    /// A filled axis-aligned square, 2r pixels on a side.
    Square,
}

/// How a legend entry is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Glyph {
    /// A line of `width` pixels, dashed as (on, off) pixels when given.
    Line {
        /// The colour of the 26-pixel stroke drawn left of the label.
        color: RGBColor,
        /// The stroke's width in pixels; widths under 2 are drawn 2 wide.
        width: u32,
        /// (on, off) dash lengths in pixels; None: solid.
        dash: Option<(u32, u32)>,
    },
    /// A point marker of radius `r`.
    Point {
        /// The marker's fill (or outline, for [`Marker::Open`]) colour.
        color: RGBColor,
        /// The marker's shape, as drawn on the chart.
        marker: Marker,
        /// The marker's radius in pixels; radii under 3 are drawn 3 in the legend.
        r: u32,
    },
    /// An arrow: values beyond the chart's edge.
    Arrow {
        /// The colour of the 2-pixel, right-pointing arrow drawn left of the label.
        color: RGBColor,
    },
}

/// One legend line: its glyph and text.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Entry {
    /// The sample of the series' look drawn at the line's left (34 pixels with its gap).
    pub glyph: Glyph,
    /// The text after the glyph, one line in the legend font; the longest label sets the
    /// legend column's width.
    pub label: String,
}

/// Legend text size (pixels).
pub(crate) const LEGEND_FONT: f64 = 15.0;
/// Height of one legend line (pixels).
pub(crate) const LINE_H: u32 = 22;
/// Width of a glyph and the gap after it (pixels).
const GLYPH_W: i32 = 34;

/// The width (pixels) of the text `s` at `size`, from the bundled font's metrics (an
/// estimate of 0.6 em per character if the font cannot be measured). The font is
/// registered first, so a picture's layout is the same whether or not one was drawn before.
pub(crate) fn text_width(s: &str, size: f64) -> u32 {
    // An unregistered font measures nothing and would give the estimate instead; an error
    // here leaves the estimate, and the drawing itself reports it.
    let _ = super::ensure_font();
    font(size)
        .box_size(s)
        .map(|b| b.0)
        .unwrap_or((0.6 * size * s.chars().count() as f64) as u32)
}

/// The width (pixels) a column of `entries` needs, with its margins.
pub(crate) fn column_width(entries: &[Entry]) -> u32 {
    entries
        .iter()
        .map(|e| text_width(&e.label, LEGEND_FONT))
        .max()
        .map_or(0, |w| w + GLYPH_W as u32 + 28)
}

/// Draw a marker of radius `r` centred at pixel `c` of `area`.
pub(crate) fn draw_marker<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    c: (i32, i32),
    marker: Marker,
    r: u32,
    color: RGBColor,
) -> Result<(), DrawError<DB>> {
    let ri = r as i32;
    match marker {
        Marker::Filled => area.draw(&Circle::new(c, r, color.filled())),
        Marker::Open => area.draw(&Circle::new(c, r, color.stroke_width(2))),
        Marker::Triangle => area.draw(&Polygon::new(
            vec![
                (c.0, c.1 - ri - 1),
                (c.0 - ri - 1, c.1 + ri),
                (c.0 + ri + 1, c.1 + ri),
            ],
            color.filled(),
        )),
        Marker::Square => area.draw(&Rectangle::new(
            [(c.0 - ri, c.1 - ri), (c.0 + ri, c.1 + ri)],
            color.filled(),
        )),
    }
}

/// Draw `glyph` with its left end at pixel (x, y) of `area` (y the text's middle).
fn draw_glyph<DB: Canvas>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    glyph: Glyph,
) -> Result<(), DrawError<DB>> {
    match glyph {
        Glyph::Line { color, width, dash } => {
            // The same stroke as the chart's curves, on whole pixel rows (crisp): an odd
            // width centred on the row's middle, an even one on its top edge.
            let width = width.max(2);
            let pen = Pen {
                color,
                width: width as f64,
                dash: dash.map(|(on, off)| (on as f64, off as f64)),
            };
            let (x, y) = (x as f64, y as f64 + if width % 2 == 1 { 0.5 } else { 0.0 });
            draw_polyline(area, &[(x, y), (x + 26.0, y)], pen)
        }
        Glyph::Point { color, marker, r } => {
            draw_marker(area, (x + 13, y), marker, r.max(3), color)
        }
        Glyph::Arrow { color } => area.draw(&PathElement::new(
            arrow_glyph((x, y), 24),
            color.stroke_width(2),
        )),
    }
}

/// Draw `entries` as a column starting at pixel (x, y) of `area`; returns the y below the
/// last line.
pub(crate) fn draw_column<DB: Canvas>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    entries: &[Entry],
) -> Result<i32, DrawError<DB>> {
    let style = font(LEGEND_FONT)
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    let mut yy = y + LINE_H as i32 / 2;
    for e in entries {
        draw_glyph(area, (x, yy), e.glyph)?;
        area.draw_text(&e.label, &style, (x + GLYPH_W, yy))?;
        yy += LINE_H as i32;
    }
    Ok(yy - LINE_H as i32 / 2)
}

/// The rows (each a run of entries) that lay `entries` out across `width` pixels.
pub(crate) fn rows(entries: &[Entry], width: u32) -> Vec<Vec<Entry>> {
    let mut out: Vec<Vec<Entry>> = Vec::new();
    let mut used = 0;
    for e in entries {
        let w = text_width(&e.label, LEGEND_FONT) + GLYPH_W as u32 + 24;
        if out.is_empty() || used + w > width {
            out.push(Vec::new());
            used = 0;
        }
        used += w;
        out.last_mut().expect("a row").push(e.clone());
    }
    out
}

/// Draw `entries` in rows across `area` (as laid out by [`rows`]), centred.
pub(crate) fn draw_rows<DB: Canvas>(
    area: &DrawingArea<DB, Shift>,
    entries: &[Entry],
) -> Result<(), DrawError<DB>> {
    let (w, _) = area.dim_in_pixel();
    let style = font(LEGEND_FONT)
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    for (k, row) in rows(entries, w).iter().enumerate() {
        let widths: Vec<i32> = row
            .iter()
            .map(|e| (text_width(&e.label, LEGEND_FONT) + GLYPH_W as u32 + 24) as i32)
            .collect();
        let mut x = (w as i32 - widths.iter().sum::<i32>()) / 2;
        let y = k as i32 * LINE_H as i32 + LINE_H as i32 / 2;
        for (e, dw) in row.iter().zip(widths) {
            draw_glyph(area, (x, y), e.glyph)?;
            area.draw_text(&e.label, &style, (x + GLYPH_W, y))?;
            x += dw;
        }
    }
    Ok(())
}

/// A continuous colour scale for lines and points on white (viridis, its darkest 88 %:
/// the palest yellow is left out); `t` clamped to [0, 1], NaN gives the first colour.
pub(crate) fn sequential_color(t: f64) -> RGBColor {
    const STOPS: [[f64; 3]; 5] = [
        [68.0, 1.0, 84.0],
        [59.0, 82.0, 139.0],
        [33.0, 145.0, 140.0],
        [94.0, 201.0, 98.0],
        [200.0, 215.0, 40.0],
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let f = t * (STOPS.len() - 1) as f64;
    let k = (f.floor() as usize).min(STOPS.len() - 2);
    let u = f - k as f64;
    let mix = |j: usize| (STOPS[k][j] + u * (STOPS[k + 1][j] - STOPS[k][j])).round() as u8;
    RGBColor(mix(0), mix(1), mix(2))
}

/// What a colour bar shows: the quantity's name, its range, and the values of the series
/// (marked on the bar).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ColorKey {
    /// The quantity's name and unit, written above the bar after `colour: `.
    pub label: String,
    /// The values (the quantity's unit) at the scale's ends: `range.0` dark purple at the
    /// bar's bottom, `range.1` yellow-green at its top; values outside take the end colours.
    pub range: (f64, f64),
    /// The series' values, each marked by a short tick on the bar's left edge; empty: no
    /// marks.
    pub values: Vec<f64>,
}

impl ColorKey {
    /// The labelled ticks of the colour bar: nice numbers ([`super::ticks::linear_ticks`])
    /// inside the range, about five (the range's ends when it is a single value).
    pub(crate) fn ticks(&self) -> Vec<f64> {
        let (lo, hi) = self.range;
        let t = super::ticks::linear_ticks(lo, hi, 5);
        if t.is_empty() {
            vec![lo]
        } else {
            t
        }
    }

    /// The colour of value `v` on this key.
    pub(crate) fn color(&self, v: f64) -> RGBColor {
        let (lo, hi) = self.range;
        sequential_color(if hi > lo { (v - lo) / (hi - lo) } else { 0.5 })
    }
}

/// The height (pixels) a colour bar takes in a legend panel.
pub(crate) const COLORBAR_H: u32 = 256;

/// Draw the colour bar of `key` in a legend panel at pixel (x, y): its name, a vertical
/// bar, and a labelled tick at each series' value.
pub(crate) fn draw_color_key<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (x, y): (i32, i32),
    key: &ColorKey,
) -> Result<(), DrawError<DB>> {
    let title = font(LEGEND_FONT)
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Top));
    area.draw_text(&format!("colour: {}", key.label), &title, (x, y))?;
    let (top, h, w) = (y + 26, COLORBAR_H as i32 - 60, 22);
    let (lo, hi) = key.range;
    let span = if hi > lo { hi - lo } else { 1.0 };
    let to_y = |v: f64| top + h - ((v - lo) / span * h as f64).round() as i32;
    for k in 0..h {
        let v = lo + span * (h - k) as f64 / h as f64;
        area.draw(&Rectangle::new(
            [(x, top + k), (x + w, top + k + 1)],
            key.color(v).filled(),
        ))?;
    }
    area.draw(&Rectangle::new(
        [(x, top), (x + w, top + h)],
        RGBColor(120, 120, 120).stroke_width(1),
    ))?;
    // The values of the series as short marks on the left edge; labels at nice values
    // on the right.
    for &v in &key.values {
        let yy = to_y(v);
        area.draw(&PathElement::new(
            vec![(x - 5, yy), (x, yy)],
            BLACK.stroke_width(1),
        ))?;
    }
    let label = font(13.0)
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    for v in key.ticks() {
        let yy = to_y(v);
        area.draw(&PathElement::new(
            vec![(x + w, yy), (x + w + 5, yy)],
            BLACK.stroke_width(1),
        ))?;
        area.draw_text(&super::fmt_tick(v), &label, (x + w + 8, yy))?;
    }
    let note = font(12.0)
        .color(&RGBColor(90, 90, 90))
        .pos(Pos::new(HPos::Left, VPos::Top));
    if !key.values.is_empty() {
        for (k, line) in ["left marks: the", "values drawn"].iter().enumerate() {
            area.draw_text(line, &note, (x - 6, top + h + 4 + 14 * k as i32))?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn colour_bar_ticks_are_nice_numbers() {
        // The CUReT incidence angles: the values themselves are uneven; the labelled ticks
        // are multiples of a 1-2-2.5-5 step.
        let key = ColorKey {
            label: "θi (degrees)".into(),
            range: (0.0, 77.8),
            values: vec![0.0, 11.25, 22.5, 33.75, 45.0, 50.24, 56.25, 64.76, 77.8],
        };
        assert_eq!(key.ticks(), vec![0.0, 20.0, 40.0, 60.0]);
        let key = ColorKey {
            range: (0.351, 1.064),
            ..key
        };
        assert_eq!(key.ticks(), vec![0.4, 0.6, 0.8, 1.0]);
    }

    #[test]
    fn sequential_scale_ends_and_is_monotone_in_lightness() {
        assert_eq!(sequential_color(0.0), RGBColor(68, 1, 84));
        assert_eq!(sequential_color(1.0), RGBColor(200, 215, 40));
        let light = |c: RGBColor| c.0 as u32 + c.1 as u32 + c.2 as u32;
        let ls: Vec<u32> = (0..=10)
            .map(|k| light(sequential_color(k as f64 / 10.0)))
            .collect();
        assert!(ls.windows(2).all(|w| w[1] >= w[0]), "{ls:?}");
    }
}
