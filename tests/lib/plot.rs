//! Pictures: what each one must show (Peters 2000, Figures 4–7), and that the files are
//! valid PNG and SVG.

use crate::common::{self, assert_svg, png_size};

use crate::geometry::{Geometry, Quantity, Sample};
use crate::model::{by_name, Model, ModelOptions};
use crate::plot::figures::{
    figure4_spheres, figure5_curves, figure6_curves, figure7_grid, Figure4, T_OVER_SIGMA,
};
use crate::plot::fit::{write_fit_plots, FitPlotInput};
use crate::plot::sphere::{pixel_xy, sphere_radiance, SpherePicture};
use crate::plot::{rgb_buffer, svg_string};

fn model(name: &str) -> Box<dyn Model> {
    by_name(name, &ModelOptions::default()).unwrap()
}

/// Width and height from a PNG's IHDR chunk, after checking the signature.
/// Brightest pixel of a rendered (plain) sphere bitmap, in sphere coordinates.
fn brightest_in_bitmap(rgb: &[u8], size: u32) -> (f64, f64) {
    let n = size as usize;
    let k = (0..n * n).max_by_key(|&k| rgb[3 * k] as u32).unwrap();
    // Ties (several pixels at 255): take the mean position of all maximal pixels.
    let top = rgb[3 * k];
    let maxima: Vec<(f64, f64)> = (0..n * n)
        .filter(|&k| rgb[3 * k] == top)
        .map(|k| pixel_xy(size, k % n, k / n))
        .collect();
    let m = maxima.len() as f64;
    (
        maxima.iter().map(|p| p.0).sum::<f64>() / m,
        maxima.iter().map(|p| p.1).sum::<f64>() / m,
    )
}

#[test]
fn kbs_sphere_bitmap_is_brightest_at_the_specular_normal() {
    let size = 96;
    let img = sphere_radiance(
        model("kbs-rough").as_ref(),
        &[1.0, 5.0, 1.0],
        45.0,
        1.0,
        size,
    )
    .unwrap();
    let pic = SpherePicture {
        image: img,
        negative: false,
        marks: false,
    };
    let rgb = rgb_buffer(&pic).unwrap();
    let (x, y) = brightest_in_bitmap(&rgb, size);
    let px = 2.0 / size as f64;
    assert!((x + 0.3827).abs() < 2.0 * px, "x = {x}");
    assert!(y.abs() < 2.0 * px, "y = {y}");
}

#[test]
fn lambert_sphere_bitmap_is_brightest_at_the_light() {
    let size = 96;
    let img = sphere_radiance(model("lambert").as_ref(), &[1.0], 45.0, 1.0, size).unwrap();
    let rgb = rgb_buffer(&SpherePicture {
        image: img,
        negative: false,
        marks: false,
    })
    .unwrap();
    let (x, y) = brightest_in_bitmap(&rgb, size);
    let px = 2.0 / size as f64;
    assert!((x + 45f64.to_radians().sin()).abs() < 2.0 * px, "x = {x}");
    assert!(y.abs() < 2.0 * px, "y = {y}");
}

#[test]
fn negative_inverts_the_plain_picture() {
    let img = sphere_radiance(model("lambert").as_ref(), &[1.0], 45.0, 1.0, 64).unwrap();
    let plain = img.to_rgb(false);
    let neg = img.to_rgb(true);
    assert!(plain
        .iter()
        .zip(&neg)
        .all(|(a, b)| *a as u16 + *b as u16 == 255));
}

#[test]
fn figure4_spheres_peak_at_the_specular_point_and_narrow_with_t_over_sigma() {
    let spheres = figure4_spheres(80).unwrap();
    assert_eq!(spheres.len(), 6);
    let px = 2.0 / 80.0;
    let mut lit_area = Vec::new();
    for (img, caption) in &spheres[..5] {
        let (x, y) = img.brightest_xy();
        assert!((x + 0.3827).abs() <= 1.5 * px, "{caption}: x = {x}");
        assert!(y.abs() <= 1.5 * px, "{caption}: y = {y}");
        let max = img.max();
        lit_area.push(img.radiance.iter().filter(|v| **v >= 0.5 * max).count());
    }
    for w in lit_area.windows(2) {
        assert!(w[1] < w[0], "lobe narrows as T/σ grows: {lit_area:?}");
    }
    let (x, _) = spheres[5].0.brightest_xy();
    assert!(
        (x + std::f64::consts::FRAC_1_SQRT_2).abs() <= 1.5 * px,
        "Lambertian: x = {x}"
    );
}

