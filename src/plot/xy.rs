//! A general x–y chart (curves, points, reference lines, legend), linear or logarithmic in
//! y: Figures 5 and 6 and most fit plots are one of these.

use super::{font, DrawError, Picture};
use plotters::coord::ranged1d::{Ranged, ValueFormatter};
use plotters::coord::types::RangedCoordf64;
use plotters::coord::Shift;
use plotters::prelude::*;

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A solid line of the given width.
    Line(u32),
    /// A dashed line of the given width.
    Dashed(u32),
    /// Filled circles of the given radius.
    Points(u32),
    /// Open circles of the given radius.
    OpenPoints(u32),
}

/// One series of an [`XyPlot`].
#[derive(Debug, Clone)]
pub struct Series {
    /// Legend text; `None` keeps the series out of the legend.
    pub label: Option<String>,
    pub color: RGBColor,
    pub kind: Kind,
    pub points: Vec<(f64, f64)>,
}

/// Where the legend goes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LegendAt {
    UpperLeft,
    UpperRight,
    LowerLeft,
    LowerRight,
    UpperMiddle,
}

/// An x–y chart.
#[derive(Debug, Clone)]
pub struct XyPlot {
    pub title: String,
    pub x_desc: String,
    pub y_desc: String,
    pub size: (u32, u32),
    pub x_range: (f64, f64),
    pub y_range: (f64, f64),
    /// Logarithmic y axis (y_range must then be positive; values ≤ 0 are dropped).
    pub log_y: bool,
    pub series: Vec<Series>,
    /// Horizontal reference lines (thin grey).
    pub hlines: Vec<f64>,
    /// Vertical reference lines with a short label at the top.
    pub vlines: Vec<(f64, String)>,
    pub legend_at: LegendAt,
}

impl XyPlot {
    /// An empty chart with the default size (900×600), linear axes.
    pub fn new(
        title: impl Into<String>,
        x_desc: impl Into<String>,
        y_desc: impl Into<String>,
    ) -> Self {
        XyPlot {
            title: title.into(),
            x_desc: x_desc.into(),
            y_desc: y_desc.into(),
            size: (900, 600),
            x_range: (0.0, 1.0),
            y_range: (0.0, 1.0),
            log_y: false,
            series: Vec::new(),
            hlines: Vec::new(),
            vlines: Vec::new(),
            legend_at: LegendAt::UpperRight,
        }
    }

    /// Set the y range to cover every finite (positive, for a log axis) y value, with a
    /// margin; keeps the current range if there is none.
    pub fn fit_y_range(&mut self) {
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
}

/// A title font size (pixels) that lets `title` fit in `width` pixels: 21 px, smaller for
/// long titles, never below 13 px.
pub fn title_font_size(title: &str, width: u32) -> f64 {
    let n = title.chars().count().max(1) as f64;
    (0.94 * width as f64 / (0.56 * n)).clamp(13.0, 21.0)
}

fn clamp_point(p: (f64, f64), y: (f64, f64), log_y: bool) -> Option<(f64, f64)> {
    if !(p.0.is_finite() && p.1.is_finite()) || (log_y && p.1 <= 0.0) {
        return None;
    }
    Some((p.0, p.1.clamp(y.0, y.1)))
}

fn draw_body<'a, DB, Y>(
    chart: &mut ChartContext<'a, DB, Cartesian2d<RangedCoordf64, Y>>,
    plot: &XyPlot,
) -> Result<(), DrawError<DB>>
where
    DB: DrawingBackend + 'a,
    Y: Ranged<ValueType = f64> + ValueFormatter<f64>,
{
    let grey = RGBColor(150, 150, 150);
    let (x0, x1) = plot.x_range;
    let (y0, y1) = plot.y_range;
    chart
        .configure_mesh()
        .x_desc(plot.x_desc.as_str())
        .y_desc(plot.y_desc.as_str())
        .x_labels(10)
        .y_labels(8)
        .x_label_formatter(&|v| super::fmt_tick(*v))
        .y_label_formatter(if plot.log_y {
            &|v: &f64| super::fmt_num(*v)
        } else {
            &|v: &f64| super::fmt_tick(*v)
        })
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
                style.pos(plotters::style::text_anchor::Pos::new(
                    plotters::style::text_anchor::HPos::Left,
                    plotters::style::text_anchor::VPos::Top,
                )),
            )))?;
        }
    }
    for s in &plot.series {
        let pts: Vec<(f64, f64)> = s
            .points
            .iter()
            .filter_map(|&p| clamp_point(p, (y0, y1), plot.log_y))
            .filter(|p| p.0 >= x0 && p.0 <= x1)
            .collect();
        let color = s.color;
        let anno = match s.kind {
            Kind::Line(w) => chart.draw_series(LineSeries::new(pts, color.stroke_width(w)))?,
            Kind::Dashed(w) => {
                chart.draw_series(DashedLineSeries::new(pts, 8, 5, color.stroke_width(w)))?
            }
            Kind::Points(r) => chart.draw_series(
                pts.into_iter()
                    .map(move |p| Circle::new(p, r, color.filled())),
            )?,
            Kind::OpenPoints(r) => chart.draw_series(
                pts.into_iter()
                    .map(move |p| Circle::new(p, r, color.stroke_width(1))),
            )?,
        };
        if let Some(label) = &s.label {
            let anno = anno.label(label.as_str());
            match s.kind {
                Kind::Line(w) | Kind::Dashed(w) => {
                    anno.legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 24, y)], color.stroke_width(w.max(2)))
                    });
                }
                Kind::Points(r) => {
                    anno.legend(move |(x, y)| Circle::new((x + 12, y), r.max(3), color.filled()));
                }
                Kind::OpenPoints(r) => {
                    anno.legend(move |(x, y)| {
                        Circle::new((x + 12, y), r.max(3), color.stroke_width(1))
                    });
                }
            }
        }
    }
    if plot.series.iter().any(|s| s.label.is_some()) {
        let pos = match plot.legend_at {
            LegendAt::UpperLeft => SeriesLabelPosition::UpperLeft,
            LegendAt::UpperRight => SeriesLabelPosition::UpperRight,
            LegendAt::LowerLeft => SeriesLabelPosition::LowerLeft,
            LegendAt::LowerRight => SeriesLabelPosition::LowerRight,
            LegendAt::UpperMiddle => SeriesLabelPosition::UpperMiddle,
        };
        chart
            .configure_series_labels()
            .position(pos)
            .margin(12)
            .legend_area_size(32)
            .label_font(font(15.0))
            .background_style(WHITE.mix(0.85))
            .border_style(RGBColor(120, 120, 120))
            .draw()?;
    }
    Ok(())
}

impl Picture for XyPlot {
    fn size(&self) -> (u32, u32) {
        self.size
    }

    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError<DB>> {
        let (x0, x1) = self.x_range;
        let (y0, y1) = self.y_range;
        let mut builder = ChartBuilder::on(root);
        builder
            .caption(
                self.title.as_str(),
                font(title_font_size(&self.title, self.size.0)),
            )
            .margin(16)
            .margin_right(28)
            .x_label_area_size(55)
            .y_label_area_size(85);
        if self.log_y {
            let mut chart = builder.build_cartesian_2d(x0..x1, (y0..y1).log_scale())?;
            draw_body(&mut chart, self)
        } else {
            let mut chart = builder.build_cartesian_2d(x0..x1, y0..y1)?;
            draw_body(&mut chart, self)
        }
    }
}
