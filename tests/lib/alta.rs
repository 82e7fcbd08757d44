//! ALTA text data: every parametrization read back to the geometry and values it was
//! written from (the file written here from directions with ALTA's published
//! `from_cartesian` formulas, independently of the reader's `to_cartesian` direction), the
//! output kinds, the uncertainty columns, located errors, mutation, and a fit that agrees
//! with the same samples read from CSV.

use crate::common;

use crate::io::{read_bytes, Dataset, ReadOptions};
use proptest::prelude::*;
use std::f64::consts::PI;
use std::path::Path;

/// A BRDF that tells θi from θr and the mirror side from the back side.
fn brdf(ti: f64, tr: f64, pr: f64) -> f64 {
    0.1 + 0.5 * ti.cos() + 0.3 * tr.cos().powi(2) + 0.2 * tr.sin() * pr.cos()
}

/// Geometries (θi, θr, φr) in goniofit's convention, all above the horizon.
fn geometries() -> Vec<(f64, f64, f64)> {
    let mut g = Vec::new();
    for ti in [0.05, 0.4, 0.9, 1.3] {
        for tr in [0.0, 0.3, 0.8, 1.45] {
            for pr in [0.0, 0.7, 2.0, -2.6, PI] {
                g.push((ti, tr, pr));
            }
        }
    }
    g
}

/// View and light unit vectors of a geometry (light at azimuth 0, view at φr + π).
fn vectors(ti: f64, tr: f64, pr: f64) -> ([f64; 3], [f64; 3]) {
    let pv = pr + PI;
    (
        [tr.sin() * pv.cos(), tr.sin() * pv.sin(), tr.cos()],
        [ti.sin(), 0.0, ti.cos()],
    )
}

/// ALTA's Rusinkiewicz coordinates (θh, φh, θd, φd) of a view and light pair: the half
/// vector, and the view rotated by −φh about z, then by −θh about y.
fn rusin(v: [f64; 3], l: [f64; 3]) -> [f64; 4] {
    let h = [v[0] + l[0], v[1] + l[1], v[2] + l[2]];
    let n = (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]).sqrt();
    let h = h.map(|x| x / n);
    let (th, ph) = (h[2].acos(), h[1].atan2(h[0]));
    let (s, c) = (-ph).sin_cos();
    let d = [c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]];
    let (s, c) = (-th).sin_cos();
    let d = [c * d[0] + s * d[2], d[1], -s * d[0] + c * d[2]];
    [th, ph, d[2].clamp(-1.0, 1.0).acos(), d[1].atan2(d[0])]
}

/// The input values of a geometry in parametrization `param`.
fn inputs(param: &str, (ti, tr, pr): (f64, f64, f64)) -> Vec<f64> {
    let (v, l) = vectors(ti, tr, pr);
    let pv = pr + PI;
    match param {
        "SPHERICAL_TL_PL_TV_PV" => vec![ti, 0.0, tr, pv],
        "ISOTROPIC_TV_TL_DPHI" => vec![tr, ti, -pv],
        "ISOTROPIC_TL_TV_PROJ_DPHI" => vec![ti, tr * pv.cos(), tr * pv.sin()],
        "RUSIN_TH_TD_PD" => {
            let r = rusin(v, l);
            vec![r[0], r[2], r[3]]
        }
        "RUSIN_TH_PH_TD_PD" => rusin(v, l).to_vec(),
        "CARTESIAN" => vec![v[0], v[1], v[2], 2.0 * l[0], 2.0 * l[1], 2.0 * l[2]],
        _ => unreachable!(),
    }
}

const PARAMS: [&str; 6] = [
    "SPHERICAL_TL_PL_TV_PV",
    "ISOTROPIC_TV_TL_DPHI",
    "ISOTROPIC_TL_TV_PROJ_DPHI",
    "RUSIN_TH_TD_PD",
    "RUSIN_TH_PH_TD_PD",
    "CARTESIAN",
];

/// An ALTA file of `brdf` at every geometry in `param`, one output.
fn alta_file(param: &str, out: &str, vs: Option<u8>) -> String {
    let dim = inputs(param, (0.1, 0.2, 0.3)).len();
    let mut s = format!("#DIM {dim} 1\n#PARAM_IN {param}\n#PARAM_OUT {out}\n");
    if let Some(v) = vs {
        s += &format!("#VS {v}\n");
    }
    for g in geometries() {
        let mut f = brdf(g.0, g.1, g.2);
        if out == "INV_STERADIAN_COSINE_FACTOR" {
            f *= g.1.cos();
        }
        let x: Vec<String> = inputs(param, g)
            .iter()
            .map(|v| format!("{v:.17e}"))
            .collect();
        s += &format!("{} {f:.17e}", x.join(" "));
        match vs {
            Some(2) => s += &format!(" {:.17e} {:.17e}", f * 0.9, f * 1.1),
            Some(1) => s += " 0.05",
            _ => {}
        }
        s += "\n";
    }
    s
}