#[test]
fn figure5_curves_peak_at_the_marks_and_narrow() {
    let curves = figure5_curves(361).unwrap();
    assert_eq!(curves.len(), 6);
    let mut widths = Vec::new();
    for (c, r) in curves.iter().zip(T_OVER_SIGMA) {
        assert_eq!(c.param, r);
        let (x, y) = c.peak();
        assert!((x + 22.5).abs() <= 0.5, "{}: peak at {x}", c.label);
        assert!((y - 1.0).abs() < 1e-12, "normalised");
        widths.push(c.width_at_half_max());
    }
    for w in widths.windows(2) {
        assert!(w[1] < w[0], "half-max widths shrink: {widths:?}");
    }
    assert!(
        (curves[5].peak().0 + 45.0).abs() <= 0.5,
        "Lambertian at the light"
    );
    // The drawn figure: six labelled curves peaking at the specular mark (Lambert: light).
    let fig = crate::plot::figures::figure5().unwrap();
    assert_eq!(fig.series.len(), 6);
    for (k, s) in fig.series.iter().enumerate() {
        assert!(s.label.is_some());
        let peak = s
            .points
            .iter()
            .copied()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap();
        let want = if k < 5 { -22.5 } else { -45.0 };
        assert!((peak.0 - want).abs() <= 0.75, "{:?}: {peak:?}", s.label);
    }
}

#[test]
fn figure6_peaks_move_monotonically_from_the_mirror_to_the_normal() {
    let curves = figure6_curves(721).unwrap();
    assert_eq!(curves.len(), 9);
    let peaks: Vec<f64> = curves.iter().map(|c| c.peak().0).collect();
    assert!(
        (peaks[0] - 45.0).abs() <= 0.125,
        "φr = 0 peaks at the mirror: {peaks:?}"
    );
    assert!(
        peaks[8].abs() <= 0.125,
        "φr = 90° peaks at θr = 0: {peaks:?}"
    );
    for w in peaks.windows(2) {
        assert!(w[1] < w[0], "peaks move toward 0: {peaks:?}");
    }
    // The φr = 90° curve's peak value is the φr = 0 curve's value at θr = 0.
    let at_zero = curves[0].points[0].1;
    assert!((curves[8].peak().1 - at_zero).abs() < 1e-12 * at_zero.max(1.0));
    assert!(
        (curves[0].peak().1 - 1.0).abs() < 1e-12,
        "normalised to the φr = 0 peak"
    );
    // The same holds for the series the drawn figure plots.
    let fig = crate::plot::figures::figure6().unwrap();
    assert_eq!(fig.series.len(), 9);
    let drawn: Vec<f64> = fig
        .series
        .iter()
        .map(|s| {
            s.points
                .iter()
                .copied()
                .max_by(|a, b| a.1.total_cmp(&b.1))
                .unwrap()
                .0
        })
        .collect();
    assert!(
        (drawn[0] - 45.0).abs() < 1e-9 && drawn[8].abs() < 1e-9,
        "{drawn:?}"
    );
    for w in drawn.windows(2) {
        assert!(w[1] < w[0], "drawn peaks move toward 0: {drawn:?}");
    }
}

