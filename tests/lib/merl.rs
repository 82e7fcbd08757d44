//! The MERL `.binary` reader on a file written here from a known analytic BRDF, following
//! the layout and lookup of MERL's reference reader (BRDFRead.cpp): the values come back
//! at 1e-6 and a fit recovers the function's parameters.

use crate::common;

use crate::fit::driver::{fit, FitConfig, FitInput};
use crate::geometry::{Geometry, Quantity, Sample};
use crate::io::{merl, read_dataset, ReadOptions};
use std::f64::consts::{FRAC_PI_2, PI};
use std::io::Write;

/// The analytic BRDF (1/sr): goniofit's lambert-specular in BRDF form, s + lobe / cos θi.
fn brdf(s: &Sample, p: [f64; 3]) -> f64 {
    let [scale, b, w] = p;
    let q = ((s.theta_r - s.theta_i) / w).powi(2) + (s.phi_r / (2.0 * w)).powi(2);
    scale + b / (w * (2.0 * PI).sqrt()) * (-0.5 * q).exp() / s.theta_i.cos()
}

/// Per channel (r, g, b): scale, B, w.
const TRUTH: [[f64; 3]; 3] = [[0.05, 0.4, 0.15], [0.08, 0.3, 0.2], [0.11, 0.2, 0.25]];

/// The reference reader's cell lookup, written from its published source.
fn reference_cell(theta_h: f64, theta_d: f64, mut phi_d: f64) -> usize {
    let th = if theta_h <= 0.0 {
        0
    } else {
        (((theta_h / FRAC_PI_2) * 90.0 * 90.0).sqrt() as i64).clamp(0, 89) as usize
    };
    let td = ((theta_d / FRAC_PI_2 * 90.0) as i64).clamp(0, 89) as usize;
    if phi_d < 0.0 {
        phi_d += PI;
    }
    let pd = ((phi_d / PI * 180.0) as i64).clamp(0, 179) as usize;
    pd + td * 180 + th * 180 * 90
}

/// Angles of a pair of directions in goniofit's convention.
fn sample_of(wi: [f64; 3], wo: [f64; 3]) -> Sample {
    let phi_i = wi[1].atan2(wi[0]);
    let mut phi_r = wo[1].atan2(wo[0]) - phi_i - PI;
    while phi_r <= -PI {
        phi_r += 2.0 * PI;
    }
    while phi_r > PI {
        phi_r -= 2.0 * PI;
    }
    Sample {
        theta_i: wi[2].acos(),
        theta_r: wo[2].min(1.0).acos(),
        phi_r,
    }
}

/// Write the MERL file: each cell's centre directions land in that cell by the reference
/// lookup; below-horizon cells and every 101st cell are marked unmeasured (−1).
fn write_merl(path: &std::path::Path) -> usize {
    let mut tables = vec![vec![-1.0f64; merl::CELLS]; 3];
    let mut measured = 0;
    for i in 0..90 {
        for j in 0..90 {
            for k in 0..180 {
                let cell = k + 180 * (j + 90 * i);
                let (th, td, pd) = merl::cell_centre(i, j, k);
                let (wi, wo) = merl::directions(th, td, pd);
                let (h2, d2, p2) = merl::half_diff(wi, wo);
                assert_eq!(reference_cell(h2, d2, p2), cell, "cell ({i}, {j}, {k})");
                if wi[2] <= 1e-9 || wo[2] <= 0.0 || cell % 101 == 0 {
                    continue;
                }
                measured += 1;
                let s = sample_of(wi, wo);
                for c in 0..3 {
                    tables[c][cell] = brdf(&s, TRUTH[c]) / merl::SCALES[c];
                }
            }
        }
    }
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for d in [90i32, 90, 180] {
        f.write_all(&d.to_le_bytes()).unwrap();
    }
    for t in &tables {
        for v in t {
            f.write_all(&v.to_le_bytes()).unwrap();
        }
    }
    measured
}

