//! A general x–y chart (curves, points, reference lines, point labels), each axis linear or
//! logarithmic, with its legend in a panel to the right of the chart (never over the data):
//! Figures 5 and 6, the fit plots and the work-precision plot are built from it.
//!
//! Honest by construction: curves are drawn at sub-pixel positions
//! ([`super::stroke`]), lines are clipped at the chart's edges (interpolated, not
//! clamped), measured points above the y range are drawn as arrows at the top edge and
//! those below it (or at y ≤ 0 on a logarithmic axis) as arrows at the bottom edge, both
//! counted in the legend, logarithmic axes get labelled ticks for any range
//! ([`super::ticks::log_ticks`]), and a chart with more series than the palette holds can
//! colour them by a continuous scale with a colour bar ([`super::legend::ColorKey`]).

use super::legend::{self, ColorKey, Entry, Glyph, Marker};
use super::marks::{self, Beyond, Rect};
use super::stroke::{draw_data_polyline, Canvas, Pen, PixelMap};
use super::ticks::log_ticks;
use super::{font, DrawError, Picture};
use plotters::coord::ranged1d::{Ranged, ValueFormatter};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Kind {
    /// A solid line of the given width.
    Line(u32),
    /// A dashed line (8 on, 5 off) of the given width.
    Dashed(u32),
    /// A dotted line (2 on, 4 off).
    Dotted(u32),
    /// A long-dashed line (16 on, 6 off).
    LongDashed(u32),
    /// Filled circles of the given radius.
    Points(u32),
    /// Open circles of the given radius.
    OpenPoints(u32),
    /// Filled triangles.
    Triangles(u32),
    /// Filled squares.
    Squares(u32),
}

impl Kind {
    /// The four line styles, in order (one per wavelength when colour shows θi).
    pub(crate) const LINES: [fn(u32) -> Kind; 4] =
        [Kind::Line, Kind::Dashed, Kind::Dotted, Kind::LongDashed];
    /// The four point markers, in the same order.
    pub(crate) const POINTS: [fn(u32) -> Kind; 4] = [
        Kind::Points,
        Kind::OpenPoints,
        Kind::Triangles,
        Kind::Squares,
    ];

    /// The legend glyph of this kind in `color`.
    pub(crate) fn glyph(self, color: RGBColor) -> Glyph {
        let line = |width, dash| Glyph::Line { color, width, dash };
        let point = |marker, r| Glyph::Point { color, marker, r };
        match self {
            Kind::Line(w) => line(w, None),
            Kind::Dashed(w) => line(w, Some((8, 5))),
            Kind::Dotted(w) => line(w, Some((2, 4))),
            Kind::LongDashed(w) => line(w, Some((16, 6))),
            Kind::Points(r) => point(Marker::Filled, r),
            Kind::OpenPoints(r) => point(Marker::Open, r),
            Kind::Triangles(r) => point(Marker::Triangle, r),
            Kind::Squares(r) => point(Marker::Square, r),
        }
    }

    fn is_points(self) -> bool {
        matches!(self.glyph(BLACK), Glyph::Point { .. })
    }
}

/// One series of an [`XyPlot`].
#[derive(Debug, Clone)]
pub(crate) struct Series {
    /// Legend text; `None` keeps the series out of the legend.
    pub label: Option<String>,
    /// The colour of its line or markers (and of its arrows at the top and bottom edges)
    /// and of its legend glyph.
    pub color: RGBColor,
    /// Line (with its dash pattern) or marker shape, with its width or radius in pixels.
    pub kind: Kind,
    /// (x, y) in data units. A line joins them in this order, cut at the axes' ends and
    /// broken at non-finite values; markers outside the x range are not drawn, those above
    /// the y range are arrows at the top edge, those below it (or at y ≤ 0 on a logarithmic
    /// axis) arrows at the bottom edge.
    pub points: Vec<(f64, f64)>,
}