#[test]
fn figure7_grid_peaks_at_the_mirror_and_is_symmetric_in_phi() {
    let g = figure7_grid(91, 181).unwrap();
    let (k, _) =
        g.z.iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .unwrap();
    let (i, j) = (k % g.xs.len(), k / g.xs.len());
    assert!((g.xs[i] - 45.0).abs() <= 1.0 && g.ys[j].abs() <= 2.0);
    let nx = g.xs.len();
    let ny = g.ys.len();
    for j in 0..ny {
        for i in 0..nx {
            let a = g.at(i, j);
            let b = g.at(i, ny - 1 - j);
            assert!((a - b).abs() <= 1e-12 * a.abs().max(1e-300) + 1e-300);
        }
    }
    // L(θr = 0) is 0.47 of the peak, so the 0.6 contour is a loop around the mirror
    // direction, away from the normal and from the back half.
    let segs = g.contour(0.6);
    assert!(!segs.is_empty());
    for (a, _) in segs {
        assert!(a.0 > 2.0 && a.0 < 89.0 && a.1.abs() < 90.0, "{a:?}");
    }
}

#[test]
fn pictures_render_to_valid_svg_and_bitmaps() {
    let fig4 = Figure4::new().unwrap();
    let svg = svg_string(&fig4).unwrap();
    assert_svg(&svg);
    assert!(svg.contains("T/σ = 10") && svg.contains("Lambertian"));
    assert!(
        svg.contains("data:image/png;base64,"),
        "spheres embedded as images"
    );
    let fig6 = crate::plot::figures::figure6().unwrap();
    let svg = svg_string(&fig6).unwrap();
    assert_svg(&svg);
    assert!(
        svg.contains("θr") && svg.contains("φr = π/2"),
        "axis label and legend"
    );
    let rgb = rgb_buffer(&fig6).unwrap();
    // The legend sits in a panel right of the 900 × 600 chart.
    let (w, h) = crate::plot::Picture::size(&fig6);
    assert!(w > 900 && h == 600, "{w} × {h}");
    assert_eq!(rgb.len(), (w * h * 3) as usize);
    assert!(rgb.iter().any(|&b| b < 128), "something is drawn");
}

/// A synthetic in-plane + out-of-plane dataset with its exact model values.
fn synthetic_fit() -> (Box<dyn Model>, Vec<f64>, Geometry, Vec<f64>) {
    let m = model("kbs");
    let params = vec![0.3, 2.0, 1.0];
    let mut samples = Vec::new();
    for ti in [20.0, 45.0, 60.0] {
        for tr in (0..=80).step_by(5) {
            samples.push(Sample::from_degrees(ti, tr as f64, 0.0));
            if tr > 0 {
                samples.push(Sample::from_degrees(ti, tr as f64, 180.0));
            }
        }
    }
    for tr in (10..=70).step_by(20) {
        for phi in [30.0, 60.0, 120.0] {
            samples.push(Sample::from_degrees(45.0, tr as f64, phi));
        }
    }
    let geo = Geometry::new(&samples, &[0.5], Quantity::Radiance).unwrap();
    let mut fitted = vec![0.0; geo.len()];
    m.eval(&geo, &params, &mut fitted, None);
    (m, params, geo, fitted)
}

/// `f` applied to the synthetic fit with measured values off the model by a relative
/// `wiggle` (a sine over the sample index) and residuals standardised by 3 %.
fn with_synthetic_input<R>(wiggle: f64, f: impl FnOnce(&FitPlotInput) -> R) -> R {
    let (m, params, geo, fitted) = synthetic_fit();
    let measured: Vec<f64> = fitted
        .iter()
        .enumerate()
        .map(|(k, v)| v * (1.0 + wiggle * ((k as f64) * 1.7).sin()))
        .collect();
    let res: Vec<f64> = measured
        .iter()
        .zip(&fitted)
        .map(|(m, f)| (m - f) / (0.03 * f.abs().max(1e-12)))
        .collect();
    f(&FitPlotInput {
        title: "kbs: sigma = 0.3, T = 2, scale = 1".into(),
        subtitle: "T/σ = 6.667; converged (xtol)".into(),
        model: m.as_ref(),
        params: &params,
        geo: &geo,
        measured: &measured,
        fitted: &fitted,
        std_residuals: &res,
        wavelength_unit: None,
        channels: Default::default(),
    })
}

#[test]
fn fit_plots_write_valid_files_with_a_hemisphere_per_incidence_angle() {
    with_synthetic_input(0.03, check_fit_plots);
}

