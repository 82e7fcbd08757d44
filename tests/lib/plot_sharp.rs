//! PNG pictures are sharp and exact. Curves are drawn at sub-pixel positions
//! (src/plot/stroke.rs): measured on the rendered bitmap, the intensity-weighted centre of a
//! line across each pixel column lies on the exact line, where integer pixel coordinates
//! leave it up to half a pixel off (stair steps); the SVG gets the same vertices to 0.01 px.
//! Edges are anti-aliased (partly covered pixels along a slanted line) and not blurred (a
//! 1-pixel axis line is one fully dark pixel wide, a 2-pixel curve has fully covered pixels
//! in every column); text is set at the size it is laid out with; embedded images are drawn
//! pixel for pixel.

use crate::plot::figures::{figure5, figure6};
use crate::plot::marks::Rect;
use crate::plot::sphere::{sphere_radiance, SpherePicture};
use crate::plot::stroke::{Canvas, PixelMap};
use crate::plot::xy::{Kind, Series, XyPlot};
use crate::plot::{ensure_font, font, rgb_buffer, svg_string, svg_to_rgb, DrawError, Picture};
use plotters::coord::Shift;
use plotters::prelude::*;

/// A 600 × 400 chart on [0, 1]² with one black line through `pts` (none if empty).
fn chart(pts: &[(f64, f64)]) -> XyPlot {
    let mut p = XyPlot::new("a line", "x", "y");
    p.size = (600, 400);
    p.x_range = (0.0, 1.0);
    p.y_range = (0.0, 1.0);
    if !pts.is_empty() {
        p.series.push(Series {
            label: None,
            color: BLACK,
            kind: Kind::Line(2),
            points: pts.to_vec(),
        });
    }
    p
}

/// How much of each pixel a black stroke covers: 1 − drawn / background (green channel),
/// from the picture with the stroke and the same picture without it.
fn black_alpha(with: &[u8], without: &[u8]) -> Vec<f64> {
    with.chunks(3)
        .zip(without.chunks(3))
        .map(|(a, b)| 1.0 - a[1] as f64 / (b[1] as f64).max(1.0))
        .collect()
}

/// For each column in `cols`: the coverage-weighted centre row (pixel centres at j + ½)
/// of the pixels in `rows`, and the column's total coverage.
fn column_centres(
    alpha: &[f64],
    width: usize,
    cols: std::ops::Range<usize>,
    rows: std::ops::Range<usize>,
) -> Vec<(usize, f64, f64)> {
    cols.map(|i| {
        let (mut s, mut sy) = (0.0, 0.0);
        for j in rows.clone() {
            let a = alpha[j * width + i].max(0.0);
            s += a;
            sy += a * (j as f64 + 0.5);
        }
        (i, sy / s.max(1e-12), s)
    })
    .collect()
}

/// The points of the straight line from (0, 0.137) to (1, 0.771), 61 of them: a slope
/// of 0.363 pixel per pixel on the 600 × 400 chart (no whole number), vertices 8 px apart.
fn straight_line() -> Vec<(f64, f64)> {
    (0..=60)
        .map(|k| {
            let x = k as f64 / 60.0;
            (x, 0.137 + 0.634 * x)
        })
        .collect()
}

/// The straight-line chart, its picture size and its plotting area.
struct Setup {
    pts: Vec<(f64, f64)>,
    plot: XyPlot,
    size: (u32, u32),
    rect: Rect,
    map: PixelMap,
}

impl Setup {
    fn straight() -> Setup {
        let pts = straight_line();
        let plot = chart(&pts);
        let size = plot.size();
        let (rect, map) = plot.plotting_area();
        Setup {
            pts,
            plot,
            size,
            rect,
            map,
        }
    }
}

