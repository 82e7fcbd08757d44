//! The sample batches the evaluation benchmarks share (`benches/eval.rs`,
//! `benches/eval_ratio.rs`).

use goniofit::{Geometry, Quantity, Sample};
use rand::{Rng, SeedableRng};

/// Samples per batch.
pub const N: usize = 10_000;

/// A batch of [`N`] samples, λ = 1: the hemisphere (θi, θr uniform in [0°, 60°], φr in
/// [0°, 360°)), or with `lobe` views within 10° of the mirror direction (θi in [10°, 50°]).
pub fn geometry(lobe: bool, seed: u64) -> Geometry {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let samples: Vec<Sample> = (0..N)
        .map(|_| {
            if lobe {
                let ti: f64 = rng.gen_range(10.0..50.0);
                let tr = (ti + rng.gen_range(-10.0..10.0f64)).clamp(0.0, 90.0);
                let pr: f64 = rng.gen_range(-10.0..10.0);
                Sample::from_degrees(ti, tr, pr)
            } else {
                Sample::from_degrees(
                    rng.gen_range(0.0..60.0),
                    rng.gen_range(0.0..60.0),
                    rng.gen_range(0.0..360.0),
                )
            }
        })
        .collect();
    Geometry::new(&samples, &[1.0], Quantity::Radiance).unwrap()
}

/// σ (λ = 1) such that g = target at c = cos θi + cos θr = 1.5.
pub fn sigma_for(g: f64) -> f64 {
    g.sqrt() / 1.5 / (2.0 * std::f64::consts::PI)
}
