//! `fit --by-group --warm-start` against the plain batch on a texture of regions: each fit
//! started at its neighbour's optimum must end where the start search ends (the reference:
//! the same batch fitted without `--warm-start`), across the jumps between regions of
//! different roughness, for every residual kind and with a diffuse term.

use crate::common;
use common::goniofit;
use std::fmt::Write as _;

/// A region of the texture: how many texels, and the ranges σ (λ), T/σ and scale are drawn
/// from (uniform, seeded).
struct Region {
    texels: usize,
    sigma: (f64, f64),
    ratio: (f64, f64),
}

/// Regions in spatial order: intermediate, smoother and narrower, intermediate again, rough
/// (only T/σ and the amplitude determined), smoother, rough. Every boundary is a jump of
/// the optimum that a warm start must survive.
const REGIONS: [Region; 6] = [
    Region {
        texels: 8,
        sigma: (0.20, 0.30),
        ratio: (8.0, 12.0),
    },
    Region {
        texels: 8,
        sigma: (0.08, 0.12),
        ratio: (20.0, 30.0),
    },
    Region {
        texels: 5,
        sigma: (0.20, 0.30),
        ratio: (8.0, 12.0),
    },
    Region {
        texels: 8,
        sigma: (1.0, 2.0),
        ratio: (3.0, 5.0),
    },
    Region {
        texels: 5,
        sigma: (0.08, 0.12),
        ratio: (20.0, 30.0),
    },
    Region {
        texels: 5,
        sigma: (1.0, 2.0),
        ratio: (3.0, 5.0),
    },
];

/// A small linear congruential generator: the texture is the same on every machine.
struct Lcg(u64);

impl Lcg {
    fn uniform(&mut self, (lo, hi): (f64, f64)) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        lo + (hi - lo) * ((self.0 >> 11) as f64 / (1u64 << 53) as f64)
    }
}

/// The texture as one CSV with a `group` column (texels `t00`, `t01`, … in spatial order),
/// each texel an in-plane scan (θi = 30°, 60°; θr to 80° in 5° steps) of `model` with 1 %
/// relative noise; `extra`: further parameters (e.g. the diffuse scale).
fn texture(dir: &std::path::Path, model: &str, extra: &str) -> std::path::PathBuf {
    let mut rng = Lcg(7);
    let mut out = String::from("theta_i,theta_r,phi_r,L,group\n");
    let one = dir.join("one.csv");
    let mut k = 0;
    for region in &REGIONS {
        for _ in 0..region.texels {
            let sigma = rng.uniform(region.sigma);
            let t = sigma * rng.uniform(region.ratio);
            let scale = rng.uniform((0.5, 2.0));
            let params = format!("sigma={sigma},T={t},scale={scale}{extra}");
            goniofit()
                .args([
                    "synth",
                    "--model",
                    model,
                    "--params",
                    &params,
                    "--wavelength",
                    "1",
                ])
                .args([
                    "--layout",
                    "inplane theta_i=30,60 max=80 step=5",
                    "--noise",
                    "0.01",
                ])
                .args(["--seed", &(100 + k).to_string(), "--out"])
                .arg(&one)
                .assert()
                .success();
            let text = std::fs::read_to_string(&one).unwrap();
            for line in text.lines().skip(1) {
                let cols: Vec<&str> = line.split(',').collect();
                writeln!(out, "{},t{k:02}", cols[..4].join(",")).unwrap();
            }
            k += 1;
        }
    }
    let path = dir.join("texture.csv");
    std::fs::write(&path, out).unwrap();
    path
}

/// The batch's fits (cost, converged, start, chosen model) in the texture's order.
fn batch(path: &std::path::Path, args: &[&str]) -> Vec<(f64, bool, String, String)> {
    let out = goniofit()
        .args([
            "fit",
            "--by-group",
            "--wavelength",
            "1",
            "--json",
            "--quiet",
            "--threads",
            "2",
        ])
        .args(args)
        .arg(path)
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    v["fits"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| {
            let cost = f["cost"].as_f64().unwrap();
            let start = f["start_from"].as_str().unwrap().to_string();
            let model = format!("{}{}", f["model"], f["factors"]);
            (cost, f["converged"].as_bool().unwrap(), start, model)
        })
        .collect()
}

/// Every texel's warm-started fit of `fit_model` (on a texture of `model`) chooses the
/// searched fit's model, ends at a cost no higher than the searched one's (to 1e-6
/// relative) and converges where it does; most texels keep their warm start.
fn check((model, fit_model): (&str, &str), extra: &str, args: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let path = texture(dir.path(), model, extra);
    let mut base = vec!["--model", fit_model];
    base.extend_from_slice(args);
    let searched = batch(&path, &base);
    base.push("--warm-start");
    let warm = batch(&path, &base);
    let n: usize = REGIONS.iter().map(|r| r.texels).sum();
    assert_eq!((searched.len(), warm.len()), (n, n));
    for (k, (s, w)) in searched.iter().zip(&warm).enumerate() {
        assert_eq!(
            s.2, "search",
            "t{k:02}: without --warm-start every fit is searched"
        );
        assert!(
            w.0 <= s.0 * (1.0 + 1e-6),
            "{fit_model} {args:?} t{k:02}: warm cost {} above the searched {} (start {})",
            w.0,
            s.0,
            w.2
        );
        assert_eq!(
            w.1, s.1,
            "{fit_model} {args:?} t{k:02}: converged differs (start {})",
            w.2
        );
    }
    let near = warm.iter().filter(|w| w.2 == "neighbour").count();
    assert!(
        2 * near >= n,
        "{fit_model} {args:?}: only {near} of {n} fits kept their warm start"
    );
}

#[test]
fn warm_started_kbs_fits_end_where_the_search_does_for_every_residual_kind() {
    for residual in ["absolute", "relative", "log"] {
        check(("kbs", "kbs"), "", &["--residual", residual]);
    }
}

#[test]
fn warm_started_fits_with_a_diffuse_term_end_where_the_search_does() {
    let model = ("kbs+lambert", "kbs+lambert");
    check(model, ",scale_d=0.02", &["--residual", "relative"]);
}

#[test]
fn warm_started_auto_fits_choose_the_searched_model() {
    check(
        ("kbs+lambert", "auto"),
        ",scale_d=0.02",
        &["--residual", "relative"],
    );
}