#[test]
fn a_straight_line_is_centred_on_the_exact_line_in_every_column() {
    let Setup {
        pts,
        plot,
        size: (w, h),
        rect,
        map,
    } = Setup::straight();
    let alpha = black_alpha(
        &rgb_buffer(&plot).unwrap(),
        &rgb_buffer(&chart(&[])).unwrap(),
    );
    // The exact line in picture pixels, through the mapped end points.
    let a = map.to_pixel(pts[0]);
    let b = map.to_pixel(pts[60]);
    let (ax, ay) = (a.0 + rect.x, a.1 + rect.y);
    let (bx, by) = (b.0 + rect.x, b.1 + rect.y);
    let exact = |x: f64| ay + (x - ax) * (by - ay) / (bx - ax);
    let cols = (rect.x as usize + 20)..(rect.x + rect.w) as usize - 20;
    let rows = rect.y as usize..(rect.y + rect.h) as usize;
    let centres = column_centres(&alpha, w as usize, cols, rows);
    let slope = (by - ay) / (bx - ax);
    assert!((slope.abs() - 0.363).abs() < 0.01, "slope {slope}");
    let mut worst = 0.0f64;
    let mut intermediate = 0;
    let mut faintest_core = 1.0f64;
    for &(i, c, s) in &centres {
        worst = worst.max((c - exact(i as f64 + 0.5)).abs());
        // The column's total coverage is the stroke's vertical extent, 2 / cos θ.
        let extent = 2.0 * (1.0 + slope * slope).sqrt();
        assert!(
            (s - extent).abs() < 0.06 * extent,
            "column {i}: {s} vs {extent}"
        );
        let partial = (0..h as usize)
            .map(|j| alpha[j * w as usize + i])
            .filter(|a| *a > 0.02 && *a < 0.98)
            .count();
        intermediate += usize::from(partial > 0);
        // A 2.13 px extent holds a whole pixel: the darkest one is fully covered.
        let core = (0..h as usize)
            .map(|j| alpha[j * w as usize + i])
            .fold(0.0f64, f64::max);
        faintest_core = faintest_core.min(core);
    }
    eprintln!("sub-pixel line: worst column centre {worst:.4} px off");
    assert!(
        worst < 0.1,
        "worst column centre {worst} px off the exact line"
    );
    // Anti-aliased: the stroke's 2.13 px extent never fills whole pixels only, so (almost)
    // every column has partly covered ones (an aliased render has none).
    assert!(
        intermediate * 100 >= 95 * centres.len(),
        "{intermediate} of {} columns have partly covered pixels",
        centres.len()
    );
    // Not blurred: every column has a fully covered pixel in the stroke's middle (a blur
    // spreads the same ink over more, fainter pixels).
    assert!(
        faintest_core > 0.95,
        "a column's darkest pixel is covered {faintest_core}"
    );
}

#[test]
fn the_same_line_at_whole_pixels_fails_that_measure() {
    // The measure above is sharp: the line drawn through whole pixels (plotters' integer
    // pixel coordinates) is more than 0.1 px off in some column.
    let setup = Setup::straight();
    let (pts, (w, h), rect, map) = (setup.pts, setup.size, setup.rect, setup.map);
    let px: Vec<(f64, f64)> = pts
        .iter()
        .map(|&p| {
            let q = map.to_pixel(p);
            (q.0 + rect.x, q.1 + rect.y)
        })
        .collect();
    // The same 2-pixel polyline with each vertex moved to its pixel's centre, rendered the
    // way every picture is.
    let mut points = String::new();
    for p in &px {
        points.push_str(&format!("{},{} ", p.0.floor() + 0.5, p.1.floor() + 0.5));
    }
    let svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" \
         viewBox=\"0 0 {w} {h}\"><polyline fill=\"none\" stroke=\"#000000\" \
         stroke-width=\"2\" stroke-linejoin=\"round\" points=\"{points}\"/></svg>"
    );
    let with = svg_to_rgb(&svg, (w, h)).unwrap();
    let alpha = black_alpha(&with, &vec![255u8; (w * h * 3) as usize]);
    let exact = |x: f64| px[0].1 + (x - px[0].0) * (px[60].1 - px[0].1) / (px[60].0 - px[0].0);
    let cols = (rect.x as usize + 20)..(rect.x + rect.w) as usize - 20;
    let centres = column_centres(&alpha, w as usize, cols, 0..h as usize);
    let worst = centres
        .iter()
        .map(|&(i, c, _)| (c - exact(i as f64 + 0.5)).abs())
        .fold(0.0f64, f64::max);
    eprintln!("whole-pixel line: worst column centre {worst:.4} px off");
    assert!(
        worst > 0.1,
        "the whole-pixel line is {worst} px off at worst"
    );
}

