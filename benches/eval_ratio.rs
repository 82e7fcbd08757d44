//! auto/rough cost ratio per KBS regime, measured pairwise: each repetition times the rough
//! approximation and then `auto` on the same 10k-sample batch, and the ratio is taken per
//! pair, so that the machine's slow and fast phases (which move criterion's separately
//! measured medians by ±20 % on a shared machine) cancel. Same batches as `benches/eval.rs`
//! (hemisphere: θi, θr ∈ [0°, 60°], φr ∈ [0°, 360°); lobe: within 10° of the mirror;
//! T/σ = 5; σ such that g = G at c = 1.5).
//!
//! `cargo bench --bench eval_ratio` prints, per geometry and regime, the median time per
//! sample of each mode and the median and quartiles of the per-pair ratio, for values and
//! with the Jacobian. The target is auto/rough ≤ 4 in every regime.
//!
//! `cargo bench --bench eval_ratio -- factors` times the lobe with its Fresnel and
//! shadowing factors against the plain lobe the same way (`auto` mode, in pairs: plain,
//! then with the factors; n = 1.5, κ = 2), on the hemisphere set (every sample its own
//! polar angles) and on the angles of a measured file (Cornell's garnet red: 18 distinct
//! polar angles, over which Smith's Λ is shared): the target is extended/plain ≤ 1.5 in
//! every regime, for values and with the Jacobian. A further argument names the one
//! combination to time (`-- factors smith`).

mod common;

use common::{geometry, sigma_for, N};
use goniofit::{EvalMode, Fresnel, Geometry, Model, ModelOptions, Shadowing};
use std::time::Instant;

const PAIRS: usize = 301;

fn quartiles(mut v: Vec<f64>) -> [f64; 3] {
    v.sort_by(f64::total_cmp);
    let q = |f: f64| v[((v.len() - 1) as f64 * f).round() as usize];
    [q(0.25), q(0.5), q(0.75)]
}