fn check_fit_plots(input: &FitPlotInput) {
    let dir = tempfile::tempdir().unwrap();
    let paths = write_fit_plots(dir.path(), input).unwrap();
    // Six pictures and one hemisphere for each of the three incidence angles, PNG and SVG.
    assert_eq!(paths.len(), 18);
    for stem in [
        "fit_linear",
        "fit_log",
        "residuals_theta",
        "residuals_phi",
        "polar",
        "contour",
        "hemisphere_1",
        "hemisphere_2",
        "hemisphere_3",
    ] {
        let png = std::fs::read(dir.path().join(format!("{stem}.png"))).unwrap();
        let (w, h) = png_size(&png);
        assert!(w >= 800 && h >= 500);
        let svg = std::fs::read_to_string(dir.path().join(format!("{stem}.svg"))).unwrap();
        assert_svg(&svg);
        assert!(
            svg.contains("sigma = 0.3"),
            "{stem}: title names the parameters"
        );
    }
    // The polar plot's lobe peaks near the mirror direction of the busiest θi (45°).
    let polar = crate::plot::fit::polar_plot(input).unwrap();
    assert!((polar.theta_i.to_degrees() - 45.0).abs() < 1e-9);
    let peak = polar
        .curve
        .iter()
        .copied()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    assert!(peak.0 > 30.0 && peak.0 < 60.0, "peak at {peak:?}");
    // Mismatched lengths are a usage error, not a panic.
    let short = FitPlotInput {
        title: input.title.clone(),
        subtitle: input.subtitle.clone(),
        measured: &input.measured[..3],
        ..*input
    };
    assert!(write_fit_plots(dir.path(), &short).is_err());
}

#[test]
fn fit_plots_cope_with_awkward_data() {
    // Out-of-plane samples only, a BRDF, a flat model, a NaN residual and zero values.
    let m = model("lambert");
    let params = vec![0.2];
    let samples: Vec<Sample> = [(30.0, 10.0, 40.0), (30.0, 50.0, 45.0), (60.0, 20.0, 100.0)]
        .iter()
        .map(|&(a, b, c)| Sample::from_degrees(a, b, c))
        .collect();
    let geo = Geometry::new(&samples, &[1.0], Quantity::Brdf).unwrap();
    let mut fitted = vec![0.0; geo.len()];
    m.eval(&geo, &params, &mut fitted, None);
    let measured = vec![0.0, 0.21, 0.19];
    let res = vec![f64::NAN, 0.5, -0.5];
    let input = FitPlotInput {
        title: "lambert: scale = 0.2".into(),
        subtitle: String::new(),
        model: m.as_ref(),
        params: &params,
        geo: &geo,
        measured: &measured,
        fitted: &fitted,
        std_residuals: &res,
        wavelength_unit: None,
        channels: Default::default(),
    };
    let dir = tempfile::tempdir().unwrap();
    let paths = write_fit_plots(&dir.path().join("new/sub"), &input).unwrap();
    // Six pictures and a hemisphere for each of the two incidence angles.
    assert_eq!(paths.len(), 16);
    // Nearest-to-plane: the 30° group shows its sample at φr = 40° (nearest), not 45°.
    let chart = crate::plot::fit::fit_chart(&input, false).unwrap();
    let measured_pts: Vec<usize> = chart
        .series
        .iter()
        .filter(|s| s.label.is_none())
        .map(|s| s.points.len())
        .collect();
    assert_eq!(measured_pts, vec![1, 1]);
}