fn read(text: &str, channel: Option<&str>) -> crate::error::Result<Dataset> {
    let opts = ReadOptions {
        channel: channel.map(String::from),
        require_value: true,
        ..Default::default()
    };
    read_bytes(Path::new("brdf.data"), text.as_bytes(), &opts)
}

/// Each sample read holds the angles of its row and the BRDF there (1e-12).
fn check_values(ds: &Dataset) {
    let values = ds.value.as_ref().unwrap();
    for (s, v) in ds.samples.iter().zip(values) {
        let want = brdf(s.theta_i, s.theta_r, s.phi_r);
        assert!((v - want).abs() < 1e-12, "{s:?}: {v} vs {want}");
    }
}

#[test]
fn every_parametrization_reads_back_its_geometry_and_values() {
    for param in PARAMS {
        let ds = read(&alta_file(param, "INV_STERADIAN", None), None).unwrap();
        let g = geometries();
        assert_eq!(ds.len(), g.len(), "{param}");
        for (s, &(ti, tr, pr)) in ds.samples.iter().zip(&g) {
            assert!((s.theta_i - ti).abs() < 1e-12, "{param} θi {s:?} {ti}");
            assert!((s.theta_r - tr).abs() < 1e-12, "{param} θr {s:?} {tr}");
            if tr > 1e-9 {
                let d = (s.phi_r - pr).rem_euclid(2.0 * PI);
                assert!(d.min(2.0 * PI - d) < 1e-9, "{param} φr {s:?} {pr}");
            }
        }
        check_values(&ds);
        assert!(ds.sigma_l.is_none() && ds.wavelength.is_none() && ds.channel.is_none());
        assert_eq!(ds.lines[0], 4, "the first data row is line 4");
    }
}

#[test]
fn cosine_weighted_values_are_divided_by_the_view_cosine() {
    let ds = read(
        &alta_file("SPHERICAL_TL_PL_TV_PV", "INV_STERADIAN_COSINE_FACTOR", None),
        None,
    )
    .unwrap();
    assert_eq!(ds.len(), geometries().len());
    check_values(&ds);
}

#[test]
fn vertical_segments_give_the_standard_uncertainty() {
    for vs in [1u8, 2] {
        let ds = read(&alta_file("CARTESIAN", "INV_STERADIAN", Some(vs)), None).unwrap();
        let (v, s, w) = (
            ds.value.as_ref().unwrap(),
            ds.sigma_l.as_ref().unwrap(),
            ds.weight.as_ref().unwrap(),
        );
        let rel = if vs == 2 { 0.1 } else { 0.05 };
        for k in 0..v.len() {
            assert!(
                (s[k] - rel * v[k]).abs() < 1e-12 * v[k],
                "VS {vs}: {} {}",
                s[k],
                v[k]
            );
            assert!((w[k] * s[k] * s[k] - 1.0).abs() < 1e-12);
        }
    }
}

#[test]
fn three_outputs_are_the_rgb_channels() {
    let mut s =
        String::from("#DIM 4 3\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN\n");
    s += "0.5 0 0.5 3.14159 0.1 0.2 0.3\n0.5 0 0.6 3.0 0.4 0.5 0.6\n";
    let refused = read(&s, None).unwrap_err().to_string();
    assert!(
        refused.contains("--channel") && refused.contains("r, g, b"),
        "{refused}"
    );
    let g = read(&s, Some("g")).unwrap();
    assert_eq!(g.value.as_ref().unwrap(), &vec![0.2, 0.5]);
    assert_eq!(g.wavelength.as_ref().unwrap(), &vec![549.0, 549.0]);
    let all = read(&s, Some("all")).unwrap();
    assert_eq!(all.len(), 6);
    assert_eq!(all.channel_names(), vec!["r", "g", "b"]);
    assert_eq!(
        all.value.as_ref().unwrap(),
        &vec![0.1, 0.4, 0.2, 0.5, 0.3, 0.6]
    );
}

#[test]
fn rows_below_the_horizon_are_skipped() {
    let s = "#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN\n\
             0.5 0 0.5 3.1 1\n0.5 0 1.7 3.1 2\n1.6 0 0.5 3.1 3\n";
    let ds = read(s, None).unwrap();
    assert_eq!(ds.value.unwrap(), vec![1.0]);
    let none =
        "#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN\n1.6 0 0.5 0 1\n";
    assert!(read(none, None)
        .unwrap_err()
        .to_string()
        .contains("above the horizon"));
}

