//! Throughput of model evaluation, per model and per KBS regime.
//!
//! `cargo bench --bench eval`. Batches of 10 000 samples built with `Geometry::new`:
//! θi, θr uniform in [0°, 60°], φr uniform in [0°, 360°) (so c = cos θi + cos θr ∈ [1, 2]
//! and g varies by at most 4× within a batch), λ = 1. Regime "g≈G": σ chosen so that g = G
//! at c = 1.5 (g ∈ [0.44 G, 1.8 G]); T/σ = 5 as in the paper's Figures 6–7, so
//! b = a/g = 6.25 v_xy²/c² spans 0..≈20 over the hemisphere. A second geometry set,
//! "lobe", keeps the view within 10° of the mirror direction (where a gonioreflectometer
//! puts most samples of a glossy surface): b ≲ 0.2.
//!
//! Groups: `kbs_hemi/<regime>/<mode>` and `kbs_lobe/<regime>/<mode>` (whole-model radiance;
//! modes series, rough, smooth, auto, and rough+jac, auto+jac with the Jacobian),
//! `lnq_hemi/<regime>/<mode>` (the sum ln Q alone, as a batch: `series::ln_q_batch`), and
//! `models/<name>/{values,jacobian}`
//! for the other models, and `kbs_factors/<regime>/<factors>` (the lobe with its Fresnel and
//! shadowing factors beside the plain one). Throughput is reported in samples/s; the target is auto/rough ≤ 4
//! in every regime.

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
mod common;

use common::{geometry, sigma_for, N};
use goniofit::{series, EvalMode, ModelOptions};
use std::time::Duration;

const REGIMES: [(&str, f64); 4] = [
    ("g=0.01", 0.01),
    ("g=1", 1.0),
    ("g=100", 100.0),
    ("g=1e4", 1e4),
];
const MODES: [(&str, EvalMode); 4] = [
    ("series", EvalMode::Series),
    ("rough", EvalMode::Rough),
    ("smooth", EvalMode::Smooth),
    ("auto", EvalMode::Auto),
];

fn bench_kbs(c: &mut Criterion) {
    for (set, lobe) in [("hemi", false), ("lobe", true)] {
        let geo = geometry(lobe, 7);
        let mut group = c.benchmark_group(format!("kbs_{set}"));
        group
            .sample_size(20)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(2))
            .throughput(Throughput::Elements(N as u64));
        for (rname, g) in REGIMES {
            let sigma = sigma_for(g);
            let p = [sigma, 5.0 * sigma, 1.0];
            for (mname, mode) in MODES {
                let m = goniofit::model(
                    "kbs",
                    &ModelOptions {
                        mode,
                        ..Default::default()
                    },
                )
                .unwrap();
                let mut out = vec![0.0; N];
                group.bench_function(BenchmarkId::new(rname, mname), |b| {
                    b.iter(|| m.radiance(&geo, &p, &mut out, None))
                });
            }
            // With the Jacobian, as a fit evaluates it.
            for (mname, mode) in [("rough+jac", EvalMode::Rough), ("auto+jac", EvalMode::Auto)] {
                let m = goniofit::model(
                    "kbs",
                    &ModelOptions {
                        mode,
                        ..Default::default()
                    },
                )
                .unwrap();
                let mut out = vec![0.0; N];
                let mut jac = vec![0.0; 3 * N];
                group.bench_function(BenchmarkId::new(rname, mname), |b| {
                    b.iter(|| m.radiance(&geo, &p, &mut out, Some(&mut jac)))
                });
            }
        }
        group.finish();
    }
}

fn bench_lnq(c: &mut Criterion) {
    let geo = geometry(false, 7);
    let mut group = c.benchmark_group("lnq_hemi");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(N as u64));
    for (rname, g0) in REGIMES {
        let sigma = sigma_for(g0);
        let g: Vec<f64> = (0..N).map(|i| geo.g(i, sigma)).collect();
        let a: Vec<f64> = (0..N).map(|i| geo.a(i, 5.0 * sigma)).collect();
        let mut out = vec![series::rough(1.0, 0.0); N];
        for (mname, mode) in MODES {
            group.bench_function(BenchmarkId::new(rname, mname), |b| {
                b.iter(|| series::ln_q_batch(&g, &a, mode, 1e-10, &mut out))
            });
        }
    }
    group.finish();
}

fn bench_models(c: &mut Criterion) {
    let geo = geometry(false, 7);
    let mut group = c.benchmark_group("models");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(N as u64));
    let sigma = sigma_for(1.0);
    for (name, p) in [
        ("lambert", vec![1.0]),
        ("lambert-specular", vec![1.0, 1.0, 0.1]),
        ("kbs+lambert", vec![sigma, 5.0 * sigma, 1.0, 0.3]),
    ] {
        let m = goniofit::model(name, &ModelOptions::default()).unwrap();
        let mut out = vec![0.0; N];
        let mut jac = vec![0.0; p.len() * N];
        group.bench_function(BenchmarkId::new(name, "values"), |b| {
            b.iter(|| m.radiance(&geo, &p, &mut out, None))
        });
        group.bench_function(BenchmarkId::new(name, "jacobian"), |b| {
            b.iter(|| m.radiance(&geo, &p, &mut out, Some(&mut jac)))
        });
    }
    group.finish();
}

/// The KBS lobe with and without its Fresnel and shadowing factors, side by side
/// (`kbs_factors/<regime>/<factors>[+jac]`, `auto` mode, hemisphere set): the target is
/// the extended lobe within 1.5× of the plain one.
fn bench_factors(c: &mut Criterion) {
    use goniofit::{Fresnel, Shadowing};
    let geo = geometry(false, 7);
    let mut group = c.benchmark_group("kbs_factors");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(N as u64));
    for (rname, g) in REGIMES {
        let sigma = sigma_for(g);
        for (fname, fresnel, shadowing) in [
            ("plain", Fresnel::None, Shadowing::None),
            ("dielectric+smith", Fresnel::Dielectric, Shadowing::Smith),
            (
                "conductor+smith-correlated",
                Fresnel::Conductor,
                Shadowing::SmithCorrelated,
            ),
        ] {
            let m = goniofit::model(
                "kbs",
                &ModelOptions {
                    fresnel,
                    shadowing,
                    ..Default::default()
                },
            )
            .unwrap();
            let p = [sigma, 5.0 * sigma, 1.0, 1.5, 2.0];
            let p = &p[..3 + fresnel.param_count()];
            let mut out = vec![0.0; N];
            let mut jac = vec![0.0; p.len() * N];
            group.bench_function(BenchmarkId::new(rname, fname), |b| {
                b.iter(|| m.radiance(&geo, p, &mut out, None))
            });
            group.bench_function(BenchmarkId::new(rname, format!("{fname}+jac")), |b| {
                b.iter(|| m.radiance(&geo, p, &mut out, Some(&mut jac)))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_kbs, bench_lnq, bench_models, bench_factors);
criterion_main!(benches);