#[test]
fn polar_points_beyond_the_rim_are_counted_and_drawn_as_arrows() {
    use crate::plot::fit::PolarPlot;
    let pic = PolarPlot {
        title: "clipped".into(),
        subtitle: String::new(),
        theta_i: 45f64.to_radians(),
        curve: (0..=90).map(|t| (t as f64, 0.5)).collect(),
        measured: vec![(10.0, 0.5), (60.0, 3.0), (70.0, 12.5), (80.0, f64::NAN)],
        l_max: 2.0,
    };
    assert_eq!(pic.clipped(), (2, 12.5));
    let svg = crate::plot::svg_string(&pic).unwrap();
    assert!(
        svg.contains("2 measured beyond the rim (up to 12.5× L_max)"),
        "legend"
    );
    // The arrow on the 60° spoke stays clear of the spoke's label (they touched): every
    // vertex of the arrows more than the label's half-diagonal (~15 px) from its centre.
    let label = svg
        .split("<text")
        .find(|t| t.contains(">\n60°\n</text>") || t.contains(">60°</text>"))
        .expect("the 60° label");
    let attr = |name: &str| -> f64 {
        let v = label.split(&format!(" {name}=\"")).nth(1).unwrap();
        v[..v.find('"').unwrap()].parse().unwrap()
    };
    let (lx, ly) = (attr("x"), attr("y"));
    let red = svg
        .lines()
        .filter(|l| l.starts_with("<polyline") && l.contains("stroke=\"#D62728\""));
    let mut vertices = 0;
    for line in red {
        let pts = line.split("points=\"").nth(1).unwrap();
        for p in pts[..pts.find('"').unwrap()].split_whitespace() {
            let (x, y) = p.split_once(',').unwrap();
            let (x, y): (f64, f64) = (x.parse().unwrap(), y.parse().unwrap());
            let d = ((x - lx).powi(2) + (y - ly).powi(2)).sqrt();
            assert!(
                d > 17.0,
                "arrow vertex ({x}, {y}) {d:.1} px from the 60° label"
            );
            vertices += 1;
        }
    }
    assert!(
        vertices >= 10,
        "two arrows of five vertices (and the legend's): {vertices}"
    );
    // Nothing beyond the rim: no such legend entry.
    let inside = PolarPlot {
        measured: vec![(10.0, 0.5)],
        ..pic
    };
    assert_eq!(inside.clipped().0, 0);
    assert!(!crate::plot::svg_string(&inside)
        .unwrap()
        .contains("beyond the rim"));
}

/// `fit --plot` on the bundled real data: the SVG of each picture, by stem.
/// `args` start with the subcommand `fit`.
fn real_fit_pictures(args: &[&str]) -> std::collections::HashMap<String, String> {
    let dir = tempfile::tempdir().unwrap();
    common::goniofit()
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .args(["--no-intervals", "--quiet", "--plot"])
        .arg(dir.path())
        .assert()
        .code(0);
    [
        "fit_linear",
        "fit_log",
        "residuals_theta",
        "polar",
        "contour",
    ]
    .iter()
    .map(|s| {
        let svg = std::fs::read_to_string(dir.path().join(format!("{s}.svg"))).unwrap();
        assert_svg(&svg);
        (s.to_string(), svg)
    })
    .collect()
}

/// The text of every SVG `<text>` element.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("<text")
        .skip(1)
        .filter_map(|t| {
            let body = t.split_once('>')?.1;
            Some(body.split_once("</text>")?.0.trim().to_string())
        })
        .collect()
}

#[test]
fn a_paint_fit_linear_is_not_crushed_by_its_grazing_points() {
    // Garnet red at 550 nm: BRDF up to 28 sr⁻¹ at grazing angles, the lobe ≈ 0.5 sr⁻¹.
    let pics =
        real_fit_pictures(&[&common::GARNET_550[..], &["data/cornell/garnet_red.astm"]].concat());
    let lin = svg_texts(&pics["fit_linear"]);
    assert!(
        lin.iter()
            .any(|t| t.starts_with("4 measured above the top (up to 28.1")),
        "{lin:?}"
    );
    // The y ticks stop below 2 sr⁻¹ (not up to the 28.1 of the highest measured sample).
    let ticks: Vec<f64> = lin.iter().filter_map(|t| t.parse().ok()).collect();
    assert!(ticks.contains(&1.5) && !ticks.contains(&25.0), "{ticks:?}");
    // Every picture states T/σ, what is not determined and that the fit converged.
    for (stem, svg) in &pics {
        assert!(
            svg_texts(svg).iter().any(|t| t.starts_with("T/σ = 7.449 ±")
                && t.contains("not determined: σ, T, scale")
                && t.ends_with("converged (ftol)")),
            "{stem}"
        );
    }
}

