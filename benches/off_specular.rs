//! Time per sample of `series::auto` against the plain sum (`series::series`, every term)
//! where neither the smooth nor the asymptotic evaluation applies: a = s g^1.5 with s ≥ 3.5
//! (far from the specular direction on a rough surface), g from 60 to 7e5. There `auto`
//! sums every h-th term where the terms' peak is wide (h ≥ 8, `src/model/series/strided.rs`)
//! and every term otherwise; this shows where the stride starts to pay. One sample per call
//! (the peak search included), the two interleaved per (g, s), median of 5 runs each.
//!
//! ```sh
//! cargo bench --bench off_specular
//! ```

use goniofit::model::series;
use std::time::Instant;

/// Calls per timing run.
const CALLS: usize = 20_000;

fn ns_per_call(f: &dyn Fn(f64, f64) -> f64, g: f64, a: f64) -> f64 {
    let mut runs: Vec<f64> = (0..5)
        .map(|_| {
            let t = Instant::now();
            let mut x = 0.0;
            for i in 0..CALLS {
                x += f(g * (1.0 + i as f64 * 1e-9), a);
            }
            std::hint::black_box(x);
            t.elapsed().as_secs_f64() * 1e9 / CALLS as f64
        })
        .collect();
    runs.sort_by(f64::total_cmp);
    runs[2]
}

fn main() {
    if std::env::args().any(|a| a == "--list") {
        return; // `cargo bench -- --list` asks the harness for its benchmarks
    }
    let auto = |g, a| series::auto(g, a, 1e-10).ln_q;
    let plain = |g, a| series::series(g, a, 1e-10).ln_q;
    println!(
        "{:>9} {:>6} {:>12} {:>12} {:>7}",
        "g", "s", "auto ns", "plain ns", "ratio"
    );
    for g in [60.0, 200.0, 400.0, 1e3, 1e4, 1e5, 7e5] {
        for s in [3.5, 30.0, 300.0] {
            let a = s * g * f64::sqrt(g);
            let (ta, tp) = (ns_per_call(&auto, g, a), ns_per_call(&plain, g, a));
            println!("{g:>9} {s:>6} {ta:>12.0} {tp:>12.0} {:>7.2}", tp / ta);
        }
    }
}
