//! Synthetic measurements: a model evaluated at known parameters on a measurement layout,
//! with seeded, reproducible noise. Used by `goniofit synth`, by the recovery tests and by
//! the work-precision benchmarks.
//!
//! The pipeline is
//!
//! ```text
//! Layout ──angles()──▶ [AnglesDeg] ──generate(model, params, λ, quantity, noise)──▶ SynthData
//!                                        exact = model.eval(...)   value = exact + noise
//! ```
//!
//! **Angles are kept in degrees**, as they are written to the CSV, and every sample the
//! model sees is [`Sample::from_degrees`](crate::geometry::Sample::from_degrees) of exactly those numbers. So a file written with
//! [`SynthData::write_csv`] and read back by any reader that parses the degrees and calls
//! `Sample::from_degrees` evaluates to the `exact` column bit for bit.
//!
//! # Layouts ([`Layout`])
//! | layout | θi (degrees) | θr (degrees) | φr (degrees) | default size |
//! |---|---|---|---|---|
//! | `inplane` | the given list (default 15, 30, 45, 60, 75) | signed, k·`step` for \|k·step\| ≤ max (default −85 … 85 step 1) | 0, or 180 for θr < 0 | 5 × 171 = 855 |
//! | `hemisphere` | `n_theta_i` cell midpoints of [0, 90) | `n_theta_r` cell midpoints of (0, 90) | `n_phi_r` points −180 + 360 l/n in [−180, 180) | 5 × 18 × 36 = 3240 |
//! | `grazing` | `n_theta_i` evenly from 70 to 89 inclusive (89 alone if n = 1) | as hemisphere | as hemisphere | 5 × 18 × 36 = 3240 |
//! | a CSV file | columns `theta_i,theta_r,phi_r` in degrees (a signed θr < 0 means \|θr\| at φr + 180) | | | its rows |
//!
//! In-plane samples with θr < 0 are stored as θr = |θr| at φr = 180° (docs/conventions.md). The CSV
//! writer can put them back as signed θr at φr = 0 ([`CsvOptions::signed_theta_r`]).
//!
//! # Noise ([`Noise`], [`NoiseKind`])
//! With z ~ N(0, 1) independent per sample, ε = `level` and M = max |exact| over the batch:
//!
//! | kind | value | σ_L (standard deviation) |
//! |---|---|---|
//! | `relative` | L (1 + ε z) | ε \|L\| |
//! | `absolute` | L + ε M z | ε M (ε is a fraction of the peak, so it is scale-free) |
//! | `poisson` | L + ε √(\|L\| M) z | ε √(\|L\| M) (variance ∝ L, equal to the absolute kind's at the peak) |
//!
//! Values are not clipped at zero: clipping would bias the mean, and background-subtracted
//! real data go negative too. `level = 0` gives the exact values (and σ_L = 0).
//! The generator is `rand`'s `StdRng` seeded with `seed`, drawing one z per sample in layout
//! order: the same seed, layout and goniofit build give the same bits on every run.
//!
//! # Example
//! ```
//! use goniofit::synth::{generate, Layout, Noise, NoiseKind};
//! use goniofit::{model, parse_params, ModelOptions, Quantity};
//!
//! let model = model("kbs", &ModelOptions::default())?;
//! let params = parse_params(model.as_ref(), "sigma=0.3,T=2,scale=1")?;
//! let layout = Layout::parse("hemisphere 5x18x36")?;
//! let noise = Noise { kind: NoiseKind::Relative, level: 0.01, seed: 1 };
//! let data = generate(model.as_ref(), &params, &layout.angles(), 1.0, Quantity::Radiance, &noise)?;
//! assert_eq!(data.len(), 3240);
//! assert!((data.value[0] / data.exact[0] - 1.0).abs() < 0.1);
//! # Ok::<(), goniofit::Error>(())
//! ```

mod noise;
mod output;
#[cfg(test)]
mod tests;

pub use crate::geometry::layout::*;
pub use noise::*;
pub use output::*;