/// A text label beside a data point (placed so that labels do not overlap).
#[derive(Debug, Clone)]
pub(crate) struct Annotation {
    /// The labelled point, in data units; the label goes beside it, joined by a leader
    /// line when it had to move away.
    pub at: (f64, f64),
    /// The label, one line at 13 pixels.
    pub text: String,
    /// The colour of the text (and, paler, of its leader line).
    pub color: RGBColor,
}

/// An x–y chart.
#[derive(Debug, Clone)]
pub(crate) struct XyPlot {
    /// The first title line, centred at the top; its font shrinks (21 to 12 pixels) to fit
    /// the width.
    pub title: String,
    /// A second title line (the fit's status); empty for none.
    pub subtitle: String,
    /// The x axis label, under the axis: the quantity and its unit.
    pub x_desc: String,
    /// The y axis label, beside the axis: the quantity and its unit.
    pub y_desc: String,
    /// Size of the chart in pixels; the legend panel is added to the right of it.
    pub size: (u32, u32),
    /// The x axis' left and right ends, in data units; lines are cut there and points
    /// beyond them are not drawn.
    pub x_range: (f64, f64),
    /// The y axis' bottom and top ends, in data units; lines are cut there, points beyond
    /// either end are drawn as arrows at that edge and counted in the legend
    /// ([`XyPlot::above_top`], [`XyPlot::below_bottom`]).
    pub y_range: (f64, f64),
    /// Logarithmic x axis (x_range must then be positive; points at x ≤ 0 are dropped).
    pub log_x: bool,
    /// Logarithmic y axis (y_range must then be positive; values ≤ 0 are dropped).
    pub log_y: bool,
    /// The curves and point sets, drawn in this order (later ones on top), after the
    /// reference lines.
    pub series: Vec<Series>,
    /// Horizontal reference lines (thin grey).
    pub hlines: Vec<f64>,
    /// Vertical reference lines with a short label at the top.
    pub vlines: Vec<(f64, String)>,
    /// Legend lines not tied to one series (styles shared by several).
    pub legend_extra: Vec<Entry>,
    /// The continuous colour scale of the series, shown as a colour bar in the legend.
    pub color_key: Option<ColorKey>,
    /// Labels beside points.
    pub annotations: Vec<Annotation>,
}

/// Where the parts of an [`XyPlot`] go, in pixels of the whole picture.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct XyLayout {
    /// The chart: axes, labels and the data area.
    pub chart: Rect,
    /// The legend panel (right of the chart), if there is a legend.
    pub legend: Option<Rect>,
}

impl XyPlot {
    /// An empty chart with the default size (900×600), linear axes.
    pub(crate) fn new(
        title: impl Into<String>,
        x_desc: impl Into<String>,
        y_desc: impl Into<String>,
    ) -> Self {
        XyPlot {
            title: title.into(),
            subtitle: String::new(),
            x_desc: x_desc.into(),
            y_desc: y_desc.into(),
            size: (900, 600),
            x_range: (0.0, 1.0),
            y_range: (0.0, 1.0),
            log_x: false,
            log_y: false,
            series: Vec::new(),
            hlines: Vec::new(),
            vlines: Vec::new(),
            legend_extra: Vec::new(),
            color_key: None,
            annotations: Vec::new(),
        }
    }

