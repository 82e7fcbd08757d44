//! Small multiples for a batch of fits: one small chart per quantity (T/σ, each model
//! parameter) against the wavelength of each fit, or against the fit's row in the summary
//! table when the fits do not differ by wavelength. Values the data does not determine are
//! open circles, determined ones filled (the page's caption says so: no legend takes room
//! from the small chart).

use super::xy::{Kind, Series, XyPlot};
use super::{series_color, ticks::nice_step};

/// One quantity across the fits: its name, unit (empty for none) and per fit (x, value,
/// determined). Non-finite values are left out.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Quantity {
    /// The quantity's name (`T/σ` or a model parameter's): the chart's title and y label.
    pub name: String,
    /// Its unit, shown in brackets after the name on the y axis; empty: none shown.
    pub unit: String,
    /// One per fit: x (wavelength or row, as the caller's x description says), the value
    /// in `unit`, and whether the data determines it (filled circle) or not (open circle).
    pub points: Vec<(f64, f64, bool)>,
}

/// The size (pixels) of each small chart.
pub(crate) const SMALL: (u32, u32) = (600, 400);

/// The small charts of `quantities` over x (described by `x_desc`), one per quantity with
/// at least one finite value.
pub(crate) fn overview_charts(x_desc: &str, quantities: &[Quantity]) -> Vec<XyPlot> {
    let xs: Vec<f64> = quantities
        .iter()
        .flat_map(|q| q.points.iter().map(|p| p.0))
        .filter(|x| x.is_finite())
        .collect();
    let (lo, hi) = xs
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let x_range = if lo.is_finite() && hi > lo {
        let pad = nice_step((hi - lo) / 20.0);
        (lo - pad, hi + pad)
    } else if lo.is_finite() {
        (lo - 1.0, lo + 1.0)
    } else {
        (0.0, 1.0)
    };
    quantities
        .iter()
        .filter(|q| q.points.iter().any(|p| p.1.is_finite()))
        .map(|q| small_chart(q, x_desc, x_range))
        .collect()
}

/// One quantity's chart.
fn small_chart(q: &Quantity, x_desc: &str, x_range: (f64, f64)) -> XyPlot {
    let y_desc = if q.unit.is_empty() {
        q.name.clone()
    } else {
        format!("{} ({})", q.name, q.unit)
    };
    let mut plot = XyPlot::new(q.name.clone(), x_desc, y_desc);
    plot.size = SMALL;
    plot.x_range = x_range;
    let pick = |det: bool| -> Vec<(f64, f64)> {
        q.points
            .iter()
            .filter(|p| p.2 == det && p.0.is_finite() && p.1.is_finite())
            .map(|p| (p.0, p.1))
            .collect()
    };
    let color = series_color(0);
    let (det, undet) = (pick(true), pick(false));
    plot.series.push(Series {
        label: None,
        color,
        kind: Kind::Points(4),
        points: det,
    });
    plot.series.push(Series {
        label: None,
        color,
        kind: Kind::OpenPoints(4),
        points: undet,
    });
    plot.fit_y_range();
    plot
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_chart_per_quantity_with_values_and_a_shared_x_range() {
        let q = |name: &str, pts: Vec<(f64, f64, bool)>| Quantity {
            name: name.into(),
            unit: String::new(),
            points: pts,
        };
        let charts = overview_charts(
            "wavelength (nm)",
            &[
                q("T/σ", vec![(400.0, 3.0, true), (700.0, 4.0, false)]),
                q("scale", vec![(400.0, f64::NAN, true)]),
            ],
        );
        assert_eq!(charts.len(), 1);
        let c = &charts[0];
        // 300 nm of x: a 20 nm pad (nice step of 15) on each side.
        assert_eq!(c.x_range, (380.0, 720.0));
        assert_eq!(c.series[0].points, vec![(400.0, 3.0)]);
        assert_eq!(c.series[1].points, vec![(700.0, 4.0)]);
    }
}