/// Each malformed file is refused with its line and what was expected.
#[test]
fn malformed_files_name_the_line() {
    let head = "#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN\n";
    let cases: Vec<(String, &str, &str)> = vec![
        (
            head.replace("SPHERICAL_TL_PL_TV_PV", "STARK_2D") + "1 2 3 4 5\n",
            "brdf.data:2:",
            "STARK_2D",
        ),
        (
            head.replace("INV_STERADIAN", "RGB_COLOR") + "1 2 3 4 5\n",
            "brdf.data:3:",
            "RGB_COLOR",
        ),
        (
            head.replace("#DIM 4 1", "#DIM 3 1") + "1 2 3 4\n",
            "brdf.data:4:",
            "has 4",
        ),
        (
            head.to_string() + "0.1 0 0.2 0 0.5\n0.1 0 0.2 0.5\n",
            "brdf.data:5:",
            "4 numbers",
        ),
        (
            head.to_string() + "0.1 0 0.2 nan 0.5\n",
            "brdf.data:4:",
            "not finite",
        ),
        (
            head.to_string() + "0.1 0 0.2 x 0.5\n",
            "brdf.data:4:",
            "'x' is not a number",
        ),
        (
            head.replace("#PARAM_IN SPHERICAL_TL_PL_TV_PV\n", "") + "1 2 3 4 5\n",
            "brdf.data:3:",
            "#PARAM_IN",
        ),
        (
            head.to_string() + "#VS 2\n0.1 0 0.2 0 0.5 0.6 0.4\n",
            "brdf.data:5:",
            "positive width",
        ),
        (
            "#DIM x\n1 2\n".to_string(),
            "brdf.data:1:",
            "#DIM inputs outputs",
        ),
    ];
    for (text, line, what) in cases {
        let m = read(&text, None).unwrap_err().to_string();
        assert!(
            m.contains(line) && m.contains(what),
            "{m}\n--- for:\n{text}"
        );
    }
    let empty = read(head, None).unwrap_err().to_string();
    assert!(empty.contains("no data rows"), "{empty}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Any bytes of a valid file changed: a dataset of finite angles and values, or an
    /// error that names a line or the file.
    #[test]
    fn mutated_alta_files_never_panic(edits in proptest::collection::vec((0usize..4000, any::<u8>()), 1..8)) {
        let mut bytes = alta_file("RUSIN_TH_TD_PD", "INV_STERADIAN", Some(2)).into_bytes();
        for (at, b) in edits {
            let n = bytes.len();
            bytes[at % n] = b;
        }
        let opts = ReadOptions { require_value: true, channel: Some("all".into()), ..Default::default() };
        match read_bytes(Path::new("m.data"), &bytes, &opts) {
            Ok(ds) => {
                prop_assert!(!ds.is_empty());
                for (s, v) in ds.samples.iter().zip(ds.value.as_ref().unwrap()) {
                    prop_assert!(s.theta_i.is_finite() && s.theta_r.is_finite() && s.phi_r.is_finite() && v.is_finite());
                    prop_assert!(s.theta_i < std::f64::consts::FRAC_PI_2 && s.theta_r < std::f64::consts::FRAC_PI_2);
                }
                for s in ds.sigma_l.iter().flatten() {
                    prop_assert!(s.is_finite() && *s > 0.0);
                }
            }
            Err(e) => {
                let m = e.to_string();
                prop_assert!(m.contains("m.data:") || m.contains("m.data"), "{}", m);
            }
        }
    }
}

/// The same samples fitted from an ALTA file and from a CSV file give the same fit.
#[test]
fn a_fit_of_alta_data_equals_the_fit_of_the_same_csv() {
    let dir = tempfile::tempdir().unwrap();
    let mut csv = String::from("# quantity: brdf\ntheta_i,theta_r,phi_r,L\n");
    let mut alta =
        String::from("#DIM 4 1\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT INV_STERADIAN\n");
    for ti in [10.0f64, 30.0, 50.0] {
        for k in 0..30 {
            let (tr, pr) = (-80.0 + 160.0 * k as f64 / 29.0, 0.0f64);
            let (tr, pr) = if tr < 0.0 { (-tr, 180.0) } else { (tr, pr) };
            let l = 0.02 + (-((tr - ti).powi(2) / 200.0)).exp() * (1.0 + 0.01 * (k % 3) as f64);
            csv += &format!("{ti},{tr},{pr},{l:.15e}\n");
            let (ti_r, tr_r) = (ti.to_radians(), tr.to_radians());
            alta += &format!(
                "{ti_r:.17e} 0 {tr_r:.17e} {:.17e} {l:.15e}\n",
                (pr + 180.0).to_radians()
            );
        }
    }
    let (c, a) = (dir.path().join("s.csv"), dir.path().join("s.data"));
    std::fs::write(&c, csv).unwrap();
    std::fs::write(&a, alta).unwrap();
    let fit = |p: &Path| {
        common::fit_json(&[
            "fit",
            "--json",
            "--model",
            "lambert-specular",
            "--no-intervals",
            p.to_str().unwrap(),
        ])
    };
    let (jc, ja) = (fit(&c), fit(&a));
    let (pc, pa) = (&jc["params"], &ja["params"]);
    for name in ["scale", "B", "w"] {
        let (x, y) = (pc[name]["value"].as_f64(), pa[name]["value"].as_f64());
        let (x, y) = (x.unwrap_or(f64::NAN), y.unwrap_or(f64::NAN));
        assert!(
            (x - y).abs() <= 1e-6 * x.abs().max(1e-12),
            "{name}: {x} vs {y}\n{jc}\n{ja}"
        );
    }
}