#[test]
fn a_curve_follows_its_exact_position() {
    // y = 0.5 + 0.3 sin(2πx), 241 points: where the curve is flatter than 1 px per px the
    // column centre is its exact height at the column's centre.
    let f = |x: f64| 0.5 + 0.3 * (2.0 * std::f64::consts::PI * x).sin();
    let pts: Vec<(f64, f64)> = (0..=240)
        .map(|k| (k as f64 / 240.0, f(k as f64 / 240.0)))
        .collect();
    let plot = chart(&pts);
    let (w, _) = plot.size();
    let (rect, map) = plot.plotting_area();
    let alpha = black_alpha(
        &rgb_buffer(&plot).unwrap(),
        &rgb_buffer(&chart(&[])).unwrap(),
    );
    let cols = (rect.x as usize + 5)..(rect.x + rect.w) as usize - 5;
    let rows = rect.y as usize..(rect.y + rect.h) as usize;
    // The map is linear: x = 0 at the area's left edge, 1 at w − 1 pixels right of it.
    let (x0, x1) = (rect.x, rect.x + rect.w - 1.0);
    let mut checked = 0;
    for (i, c, _) in column_centres(&alpha, w as usize, cols, rows) {
        // The value at the column's centre.
        let x = (i as f64 + 0.5 - x0) / (x1 - x0);
        let (px, py) = map.to_pixel((x, f(x)));
        assert!((px + rect.x - (i as f64 + 0.5)).abs() < 1e-9);
        let slope = 0.3
            * 2.0
            * std::f64::consts::PI
            * (2.0 * std::f64::consts::PI * x).cos()
            * (rect.h - 1.0)
            / (rect.w - 1.0);
        if slope.abs() < 1.0 {
            let err = (c - (py + rect.y)).abs();
            assert!(err < 0.15, "column {i}: centre {c}, exact {}", py + rect.y);
            checked += 1;
        }
    }
    assert!(checked > 200, "{checked} columns checked");
}

#[test]
fn svg_curves_keep_their_sub_pixel_vertices() {
    let pts = straight_line();
    let plot = chart(&pts);
    let (rect, map) = plot.plotting_area();
    let svg = svg_string(&plot).unwrap();
    assert!(!svg.contains("-7777"), "a placeholder was left in the SVG");
    let line = svg
        .lines()
        .find(|l| l.contains("stroke-linejoin=\"round\""))
        .expect("the curve's polyline");
    let points = line.split("points=\"").nth(1).unwrap();
    let points: Vec<(f64, f64)> = points
        .trim_end_matches("\"/>")
        .split_whitespace()
        .map(|p| {
            let (x, y) = p.split_once(',').unwrap();
            (x.parse().unwrap(), y.parse().unwrap())
        })
        .collect();
    assert_eq!(points.len(), pts.len());
    for (got, p) in points.iter().zip(&pts) {
        let q = map.to_pixel(*p);
        assert!((got.0 - q.0 - rect.x).abs() <= 0.005 && (got.1 - q.1 - rect.y).abs() <= 0.005);
    }
    assert!(
        points.iter().any(|p| p.1.fract().abs() > 0.01),
        "not only whole pixels"
    );
}

#[test]
fn figures_5_and_6_draw_every_curve_as_a_sub_pixel_polyline() {
    for (plot, n) in [(figure5().unwrap(), 6), (figure6().unwrap(), 9)] {
        let svg = svg_string(&plot).unwrap();
        let curves = svg
            .lines()
            .filter(|l| l.contains("stroke-linejoin=\"round\"") && l.contains("stroke-width=\"2\""))
            .filter(|l| l.matches(',').count() > 100)
            .count();
        // Figure 5's dashed Lambertian curve is many short dashes: count the solid ones.
        assert!(curves >= n - 1, "{}: {curves} curves", plot.title);
        let bitmap = rgb_buffer(&plot).unwrap();
        assert_eq!(bitmap.len(), (plot.size().0 * plot.size().1 * 3) as usize);
    }
}