/// The PTFE fit of the picture tests (before the file).
const PTFE_FIT: &[&str] = &["fit", "--model", "kbs+lambert", "--residual", "log"];

#[test]
fn ptfe_pictures_have_log_ticks_and_a_colour_bar() {
    // All four wavelengths: 24 (θi, λ) series, more than the 10 colours.
    let pics = real_fit_pictures(&[PTFE_FIT, &["data/nist-ptfe/PTFE.data.csv"]].concat());
    let log = svg_texts(&pics["fit_log"]);
    // The BRDF spans 0.27–0.5 sr⁻¹, under a decade: labelled ticks all the same.
    for tick in ["0.3", "0.35", "0.4", "0.45", "0.5"] {
        assert!(log.iter().any(|t| t == tick), "{tick}: {log:?}");
    }
    assert!(log.iter().any(|t| t == "colour: θi (degrees)"));
    for wl in ["0.351", "0.532", "0.633", "1.064"] {
        // With the file's unit (the PTFE lambda column is in µm).
        assert!(
            log.iter().any(|t| *t == format!("λ = {wl} µm fitted")),
            "{wl}"
        );
    }
    // No per-series legend lines (24 of them would repeat colours).
    assert!(!log.iter().any(|t| t.starts_with("θi = ")), "{log:?}");
    let res = svg_texts(&pics["residuals_theta"]);
    assert!(res.iter().any(|t| t == "colour: θi (degrees)"));
    // The residual sign, as the code, the residuals CSV and docs/conventions.md use it.
    assert!(res
        .iter()
        .any(|t| t == "standardized residual (fitted − measured) / u"));
    let conventions =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/conventions.md"))
            .unwrap();
    assert!(conventions.contains("Residual r = **fitted − measured**"));
    assert!(conventions.contains("**φr = 0 is the forward side**"));
}

#[test]
fn a_joint_fit_draws_every_channel_with_its_own_scales() {
    // PTFE `--channel all`: one joint fit, four channels (one per λ) with their own scales.
    let pics = real_fit_pictures(
        &[
            PTFE_FIT,
            &["--channel", "all", "data/nist-ptfe/PTFE.data.csv"],
        ]
        .concat(),
    );
    let log = svg_texts(&pics["fit_log"]);
    for wl in ["0.351", "0.532", "0.633", "1.064"] {
        assert!(
            log.iter().any(|t| *t == format!("λ = {wl} µm fitted")),
            "{wl}"
        );
        assert!(
            log.iter().any(|t| *t == format!("λ = {wl} µm measured")),
            "{wl}"
        );
    }
    assert!(
        log.iter()
            .any(|t| t.contains("(joint fit of 4 channels; scale, scale_d per channel)")),
        "{log:?}"
    );
    // 6 θi × 4 λ fitted curves: every channel is drawn, not the middle one alone: six
    // solid curves (λ = 0.351 µm) and the other three line styles in short pieces.
    let strokes: Vec<&str> = pics["fit_log"]
        .lines()
        .filter(|l| l.contains("stroke-linejoin=\"round\""))
        .collect();
    let solid = strokes
        .iter()
        .filter(|l| l.matches(',').count() > 100)
        .count();
    assert_eq!(solid, 6, "solid curves");
    assert!(strokes.len() > 6 + 3 * 6 * 10, "{} strokes", strokes.len());
    // The polar and contour maps show one θi of one channel, and say which.
    for stem in ["polar", "contour"] {
        let texts = svg_texts(&pics[stem]);
        assert!(
            texts
                .iter()
                .any(|t| t.contains("θi = 75° [channel 0.351µm]")),
            "{stem}: {texts:?}"
        );
    }
}

/// The (cx, cy) of the filled SVG circles left of `x_max` (the measured panel's dots; the
/// legend's grey sample glyph, #5A5A5A, left out).
fn filled_circles(svg: &str, x_max: f64) -> Vec<(f64, f64)> {
    let attr = |c: &str, name: &str| -> f64 {
        let i = c.find(&format!(" {name}=\"")).unwrap() + name.len() + 3;
        c[i..].split('"').next().unwrap().parse().unwrap()
    };
    svg.split("<circle")
        .skip(1)
        .filter(|c| {
            let head = c.split("/>").next().unwrap();
            !head.contains("fill=\"none\"") && !head.contains("fill=\"#5A5A5A\"")
        })
        .map(|c| (attr(c, "cx"), attr(c, "cy")))
        .filter(|p| p.0 < x_max)
        .collect()
}