    /// Set the y range to cover every finite (positive, for a log axis) y value, with a
    /// margin; keeps the current range if there is none.
    pub(crate) fn fit_y_range(&mut self) {
        let ys = self
            .series
            .iter()
            .flat_map(|s| s.points.iter().map(|p| p.1))
            .chain(self.hlines.iter().copied())
            .filter(|y| y.is_finite() && (!self.log_y || *y > 0.0));
        let (lo, hi) = ys.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), y| {
            (a.min(y), b.max(y))
        });
        if !(lo.is_finite() && hi.is_finite()) {
            return;
        }
        if self.log_y {
            let (lo, hi) = if hi > lo {
                (lo, hi)
            } else {
                (lo / 2.0, hi * 2.0)
            };
            let pad = (hi / lo).powf(0.05);
            self.y_range = (lo / pad, hi * pad);
        } else {
            let span = if hi > lo { hi - lo } else { hi.abs().max(1.0) };
            self.y_range = (lo - 0.05 * span, hi + 0.08 * span);
        }
    }

    /// The y values of the measured points (point series) within the x range.
    fn measured_in_x_range(&self) -> impl Iterator<Item = f64> + '_ {
        self.series
            .iter()
            .filter(|s| s.kind.is_points())
            .flat_map(|s| s.points.iter())
            .filter(|p| p.0 >= self.x_range.0 && p.0 <= self.x_range.1)
            .map(|p| p.1)
    }

    /// The measured points (point series) above the y range: drawn as arrows at the top.
    pub(crate) fn above_top(&self) -> Beyond {
        Beyond::above(self.measured_in_x_range(), self.y_range.1)
    }

    /// The measured points (point series, within the x range) below the y range, or at
    /// y ≤ 0 on a logarithmic axis: drawn as arrows at the bottom edge. `worst` is the
    /// smallest of them.
    pub(crate) fn below_bottom(&self) -> Beyond {
        // On a logarithmic axis y ≤ 0 lies below any bottom it can have.
        let bottom = if self.log_y {
            self.y_range.0.max(f64::MIN_POSITIVE)
        } else {
            self.y_range.0
        };
        Beyond::below(self.measured_in_x_range(), bottom)
    }

    /// The legend's lines: the labelled series, the extra lines, and the arrows' counts.
    pub(crate) fn legend_entries(&self) -> Vec<Entry> {
        let mut out: Vec<Entry> = self
            .series
            .iter()
            .filter_map(|s| {
                s.label.as_ref().map(|l| Entry {
                    glyph: s.kind.glyph(s.color),
                    label: l.clone(),
                })
            })
            .collect();
        out.extend(self.legend_extra.iter().cloned());
        let b = self.above_top();
        if b.count > 0 {
            out.push(Entry {
                glyph: Glyph::Arrow {
                    color: RGBColor(60, 60, 60),
                },
                label: b.label("above the top", ""),
            });
        }
        let b = self.below_bottom();
        if b.count > 0 {
            out.push(Entry {
                glyph: Glyph::Arrow {
                    color: RGBColor(60, 60, 60),
                },
                label: b.label("below the bottom", ""),
            });
        }
        out
    }

    /// The legend panel's width for these entries (0 without a legend).
    fn panel_width(&self, entries: &[Entry]) -> u32 {
        let key = self.color_key.as_ref().map_or(0, |k| {
            legend::text_width(&format!("colour: {}", k.label), legend::LEGEND_FONT) + 24
        });
        legend::column_width(entries)
            .max(key)
            .max(if self.color_key.is_some() { 130 } else { 0 })
    }

    /// The layout in a picture of `w` × `h` pixels.
    pub(crate) fn layout_in(&self, w: u32, h: u32) -> XyLayout {
        let panel = self.panel_width(&self.legend_entries()).min(w / 2);
        let top = titles_height(&self.title, &self.subtitle, w);
        let chart = Rect {
            x: 0.0,
            y: top as f64,
            w: (w - panel) as f64,
            h: h.saturating_sub(top) as f64,
        };
        let legend = (panel > 0).then_some(Rect {
            x: chart.w,
            y: top as f64,
            w: panel as f64,
            h: chart.h,
        });
        XyLayout { chart, legend }
    }

    /// The layout at this chart's own size.
    #[cfg(test)]
    pub(crate) fn layout(&self) -> XyLayout {
        let (w, h) = self.size();
        self.layout_in(w, h)
    }
}