/// The darkness (255 − green) of row `j` of an RGB bitmap `w` pixels wide.
fn darkness_row(rgb: &[u8], w: usize, j: usize) -> Vec<u8> {
    (0..w).map(|i| 255 - rgb[(j * w + i) * 3 + 1]).collect()
}

#[test]
fn a_one_pixel_axis_line_is_one_fully_dark_pixel_wide() {
    // The y axis, 1 px black, seen across a row in the middle of a chart whose x range
    // starts between ticks (no grid line beside the axis): one pixel at full intensity,
    // white on both sides. A line half a pixel off would be two grey pixels; a blurred one,
    // a fainter, wider profile.
    let mut plot = chart(&[]);
    plot.x_range = (0.03, 0.97);
    plot.y_range = (0.03, 0.97);
    let (w, _) = plot.size();
    let (rect, _) = plot.plotting_area();
    let rgb = rgb_buffer(&plot).unwrap();
    let row = darkness_row(&rgb, w as usize, (rect.y + 0.5 * rect.h) as usize);
    let window = (rect.x as usize - 6)..(rect.x as usize + 4);
    let profile: Vec<u8> = row[window.clone()].to_vec();
    let darkest = window.clone().max_by_key(|&i| row[i]).unwrap();
    assert_eq!(row[darkest], 255, "the axis pixel is black: {profile:?}");
    assert!(
        row[darkest - 1] < 5 && row[darkest + 1] < 5,
        "its neighbours are white: {profile:?}"
    );
    // The ink across the line is one pixel's worth.
    let ink: u32 = profile.iter().map(|&d| d as u32).sum();
    assert!(ink <= 255 + 10, "{ink}: {profile:?}");
}

/// A line of text at 24 px, as the pictures set it.
struct Words;

const WORDS: &str = "measured and fitted radiance (σ = 190 nm)";

impl Picture for Words {
    fn size(&self) -> (u32, u32) {
        (640, 60)
    }

    fn draw<DB: Canvas>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), DrawError<DB>> {
        root.draw(&Text::new(WORDS, (20, 15), font(24.0).color(&BLACK)))
    }
}

#[test]
fn text_is_set_at_the_size_it_is_laid_out_with() {
    // Layouts (legend panels, label areas) are sized by plotters' measure of the text; the
    // rendered text's ink is as wide, to within its side bearings.
    ensure_font().unwrap();
    let (measured, _) = font(24.0).box_size(WORDS).unwrap();
    let (w, h) = Words.size();
    let rgb = rgb_buffer(&Words).unwrap();
    let inked: Vec<usize> = (0..w as usize)
        .filter(|&i| (0..h as usize).any(|j| rgb[(j * w as usize + i) * 3 + 1] < 128))
        .collect();
    let ink = (inked.last().unwrap() - inked[0] + 1) as f64;
    eprintln!("text: ink {ink} px, measured {measured} px");
    assert!(
        (ink - measured as f64).abs() < 0.02 * measured as f64 + 3.0,
        "ink {ink} px wide, measured {measured} px"
    );
    assert!(
        (20..=23).contains(&inked[0]),
        "the text starts where it is placed, at x = 20 (plus its bearing): {}",
        inked[0]
    );
}

#[test]
fn embedded_images_are_drawn_pixel_for_pixel() {
    // A sphere is embedded in the SVG as one PNG image; the rendered picture has exactly
    // its pixels (no resampling blur, no shift).
    let model = crate::model::by_name("lambert", &Default::default()).unwrap();
    let image = sphere_radiance(model.as_ref(), &[1.0], 45.0, 1.0, 64).unwrap();
    let pic = SpherePicture {
        image: image.clone(),
        negative: false,
        marks: false,
    };
    assert_eq!(rgb_buffer(&pic).unwrap(), image.to_rgb(false));
}
