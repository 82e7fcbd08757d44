//! Time per sample of `series::auto` against the plain sum (`series::series`, every term)
//! where neither the smooth nor the asymptotic evaluation applies: a = s g^1.5 with s ≥ 3.5
//! (far from the specular direction on a rough surface), g from 60 to 7e5. There `auto`
//! sums every h-th term where the terms' peak is wide (h ≥ 8, `src/model/series/strided.rs`)
//! and every term otherwise; this shows where the stride starts to pay. Batches of 1000
//! samples (`ln_q_batch`, as the models call it; the peak search included), the two
//! interleaved per (g, s), median of 5 runs each.
//!
//! ```sh
//! cargo bench --bench off_specular
//! ```

use goniofit::series;
use goniofit::EvalMode;
use std::time::Instant;

/// Samples per batch, and batches per timing run.
const BATCH: usize = 1000;
const BATCHES: usize = 20;

/// Median over 5 runs of the time per sample of `mode` on a batch at (g, a).
fn ns_per_sample(mode: EvalMode, g: f64, a: f64) -> f64 {
    let gs: Vec<f64> = (0..BATCH).map(|i| g * (1.0 + i as f64 * 1e-9)).collect();
    let az = vec![a; BATCH];
    let mut out = vec![series::rough(1.0, 0.0); BATCH];
    let mut runs: Vec<f64> = (0..5)
        .map(|_| {
            let t = Instant::now();
            for _ in 0..BATCHES {
                series::ln_q_batch(&gs, &az, mode, 1e-10, &mut out);
                std::hint::black_box(&out);
            }
            t.elapsed().as_secs_f64() * 1e9 / (BATCH * BATCHES) as f64
        })
        .collect();
    runs.sort_by(f64::total_cmp);
    runs[2]
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return; // `cargo bench -- --list` asks the harness for its benchmarks
    }
    println!(
        "{:>9} {:>6} {:>12} {:>12} {:>7}",
        "g", "s", "auto ns", "plain ns", "ratio"
    );
    for g in [60.0, 200.0, 400.0, 1e3, 1e4, 1e5, 7e5] {
        for s in [3.5, 30.0, 300.0] {
            let a = s * g * f64::sqrt(g);
            let ta = ns_per_sample(EvalMode::Auto, g, a);
            let tp = ns_per_sample(EvalMode::Series, g, a);
            println!("{g:>9} {s:>6} {ta:>12.0} {tp:>12.0} {:>7.2}", tp / ta);
        }
    }
}