/// The height (pixels) [`draw_titles`] takes.
pub(crate) fn titles_height(title: &str, subtitle: &str, width: u32) -> u32 {
    let t = title_font_size(title, width);
    let mut h = 10.0 + 1.25 * t;
    if !subtitle.is_empty() {
        h += 1.3 * title_font_size(subtitle, width).min(16.0);
    }
    (h + 6.0).ceil() as u32
}

/// Draw `title` (and `subtitle` below it, if not empty) centred at the top of `root`, 10 px
/// from its edge, each in a size that fits the width; returns the area below them.
pub(crate) fn draw_titles<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    title: &str,
    subtitle: &str,
) -> Result<DrawingArea<DB, Shift>, DrawError<DB>> {
    let (w, _) = root.dim_in_pixel();
    let centre = Pos::new(HPos::Center, VPos::Top);
    let t = title_font_size(title, w);
    root.draw_text(
        title,
        &font(t).color(&BLACK).pos(centre),
        (w as i32 / 2, 10),
    )?;
    if !subtitle.is_empty() {
        let s = title_font_size(subtitle, w).min(16.0);
        root.draw_text(
            subtitle,
            &font(s).color(&RGBColor(60, 60, 60)).pos(centre),
            (w as i32 / 2, (10.0 + 1.25 * t) as i32),
        )?;
    }
    Ok(root.split_vertically(titles_height(title, subtitle, w)).1)
}

/// A title font size (pixels) that lets `title` fit in `width` pixels: 21 px, smaller for
/// long titles, never below 12 px.
pub(crate) fn title_font_size(title: &str, width: u32) -> f64 {
    let n = title.chars().count().max(1) as f64;
    (0.92 * width as f64 / (0.58 * n)).clamp(12.0, 21.0)
}

/// The polyline `pts` cut to the rectangle `x` × `y` (in the axes' own scale: logarithms
/// for a log axis), interpolating where it crosses an edge: one piece per run inside.
/// Points that are not finite (or ≤ 0 on a log axis) break the line.
pub(crate) fn clip_polyline(
    pts: &[(f64, f64)],
    x: (f64, f64),
    y: (f64, f64),
    log: (bool, bool),
) -> Vec<Vec<(f64, f64)>> {
    let fwd = |v: f64, l: bool| if l { v.ln() } else { v };
    let back = |v: f64, l: bool| if l { v.exp() } else { v };
    let ok = |v: f64, l: bool| v.is_finite() && (!l || v > 0.0);
    let (x0, x1) = (fwd(x.0, log.0), fwd(x.1, log.0));
    let (y0, y1) = (fwd(y.0, log.1), fwd(y.1, log.1));
    let mut out: Vec<Vec<(f64, f64)>> = Vec::new();
    let mut cur: Vec<(f64, f64)> = Vec::new();
    let flush = |cur: &mut Vec<(f64, f64)>, out: &mut Vec<Vec<(f64, f64)>>| {
        if cur.len() >= 2 {
            out.push(std::mem::take(cur));
        } else {
            cur.clear();
        }
    };
    for w in pts.windows(2) {
        let (a, b) = (w[0], w[1]);
        if !(ok(a.0, log.0) && ok(a.1, log.1) && ok(b.0, log.0) && ok(b.1, log.1)) {
            flush(&mut cur, &mut out);
            continue;
        }
        let (ax, ay, bx, by) = (
            fwd(a.0, log.0),
            fwd(a.1, log.1),
            fwd(b.0, log.0),
            fwd(b.1, log.1),
        );
        // Liang–Barsky: the part t ∈ [t0, t1] of a + t (b − a) inside the rectangle.
        let (dx, dy) = (bx - ax, by - ay);
        let (mut t0, mut t1) = (0.0f64, 1.0f64);
        let mut inside = true;
        for (p, q) in [(-dx, ax - x0), (dx, x1 - ax), (-dy, ay - y0), (dy, y1 - ay)] {
            if p == 0.0 {
                if q < 0.0 {
                    inside = false;
                }
            } else {
                let r = q / p;
                if p < 0.0 {
                    t0 = t0.max(r);
                } else {
                    t1 = t1.min(r);
                }
            }
        }
        if !inside || t0 > t1 {
            flush(&mut cur, &mut out);
            continue;
        }
        let at = |t: f64| (back(ax + t * dx, log.0), back(ay + t * dy, log.1));
        if t0 > 0.0 {
            flush(&mut cur, &mut out);
        }
        if cur.is_empty() {
            cur.push(at(t0));
        }
        cur.push(at(t1));
        if t1 < 1.0 {
            flush(&mut cur, &mut out);
        }
    }
    flush(&mut cur, &mut out);
    out
}

