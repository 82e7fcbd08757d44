use goniofit::geometry::{Geometry, Quantity, Sample};
use goniofit::model::{by_name, EvalMode, ModelOptions};
use std::time::Instant;
fn main() {
    let mut s = Vec::new();
    for i in 0..8 {
        for j in 0..8 {
            for k in 0..8 {
                s.push(Sample::from_degrees(
                    5.0 + 10.0 * i as f64,
                    5.0 + 11.0 * j as f64,
                    -180.0 + 45.0 * k as f64,
                ));
            }
        }
    }
    let geo = Geometry::new(&s, &[1.0], Quantity::Radiance).unwrap();
    for (mode, tol) in [
        (EvalMode::Auto, 1e-4),
        (EvalMode::Auto, 1e-10),
        (EvalMode::Rough, 1e-4),
        (EvalMode::Series, 1e-10),
    ] {
        let m = by_name(
            "kbs",
            &ModelOptions {
                mode,
                tol,
                patch: None,
            },
        )
        .unwrap();
        let mut out = vec![0.0; s.len()];
        let mut jac = vec![0.0; 3 * s.len()];
        for sig in [0.002, 0.01, 0.05, 0.25, 1.0, 4.0] {
            let mut line = format!("{mode:?} {tol:e} sigma={sig}:");
            for t in [0.02, 0.2, 2.0, 20.0, 400.0] {
                let t0 = Instant::now();
                for _ in 0..20 {
                    m.eval(&geo, &[sig, t, 1.0], &mut out, Some(&mut jac));
                }
                let ns = t0.elapsed().as_nanos() as f64 / 20.0 / s.len() as f64;
                line += &format!(" T={t}:{ns:.0}ns");
            }
            println!("{line}");
        }
    }
}