/// Median time per sample (ns) of `a` and `b` at their parameters on `geo`, each pair timed
/// back to back, and the quartiles of the per-pair ratio b/a.
fn pairs(
    geo: &Geometry,
    a: (&dyn Model, &[f64]),
    b: (&dyn Model, &[f64]),
    jac: bool,
) -> (f64, f64, [f64; 3]) {
    let n = geo.len();
    let mut out = vec![0.0; n];
    let mut j = vec![0.0; 5 * n];
    let mut time = |(m, p): (&dyn Model, &[f64])| {
        let t = Instant::now();
        let cols = &mut j[..p.len() * n];
        m.radiance(geo, p, &mut out, jac.then_some(cols));
        t.elapsed().as_secs_f64() * 1e9 / n as f64
    };
    for _ in 0..5 {
        time(a);
        time(b);
    }
    let (mut ta, mut tb, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..PAIRS {
        let x = time(a);
        let y = time(b);
        ta.push(x);
        tb.push(y);
        ratio.push(y / x);
    }
    (quartiles(ta)[1], quartiles(tb)[1], quartiles(ratio))
}

/// The factors' cost: plain against the dielectric factor alone, Smith alone, dielectric +
/// Smith and conductor + correlated Smith.
fn factors() {
    let model = |fresnel, shadowing| {
        goniofit::model(
            "kbs",
            &ModelOptions {
                fresnel,
                shadowing,
                ..Default::default()
            },
        )
        .unwrap()
    };
    let plain = model(Fresnel::None, Shadowing::None);
    for (layout, geo) in [
        ("random", geometry(false, 7)),
        ("cornell", cornell_layout()),
    ] {
        println!("{layout} layout ({} samples)", geo.len());
        factors_on(&geo, plain.as_ref(), &model);
    }
}

/// The angles of Cornell's garnet red paint (data/cornell/garnet_red.astm, 1439 samples at
/// 8 incidence and 10 view polar angles), λ = 1.
fn cornell_layout() -> Geometry {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/cornell/garnet_red.astm");
    let opts = goniofit::ReadOptions {
        channel: Some("550nm".into()),
        ..Default::default()
    };
    let ds = goniofit::read(&path, &opts).expect("the bundled Cornell file");
    Geometry::new(&ds.samples, &[1.0], goniofit::Quantity::Radiance).unwrap()
}

/// [`factors`] on one layout.
fn factors_on(
    geo: &Geometry,
    plain: &dyn Model,
    model: &dyn Fn(Fresnel, Shadowing) -> Box<dyn Model>,
) {
    println!("factors                     g     jac   plain ns  ext ns   ratio: q1  median  q3");
    for (name, fresnel, shadowing) in [
        ("dielectric", Fresnel::Dielectric, Shadowing::None),
        ("smith", Fresnel::None, Shadowing::Smith),
        ("dielectric+smith", Fresnel::Dielectric, Shadowing::Smith),
        (
            "conductor+smith-correlated",
            Fresnel::Conductor,
            Shadowing::SmithCorrelated,
        ),
    ] {
        if !std::env::args()
            .skip(1)
            .all(|a| a == "factors" || a.starts_with('-') || name == a)
        {
            continue;
        }
        let ext = model(fresnel, shadowing);
        for g in [0.01, 1.0, 100.0, 1e4] {
            let sigma = sigma_for(g);
            let p = [sigma, 5.0 * sigma, 1.0, 1.5, 2.0];
            let pe = &p[..3 + fresnel.param_count()];
            for jac in [false, true] {
                let (a, b, [q1, med, q3]) = pairs(geo, (plain, &p[..3]), (ext.as_ref(), pe), jac);
                println!(
                    "{name:<27} {g:<6} {:<5} {a:>8.1} {b:>7.1}   {q1:>9.2} {med:>7.2} {q3:>5.2}",
                    if jac { "yes" } else { "no" },
                );
            }
        }
    }
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return; // `cargo bench -- --list` asks the harness for its benchmarks
    }
    if std::env::args().any(|a| a == "factors") {
        return factors();
    }
    let model = |mode| {
        goniofit::model(
            "kbs",
            &ModelOptions {
                mode,
                ..Default::default()
            },
        )
        .unwrap()
    };
    let (rough, auto) = (model(EvalMode::Rough), model(EvalMode::Auto));
    println!("geometry    g     jac   rough ns  auto ns   ratio: q1  median  q3");
    for (set, lobe) in [("hemisphere", false), ("lobe", true)] {
        let geo = geometry(lobe, 7);
        for g in [0.01, 1.0, 100.0, 1e4] {
            let sigma = sigma_for(g);
            let p = [sigma, 5.0 * sigma, 1.0];
            for jac in [false, true] {
                let mut out = vec![0.0; N];
                let mut j = vec![0.0; 3 * N];
                let time = |m: &dyn Model, out: &mut [f64], j: &mut [f64]| {
                    let t = Instant::now();
                    m.radiance(&geo, &p, out, jac.then_some(j));
                    t.elapsed().as_secs_f64() * 1e9 / N as f64
                };
                // Warm-up, then pairs.
                for _ in 0..5 {
                    time(rough.as_ref(), &mut out, &mut j);
                    time(auto.as_ref(), &mut out, &mut j);
                }
                let (mut tr, mut ta, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
                for _ in 0..PAIRS {
                    let r = time(rough.as_ref(), &mut out, &mut j);
                    let a = time(auto.as_ref(), &mut out, &mut j);
                    tr.push(r);
                    ta.push(a);
                    ratio.push(a / r);
                }
                let [q1, med, q3] = quartiles(ratio);
                println!(
                    "{set:<10} {g:<6} {:<5} {:>8.1} {:>8.1}   {q1:>9.2} {med:>7.2} {q3:>5.2}",
                    if jac { "yes" } else { "no" },
                    quartiles(tr)[1],
                    quartiles(ta)[1],
                );
            }
        }
    }
}
