//! The RGL `.bsdf` reader against RGL's own loader (tests/ref/rgl_reference.cpp and its
//! output tests/ref/rgl_reference.csv): the measured points' directions and BRDF values,
//! and the interpolation at random directions, on every bundled file.

use crate::io::rgl::{RglBrdf, RglSample};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/rgl-epfl")
        .join(name)
}

/// One row of the reference table.
struct RefRow {
    kind: String,
    file: String,
    index: (usize, i64, i64),
    wi: [f64; 3],
    wo: [f64; 3],
    fr_cos: [f64; 3],
}

fn reference() -> Vec<RefRow> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/ref/rgl_reference.csv");
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            let num = |k: usize| f[k].parse::<f64>().unwrap();
            RefRow {
                kind: f[0].into(),
                file: f[1].into(),
                index: (
                    f[2].parse().unwrap(),
                    f[3].parse().unwrap(),
                    f[4].parse().unwrap(),
                ),
                wi: [num(5), num(6), num(7)],
                wo: [num(8), num(9), num(10)],
                fr_cos: [num(11), num(12), num(13)],
            }
        })
        .collect()
}

/// |a − b| within `rel` of |b|, or of `floor` for values near 0 (the loader runs in f32).
fn close(a: f64, b: f64, rel: f64, floor: f64) -> bool {
    (a - b).abs() <= rel * b.abs().max(floor)
}

const FILES: [&str; 7] = [
    "cc_ibiza_sunset_rgb.bsdf",
    "cc_iris_purple_gem_rgb.bsdf",
    "cg_sunflower_rgb.bsdf",
    "colodur_napoli_4f_rgb.bsdf",
    "paper_white_rgb.bsdf",
    "satin_rosaline_rgb.bsdf",
    "vch_golden_yellow_rgb.bsdf",
];

fn load(file: &str) -> RglBrdf {
    let p = data(file);
    RglBrdf::parse(&p, &std::fs::read(&p).unwrap()).unwrap()
}

/// Each measured point the loader maps a grid point to has the loader's direction (to
/// 1e-5) and BRDF (f_r·cos θo / cos θo, to 1e-5 relative), on every bundled file.
#[test]
fn measured_points_match_the_reference_loader() {
    let rows = reference();
    for file in FILES {
        let brdf = load(file);
        let mine: HashMap<(usize, usize, usize), RglSample> =
            brdf.samples().into_iter().map(|s| (s.index, s)).collect();
        let refs: Vec<&RefRow> = rows
            .iter()
            .filter(|r| r.kind == "grid" && r.file == file)
            .collect();
        assert!(refs.len() > 500, "{file}: {} reference points", refs.len());
        let scale = refs
            .iter()
            .map(|r| (r.fr_cos[1] / r.wo[2]).abs())
            .fold(0.0, f64::max);
        let mut unplaced = 0;
        let mut worst = 0.0f64;
        for r in &refs {
            let key = (r.index.0, r.index.1 as usize, r.index.2 as usize);
            if r.wo.iter().any(|v| v.is_nan()) {
                // The loader's f32 square root of a rounding-negative number at the grid's
                // last column: it cannot place this point. The reader clamps the radicand
                // at 0: a point it keeps is finite.
                if let Some(s) = mine.get(&key) {
                    assert!(
                        s.brdf.iter().chain(&s.wo).all(|v| v.is_finite()),
                        "{file} {key:?}"
                    );
                }
                unplaced += 1;
                continue;
            }
            let Some(s) = mine.get(&key) else {
                assert!(r.wo[2] < 1e-5, "{file} {key:?}: the loader has a point above the horizon ({:?}), the reader none", r.wo);
                continue;
            };
            for k in 0..3 {
                assert!(
                    (s.wo[k] - r.wo[k]).abs() < 1e-5,
                    "{file} {key:?}: wo {:?} vs the loader's {:?}",
                    s.wo,
                    r.wo
                );
                let want = r.fr_cos[k] / r.wo[2];
                worst = worst.max((s.brdf[k] - want).abs() / want.abs().max(1e-3 * scale));
                assert!(
                    close(s.brdf[k], want, 1e-5, 1e-3 * scale),
                    "{file} {key:?} channel {k}: {} vs the loader's {want}",
                    s.brdf[k]
                );
            }
        }
        println!("{file}: {} points, largest relative difference {worst:.2e}, {unplaced} the loader cannot place", refs.len());
        assert!(
            unplaced * 100 <= refs.len(),
            "{file}: {unplaced} points the loader cannot place"
        );
    }
}

/// The interpolation at random pairs of directions matches the loader's eval (f_r·cos θo)
/// to 1e-5 relative, on every bundled file.
#[test]
fn evaluation_at_random_directions_matches_the_reference_loader() {
    let rows = reference();
    for file in FILES {
        let brdf = load(file);
        let refs: Vec<&RefRow> = rows
            .iter()
            .filter(|r| r.kind == "random" && r.file == file)
            .collect();
        assert_eq!(refs.len(), 150, "{file}");
        let scale = refs.iter().map(|r| r.fr_cos[1].abs()).fold(0.0, f64::max);
        for r in &refs {
            let got = brdf.eval_cos(r.wi, r.wo);
            for (k, (&g, &want)) in got.iter().zip(&r.fr_cos).enumerate() {
                assert!(
                    close(g, want, 1e-5, 1e-3 * scale),
                    "{file} pair {}: channel {k}: {g} vs the loader's {want}",
                    r.index.0
                );
            }
            let f = brdf.eval(r.wi, r.wo);
            assert!(
                close(f[1] * r.wo[2], got[1], 1e-12, 1e-300),
                "{file}: eval is eval_cos / cos θo"
            );
        }
    }
}

