//! Instructions per sample of `series::ln_q_batch` in `auto` mode, counted by callgrind
//! (exact and repeatable, unlike times on a shared machine). Same hemisphere batch as
//! `benches/eval_ratio.rs` (T/σ = 5, σ such that g = G at c = 1.5).
//!
//! ```sh
//! cargo bench --bench lnq_instructions --no-run
//! valgrind --tool=callgrind --toggle-collect=goniofit::model::series::ln_q_batch \
//!     target/release/deps/lnq_instructions-<hash> 100
//! ```
//! counts only inside `ln_q_batch`; divide the `Collected` total by the
//! [`REPS`] × 10 000 samples this prints. Without valgrind (as `cargo bench` runs it) it
//! prints the time per sample of each regime, a rough check only: `eval_ratio` is the
//! timing benchmark.

mod common;

use common::{geometry, sigma_for, N};
use goniofit::series::{self, LnQ};
use goniofit::EvalMode;
use std::time::Instant;

/// Evaluations of the batch per regime.
const REPS: usize = 10;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--list") {
        return; // `cargo bench -- --list` asks the harness for its benchmarks
    }
    // `cargo bench` passes `--bench`; any number given is a regime.
    let mut regimes: Vec<f64> = args.iter().filter_map(|a| a.parse().ok()).collect();
    if regimes.is_empty() {
        regimes = vec![0.01, 1.0, 100.0, 1e4];
    }
    let geo = geometry(false, 7);
    for g0 in regimes {
        let sigma = sigma_for(g0);
        let g: Vec<f64> = (0..N).map(|i| geo.g(i, sigma)).collect();
        let a: Vec<f64> = (0..N).map(|i| geo.a(i, 5.0 * sigma)).collect();
        let mut out = vec![series::rough(1.0, 0.0); N];
        let t = Instant::now();
        for _ in 0..REPS {
            series::ln_q_batch(&g, &a, EvalMode::Auto, 1e-10, &mut out);
        }
        let ns = t.elapsed().as_secs_f64() * 1e9 / (REPS * N) as f64;
        let check: f64 = out.iter().map(|q: &LnQ| q.ln_q).sum();
        println!(
            "g≈{g0}: {} samples of ln_q_batch (auto, tol 1e-10), {ns:.1} ns/sample; Σ ln Q = {check:.6e}",
            REPS * N
        );
    }
}