/// An axis of an x–y chart: f64 values, tick labels formatted by our formatters.
pub(crate) trait Axis: Ranged<ValueType = f64> + ValueFormatter<f64> {}
impl<T: Ranged<ValueType = f64> + ValueFormatter<f64>> Axis for T {}

fn draw_series_of<DB: Canvas, X: Axis, Y: Axis>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    plot: &XyPlot,
    s: &Series,
) -> Result<(), DrawError<DB>> {
    let (xr, yr) = (plot.x_range, plot.y_range);
    let color = s.color;
    let dashed = |w: u32, on: u32, off: u32| (w, on, off);
    let dash = match s.kind {
        Kind::Line(w) => Some(dashed(w, 0, 0)),
        Kind::Dashed(w) => Some(dashed(w, 8, 5)),
        Kind::Dotted(w) => Some(dashed(w, 2, 4)),
        Kind::LongDashed(w) => Some(dashed(w, 16, 6)),
        _ => None,
    };
    if let Some((w, on, off)) = dash {
        let map = PixelMap {
            size: chart.plotting_area().dim_in_pixel(),
            x_range: xr,
            y_range: yr,
            log: (plot.log_x, plot.log_y),
        };
        let pen = Pen {
            color,
            width: w as f64,
            dash: (on > 0).then_some((on as f64, off as f64)),
        };
        for piece in clip_polyline(&s.points, xr, yr, (plot.log_x, plot.log_y)) {
            draw_data_polyline(chart.plotting_area(), &map, &piece, pen)?;
        }
        return Ok(());
    }
    let Glyph::Point { marker, r, .. } = s.kind.glyph(color) else {
        return Ok(());
    };
    let area = chart.plotting_area().strip_coord_spec();
    let base = chart.plotting_area().get_base_pixel();
    for &(x, y) in &s.points {
        let x_ok = x.is_finite() && x >= xr.0 && x <= xr.1 && (!plot.log_x || x > 0.0);
        if !x_ok || !y.is_finite() {
            continue;
        }
        let edge = if y > yr.1 {
            Some((yr.1, -1.0))
        } else if y < yr.0 || (plot.log_y && y <= 0.0) {
            Some((yr.0, 1.0))
        } else {
            None
        };
        if let Some((end, dir)) = edge {
            let tip = chart.backend_coord(&(x, end));
            let path: Vec<(i32, i32)> = marks::arrow((0.0, dir), 20.0, 8.0)
                .into_iter()
                .map(|(dx, dy)| (tip.0 - base.0 + dx, tip.1 - base.1 + dy))
                .collect();
            area.draw(&PathElement::new(path, color.stroke_width(2)))?;
            continue;
        }
        let c = chart.backend_coord(&(x, y));
        legend::draw_marker(&area, (c.0 - base.0, c.1 - base.1), marker, r, color)?;
    }
    Ok(())
}

