//! The x–y chart's layout, clipping, ranges and its marks beyond the axes.

use super::*;

#[test]
fn lines_are_cut_at_the_edges_not_clamped() {
    // A line from (0, 0) to (2, 4) in a [0, 2] × [0, 2] box leaves it at (1, 2).
    let pieces = clip_polyline(
        &[(0.0, 0.0), (2.0, 4.0)],
        (0.0, 2.0),
        (0.0, 2.0),
        (false, false),
    );
    assert_eq!(pieces, vec![vec![(0.0, 0.0), (1.0, 2.0)]]);
    // Out and back in: two pieces.
    let pts = [(0.0, 1.0), (1.0, 3.0), (2.0, 1.0)];
    let pieces = clip_polyline(&pts, (0.0, 2.0), (0.0, 2.0), (false, false));
    assert_eq!(pieces.len(), 2);
    assert_eq!(pieces[0], vec![(0.0, 1.0), (0.5, 2.0)]);
    assert_eq!(pieces[1], vec![(1.5, 2.0), (2.0, 1.0)]);
    // On a log axis the crossing is interpolated in ln y: 1 → 100 crosses 10 halfway.
    let pieces = clip_polyline(
        &[(0.0, 1.0), (1.0, 100.0)],
        (0.0, 1.0),
        (0.5, 10.0),
        (false, true),
    );
    assert!((pieces[0][1].0 - 0.5).abs() < 1e-12 && (pieces[0][1].1 - 10.0).abs() < 1e-9);
    // A NaN breaks the line.
    let pieces = clip_polyline(
        &[
            (0.0, 1.0),
            (0.5, 1.0),
            (1.0, f64::NAN),
            (1.5, 1.0),
            (2.0, 1.0),
        ],
        (0.0, 2.0),
        (0.0, 2.0),
        (false, false),
    );
    assert_eq!(pieces.len(), 2);
}

#[test]
fn the_legend_panel_is_beside_the_chart() {
    let mut p = XyPlot::new("t", "x", "y");
    p.series.push(Series {
        label: Some("a rather long legend label".into()),
        color: BLACK,
        kind: Kind::Points(4),
        points: vec![(0.5, 2.0), (0.5, 0.5)],
    });
    let (w, h) = p.size();
    assert!(w > 900, "the panel widens the picture");
    let lay = p.layout();
    let legend = lay.legend.expect("a legend");
    assert!(!legend.overlaps(&lay.chart));
    assert_eq!(legend.x + legend.w, w as f64);
    assert!(lay.chart.h < h as f64);
    // The point above the range is counted.
    assert_eq!(p.above_top().count, 1);
    assert_eq!(
        p.legend_entries()[1].label,
        "1 measured above the top (up to 2)"
    );
}

#[test]
fn points_below_the_range_are_counted_and_drawn_at_the_bottom() {
    let mut p = XyPlot::new("t", "x", "y");
    p.log_y = true;
    p.series.push(Series {
        // Longer than the count's line: the legend panel, and so the chart, keeps its
        // width without the points below.
        label: Some("measured values of a rather noisy dark region of the scan".into()),
        color: BLACK,
        kind: Kind::Points(4),
        points: vec![
            (0.2, 0.5),
            (0.4, -0.003),
            (0.6, 0.0),
            (0.8, 1e-9),
            (5.0, -1.0),
        ],
    });
    p.x_range = (0.0, 1.0);
    p.y_range = (0.01, 1.0);
    // −0.003 and 0 (not on a log axis) and 1e-9 (below 0.01); x = 5 is off the chart.
    let b = p.below_bottom();
    assert_eq!((b.count, b.worst), (3, -0.003));
    assert_eq!(
        p.legend_entries()[1].label,
        "3 measured below the bottom (down to -0.003)"
    );
    // Drawn: three dark arrows below the chart's bottom third, none without the points.
    let dark = |p: &XyPlot| {
        let (w, h) = p.size();
        let rgb = crate::plot::rgb_buffer(p).unwrap();
        let lay = p.layout();
        let bottom = (lay.chart.y + lay.chart.h * 0.8) as u32;
        let right = w.min((lay.chart.x + lay.chart.w) as u32);
        (bottom..h.min((lay.chart.y + lay.chart.h) as u32))
            .flat_map(|y| (0..right).map(move |x| (x, y)))
            .filter(|&(x, y)| rgb[((y * w + x) * 3) as usize] < 60)
            .count()
    };
    let with = dark(&p);
    let chart = p.layout().chart;
    p.series[0].points = vec![(0.2, 0.5)];
    assert_eq!(p.layout().chart, chart);
    assert!(with > dark(&p) + 30, "{with} against {}", dark(&p));
}
