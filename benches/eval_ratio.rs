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

mod common;

use common::{geometry, sigma_for, N};
use goniofit::model::{kbs::Kbs, EvalMode, Model, ModelOptions};
use std::time::Instant;

const PAIRS: usize = 301;

fn quartiles(mut v: Vec<f64>) -> [f64; 3] {
    v.sort_by(f64::total_cmp);
    let q = |f: f64| v[((v.len() - 1) as f64 * f).round() as usize];
    [q(0.25), q(0.5), q(0.75)]
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return; // `cargo bench -- --list` asks the harness for its benchmarks
    }
    let model = |mode| {
        Kbs::new(ModelOptions {
            mode,
            ..Default::default()
        })
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
                let time = |m: &Kbs, out: &mut [f64], j: &mut [f64]| {
                    let t = Instant::now();
                    m.radiance(&geo, &p, out, jac.then_some(j));
                    t.elapsed().as_secs_f64() * 1e9 / N as f64
                };
                // Warm-up, then pairs.
                for _ in 0..5 {
                    time(&rough, &mut out, &mut j);
                    time(&auto, &mut out, &mut j);
                }
                let (mut tr, mut ta, mut ratio) = (Vec::new(), Vec::new(), Vec::new());
                for _ in 0..PAIRS {
                    let r = time(&rough, &mut out, &mut j);
                    let a = time(&auto, &mut out, &mut j);
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