fn draw_annotations<DB: DrawingBackend, X: Axis, Y: Axis>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    plot: &XyPlot,
) -> Result<(), DrawError<DB>> {
    if plot.annotations.is_empty() {
        return Ok(());
    }
    let base = chart.plotting_area().get_base_pixel();
    let (pw, ph) = chart.plotting_area().dim_in_pixel();
    let pts: Vec<(f64, f64)> = plot
        .annotations
        .iter()
        .map(|a| {
            let c = chart.backend_coord(&a.at);
            ((c.0 - base.0) as f64, (c.1 - base.1) as f64)
        })
        .collect();
    let size = 13.0;
    let sizes: Vec<(f64, f64)> = plot
        .annotations
        .iter()
        .map(|a| (legend::text_width(&a.text, size) as f64, size + 2.0))
        .collect();
    let area_rect = Rect {
        x: 0.0,
        y: 0.0,
        w: pw as f64,
        h: ph as f64,
    };
    let placed = marks::place_labels(&pts, &sizes, 6.0, area_rect);
    let area = chart.plotting_area().strip_coord_spec();
    let top_left = Pos::new(HPos::Left, VPos::Top);
    for ((a, p), (&(x, y), &(w, h))) in plot
        .annotations
        .iter()
        .zip(&placed)
        .zip(pts.iter().zip(&sizes))
    {
        let (lx, ly) = (x + p.dx, y + p.dy);
        if p.leader {
            // From the point to the nearest point of the label's box.
            let nx = x.clamp(lx, lx + w);
            let ny = y.clamp(ly, ly + h);
            area.draw(&PathElement::new(
                vec![(x as i32, y as i32), (nx as i32, ny as i32)],
                a.color.mix(0.6).stroke_width(1),
            ))?;
        }
        area.draw_text(
            &a.text,
            &font(size).color(&a.color).pos(top_left),
            (lx.round() as i32, ly.round() as i32 + 1),
        )?;
    }
    Ok(())
}

fn draw_body<DB: Canvas, X: Axis, Y: Axis>(
    chart: &mut ChartContext<'_, DB, Cartesian2d<X, Y>>,
    plot: &XyPlot,
) -> Result<(), DrawError<DB>> {
    let grey = RGBColor(150, 150, 150);
    let (x0, x1) = plot.x_range;
    let (y0, y1) = plot.y_range;
    let tick = |log: bool| -> &dyn Fn(&f64) -> String {
        if log {
            &|v: &f64| super::fmt_num(*v)
        } else {
            &|v: &f64| super::fmt_tick(*v)
        }
    };
    chart
        .configure_mesh()
        .x_desc(plot.x_desc.as_str())
        .y_desc(plot.y_desc.as_str())
        .x_labels(10)
        .y_labels(8)
        .x_label_formatter(tick(plot.log_x))
        .y_label_formatter(tick(plot.log_y))
        .label_style(font(15.0))
        .axis_desc_style(font(18.0))
        .max_light_lines(1)
        .light_line_style(RGBColor(238, 238, 238))
        .bold_line_style(RGBColor(215, 215, 215))
        .draw()?;
    for &h in &plot.hlines {
        if h >= y0 && h <= y1 {
            chart.draw_series(std::iter::once(PathElement::new(
                vec![(x0, h), (x1, h)],
                grey.stroke_width(1),
            )))?;
        }
    }
    for (x, text) in &plot.vlines {
        if *x >= x0 && *x <= x1 {
            chart.draw_series(DashedLineSeries::new(
                vec![(*x, y0), (*x, y1)],
                6,
                4,
                grey.stroke_width(1),
            ))?;
            let style = font(14.0).color(&RGBColor(90, 90, 90));
            chart.draw_series(std::iter::once(Text::new(
                text.clone(),
                (*x, y1),
                style.pos(Pos::new(HPos::Left, VPos::Top)),
            )))?;
        }
    }
    for s in &plot.series {
        draw_series_of(chart, plot, s)?;
    }
    draw_annotations(chart, plot)
}