/// Read as a dataset: one channel's measured points as BRDF (1/sr) at the channel's
/// nominal wavelength; white paper's BRDF near normal incidence is that of a diffuser with
/// a reflectance of 0.7–1 (f_r = ρ/π).
#[test]
fn white_paper_reads_as_a_near_lambertian_brdf() {
    use crate::io::{read_dataset, ReadOptions};
    let path = data("paper_white_rgb.bsdf");
    let opts = ReadOptions {
        channel: Some("g".into()),
        require_value: true,
        ..Default::default()
    };
    let ds = read_dataset(&path, &opts).unwrap();
    assert_eq!(ds.len(), load("paper_white_rgb.bsdf").samples().len());
    assert_eq!(ds.quantity, Some(crate::geometry::Quantity::Brdf));
    assert!(ds.wavelength.as_ref().unwrap().iter().all(|&w| w == 549.0));
    let values = ds.value.as_ref().unwrap();
    let mut normal: Vec<f64> = (0..ds.len())
        .filter(|&k| ds.samples[k].theta_i == 0.0 && ds.samples[k].theta_r < 0.8)
        .map(|k| values[k])
        .collect();
    normal.sort_by(f64::total_cmp);
    let median = normal[normal.len() / 2];
    assert!(
        (0.7 / std::f64::consts::PI..1.0 / std::f64::consts::PI).contains(&median),
        "median {median}"
    );
    // Every angle in goniofit's domain; the specular direction of θi = 0 is θr = 0.
    for s in &ds.samples {
        assert!(
            s.theta_i < std::f64::consts::FRAC_PI_2 && s.theta_r <= std::f64::consts::FRAC_PI_2
        );
        assert!(s.phi_r.abs() <= std::f64::consts::PI);
    }
    let all = ReadOptions {
        channel: Some("all".into()),
        ..opts.clone()
    };
    assert_eq!(read_dataset(&path, &all).unwrap().len(), 3 * ds.len());
    let none = ReadOptions {
        channel: None,
        ..opts
    };
    let err = read_dataset(&path, &none).unwrap_err().to_string();
    assert!(err.contains("r, g, b"), "{err}");
}

/// The byte position of field `name`'s shape (its first dimension) in a tensor file.
fn shape_at(bytes: &[u8], name: &str) -> usize {
    let mut needle = (name.len() as u16).to_le_bytes().to_vec();
    needle.extend_from_slice(name.as_bytes());
    let at = bytes
        .windows(needle.len())
        .position(|w| w == needle)
        .unwrap();
    at + needle.len() + 2 + 1 + 8
}

/// Anisotropic, foreign and damaged files are refused with the field, the byte offset and
/// what was expected.
#[test]
fn unreadable_files_are_located() {
    use crate::io::{read_bytes, ReadOptions};
    let good = std::fs::read(data("paper_white_rgb.bsdf")).unwrap();
    let opts = ReadOptions {
        channel: Some("r".into()),
        ..Default::default()
    };
    let read = |bytes: &[u8]| {
        read_bytes(Path::new("x.bsdf"), bytes, &opts)
            .unwrap_err()
            .to_string()
    };

    let mut aniso = good.clone();
    let at = shape_at(&aniso, "phi_i");
    aniso[at] = 2;
    let err = read(&aniso);
    assert!(
        err.contains("'phi_i'") && err.contains("anisotropic") && err.contains("byte"),
        "{err}"
    );

    let mut magic = good.clone();
    magic[0] = b'T';
    assert!(read(&magic).contains("byte 0: magic"), "{}", read(&magic));

    let err = read(&good[..300]);
    assert!(
        err.contains("beyond the end of the file") || err.contains("the file ends"),
        "{err}"
    );

    let mut spectral = good.clone();
    let at = spectral
        .windows(5)
        .position(|w| w == b"\x03\x00rgb")
        .unwrap();
    spectral[at + 2..at + 5].copy_from_slice(b"xyz");
    let err = read(&spectral);
    assert!(err.contains("'rgb' is missing"), "{err}");
    let at = spectral.windows(7).position(|w| w == b"version").unwrap();
    spectral[at..at + 7].copy_from_slice(b"spectra");
    let err = read(&spectral);
    assert!(
        err.contains("'spectra'") && err.contains("a spectral file") && err.contains("byte"),
        "{err}"
    );

    let mut nan = good.clone();
    let at = shape_at(&nan, "theta_i");
    let offset = u64::from_le_bytes(nan[at - 8..at].try_into().unwrap()) as usize;
    nan[offset + 4..offset + 8].copy_from_slice(&f32::NAN.to_le_bytes());
    let err = read(&nan);
    assert!(
        err.contains("'theta_i'") && err.contains(&format!("byte {}", offset + 4)),
        "{err}"
    );
}