#[test]
fn a_written_merl_file_reads_back_and_fits() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("analytic.binary");
    let measured = write_merl(&path);
    assert_eq!(std::fs::metadata(&path).unwrap().len(), merl::FILE_BYTES);
    for (c, name) in ["r", "g", "b"].iter().enumerate() {
        let opts = ReadOptions {
            channel: Some(name.to_string()),
            require_value: true,
            ..Default::default()
        };
        let ds = read_dataset(&path, &opts).unwrap();
        assert_eq!(ds.len(), measured, "channel {name}");
        assert_eq!(ds.quantity, Some(Quantity::Brdf));
        let v = ds.value.as_ref().unwrap();
        for (s, &got) in ds.samples.iter().zip(v) {
            let want = brdf(s, TRUTH[c]);
            assert!(
                (got - want).abs() <= 1e-6 * want,
                "channel {name} at {s:?}: {got} vs {want}"
            );
        }
    }
    // The fit: every 3rd θd and φd cell of channel g, lambert-specular as a BRDF.
    let opts = ReadOptions {
        channel: Some("g".into()),
        require_value: true,
        ..Default::default()
    };
    let ds = merl::read_path(&path, &opts, 3).unwrap();
    assert!(
        ds.len() * 8 < measured && ds.len() > 10_000,
        "{} of {measured}",
        ds.len()
    );
    let lambda = vec![549.0; ds.len()];
    let geo = Geometry::new(&ds.samples, &lambda, Quantity::Brdf).unwrap();
    let n = geo.len();
    let input = FitInput {
        geo,
        y: ds.value.clone().unwrap().into(),
        weight: vec![1.0; n].into(),
        channel: vec![0; n].into(),
        channel_names: vec!["g".into()],
    };
    let config = FitConfig {
        model: "lambert-specular".into(),
        residual: crate::fit::problem::ResidualKind::Relative,
        ..FitConfig::default()
    };
    let r = fit(&input, &config).unwrap();
    assert!(r.converged());
    for (name, truth) in ["scale", "B", "w"].iter().zip(TRUTH[1]) {
        let p = r.params.iter().find(|p| p.name == *name).unwrap();
        assert!(
            (p.value - truth).abs() <= 1e-6 * truth,
            "{name}: {} vs {truth}",
            p.value
        );
    }
    // The same subsampling on the command line: convert writes those samples, one row each;
    // a file that is not MERL refuses it.
    let out = dir.path().join("g.csv");
    common::success_stdout(&[
        "convert",
        "--channel",
        "g",
        "--subsample",
        "3",
        "--out",
        out.to_str().unwrap(),
        path.to_str().unwrap(),
    ]);
    let text = std::fs::read_to_string(&out).unwrap();
    let rows = text.lines().filter(|l| !l.starts_with('#')).count();
    assert_eq!(rows, ds.len() + 1, "a header and one row per sample");
    let csv = common::data("angles_inplane.csv");
    let refused = common::goniofit()
        .args(["convert", "--subsample", "3", csv.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(refused.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&refused.stderr).contains("MERL tables only"));
}

/// A file of the wrong size or dimensions is refused with what was expected.
#[test]
fn damaged_merl_files_are_located() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("short.binary");
    let mut bytes = Vec::new();
    for d in [90i32, 90, 180] {
        bytes.extend_from_slice(&d.to_le_bytes());
    }
    bytes.extend_from_slice(&[0u8; 800]);
    std::fs::write(&path, &bytes).unwrap();
    let opts = ReadOptions {
        channel: Some("r".into()),
        ..Default::default()
    };
    let err = read_dataset(&path, &opts).unwrap_err().to_string();
    assert!(
        err.contains(&format!("expected {} bytes", merl::FILE_BYTES)),
        "{err}"
    );
    bytes[4] = 91;
    std::fs::write(&path, &bytes).unwrap();
    let err = read_dataset(&path, &opts).unwrap_err().to_string();
    assert!(
        err.contains("byte 4: dimension 1: expected 90") && err.contains("found 91"),
        "{err}"
    );
}