/// The chart's margins and label areas (the same for every axis kind).
fn chart_builder<'a, 'b, DB: DrawingBackend>(
    area: &'a DrawingArea<DB, Shift>,
) -> ChartBuilder<'a, 'b, DB> {
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(16)
        .margin_right(28)
        .x_label_area_size(55)
        .y_label_area_size(85);
    builder
}

/// Build the chart on `area` with each axis linear or logarithmic (log axes with ticks
/// from [`log_ticks`]) and draw its body.
fn draw_chart<DB: Canvas>(
    area: &DrawingArea<DB, Shift>,
    plot: &XyPlot,
) -> Result<(), DrawError<DB>> {
    let (x0, x1) = plot.x_range;
    let (y0, y1) = plot.y_range;
    let mut builder = chart_builder(area);
    let lx = || (x0..x1).log_scale().with_key_points(log_ticks(x0, x1));
    let ly = || (y0..y1).log_scale().with_key_points(log_ticks(y0, y1));
    match (plot.log_x, plot.log_y) {
        (false, false) => draw_body(&mut builder.build_cartesian_2d(x0..x1, y0..y1)?, plot),
        (false, true) => draw_body(&mut builder.build_cartesian_2d(x0..x1, ly())?, plot),
        (true, false) => draw_body(&mut builder.build_cartesian_2d(lx(), y0..y1)?, plot),
        (true, true) => draw_body(&mut builder.build_cartesian_2d(lx(), ly())?, plot),
    }
}

impl XyPlot {
    /// Draw the chart, its titles and its legend panel into `root` (any size).
    pub(crate) fn draw_in<DB: Canvas>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> Result<(), DrawError<DB>> {
        let (w, h) = root.dim_in_pixel();
        let lay = self.layout_in(w, h);
        let body = draw_titles(root, &self.title, &self.subtitle)?;
        let (main, panel) = body.split_horizontally(lay.chart.w as u32);
        draw_chart(&main, self)?;
        if lay.legend.is_some() {
            let y = legend::draw_column(&panel, (4, 24), &self.legend_entries())?;
            if let Some(key) = &self.color_key {
                legend::draw_color_key(&panel, (8, y + 16), key)?;
            }
        }
        Ok(())
    }
}

impl XyPlot {
    /// The plotting area (the data rectangle inside the axes, in pixels of the whole
    /// picture) and the map from values to sub-pixel positions in it that the curves are
    /// drawn with. Found by laying the chart out as [`Picture::draw`] does.
    #[cfg(test)]
    pub(crate) fn plotting_area(&self) -> (Rect, PixelMap) {
        let (w, h) = self.size();
        let lay = self.layout_in(w, h);
        let top = titles_height(&self.title, &self.subtitle, w);
        let mut svg = String::new();
        let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
        let (_, body) = root.split_vertically(top);
        let (main, _) = body.split_horizontally(lay.chart.w as u32);
        let (x0, x1) = self.x_range;
        let (y0, y1) = self.y_range;
        let (xs, ys) = match chart_builder(&main).build_cartesian_2d(x0..x1, y0..y1) {
            Ok(chart) => chart.plotting_area().get_pixel_range(),
            Err(_) => (0..0, 0..0),
        };
        let rect = Rect {
            x: xs.start as f64,
            y: ys.start as f64,
            w: (xs.end - xs.start) as f64,
            h: (ys.end - ys.start) as f64,
        };
        let map = PixelMap {
            size: (rect.w as u32, rect.h as u32),
            x_range: self.x_range,
            y_range: self.y_range,
            log: (self.log_x, self.log_y),
        };
        (rect, map)
    }
}

impl Picture for XyPlot {
    fn size(&self) -> (u32, u32) {
        let panel = self.panel_width(&self.legend_entries());
        (self.size.0 + panel, self.size.1)
    }

    fn draw<DB: Canvas>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError<DB>> {
        self.draw_in(root)
    }
}

#[cfg(test)]
mod tests;