#[test]
fn hemisphere_dots_land_where_the_projection_puts_the_samples() {
    use crate::plot::hemisphere::{hemisphere_plots, project, DISC_R};
    with_synthetic_input(0.03, |input| {
        let pics = hemisphere_plots(input).unwrap();
        assert_eq!(pics.len(), 3);
        let h45 = &pics[1];
        assert!((h45.theta_i.to_degrees() - 45.0).abs() < 1e-9);
        // θr = 30°, φr = 60°: (sin 30° cos 60°, sin 30° sin 60°) = (1/4, √3/4).
        let (x, y) = project(30f64.to_radians(), 60f64.to_radians());
        assert!((x - 0.25).abs() < 1e-15 && (y - 3f64.sqrt() / 4.0).abs() < 1e-15);
        assert!(h45
            .points
            .iter()
            .any(|p| (p.0 - 0.25).abs() < 1e-12 && (p.1 - 3f64.sqrt() / 4.0).abs() < 1e-12));
        // In the drawing: the θr = 0 sample is the disc's centre; the others sit at
        // centre + DISC_R (x, −y) pixels (y up), to the pixel.
        let svg = svg_string(h45).unwrap();
        let dots = filled_circles(&svg, 430.0);
        assert_eq!(dots.len(), h45.points.len());
        let centre = dots[h45
            .points
            .iter()
            .position(|p| p.0 == 0.0 && p.1 == 0.0)
            .unwrap()];
        for (p, d) in h45.points.iter().zip(&dots) {
            let want = (centre.0 + DISC_R * p.0, centre.1 - DISC_R * p.1);
            assert!(
                (d.0 - want.0).abs() <= 0.5 && (d.1 - want.1).abs() <= 0.5,
                "{p:?}: {d:?} vs {want:?}"
            );
        }
        // Measured and fitted share one scale; the values span two decades: logarithmic.
        assert!(h45.scale.log);
        assert!(svg.contains("log scale"));
    });
}

#[test]
fn hemisphere_pictures_are_capped_at_the_busiest_incidence_angles() {
    use crate::plot::hemisphere::{hemisphere_plots, MAX_HEMISPHERES};
    let m = model("lambert");
    let params = vec![0.2];
    // Six incidence angles; 60° and 10° have the most samples.
    let mut samples = Vec::new();
    for (ti, n) in [
        (0.0, 3),
        (10.0, 8),
        (20.0, 4),
        (30.0, 2),
        (50.0, 5),
        (60.0, 9),
    ] {
        for k in 0..n {
            samples.push(Sample::from_degrees(
                ti,
                5.0 + 8.0 * k as f64,
                20.0 * k as f64,
            ));
        }
    }
    let geo = Geometry::new(&samples, &[1.0], Quantity::Brdf).unwrap();
    let mut fitted = vec![0.0; geo.len()];
    m.eval(&geo, &params, &mut fitted, None);
    let res = vec![0.0; geo.len()];
    let input = FitPlotInput {
        title: "lambert".into(),
        subtitle: String::new(),
        model: m.as_ref(),
        params: &params,
        geo: &geo,
        measured: &fitted,
        fitted: &fitted,
        std_residuals: &res,
        wavelength_unit: None,
        channels: Default::default(),
    };
    let pics = hemisphere_plots(&input).unwrap();
    assert_eq!(pics.len(), MAX_HEMISPHERES);
    let angles: Vec<f64> = pics
        .iter()
        .map(|p| p.theta_i.to_degrees().round())
        .collect();
    assert_eq!(angles, vec![10.0, 20.0, 50.0, 60.0]);
    assert!(pics[0]
        .caption
        .contains("one of the 4 incidence angles with the most samples, of 6"));
    // A constant BRDF: a linear scale around its one value.
    assert!(!pics[0].scale.log);
}
