//! NIST StRD suite: goniofit's LM against the `levenberg-marquardt` crate (rust-cv, a MINPACK
//! port on nalgebra 0.34) on the same 54 runs (27 problems × 2 starts), same analytic
//! Jacobians, same process.
//!
//! `cargo bench --bench nist` (repeats: `NIST_BENCH_REPEATS`, default 21).
//!
//! Settings: goniofit with the NIST test settings (`ftol = xtol = 1e-15`, `gtol = 0`, up to
//! 10 000 evaluations, Gauss–Newton polishing on); the `levenberg-marquardt` crate with its
//! own defaults (`ftol = xtol = gtol = 30ε ≈ 6.7e-15`, the tightest it accepts without
//! reporting `NoImprovementPossible`) and `patience = 2000` (up to 2000·(n+1) evaluations, so
//! the budget never decides). Reported: residual and Jacobian evaluations (counted in the
//! problem wrappers), worst-parameter LRE per run, and the wall time of the whole suite as
//! the median over the repeats (the two solvers interleaved run by run); ratios are goniofit / levenberg-marquardt.

#[path = "../tests/lib/nist/problems.rs"]
mod problems;

use goniofit::lm::{minimize, LeastSquaresProblem as _, LmConfig};
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use nalgebra::{DMatrix, DVector, Dyn, Owned};
use problems::{lre, Nist};
use std::cell::Cell;
use std::path::Path;
use std::time::Instant;

/// The same problem in the `levenberg-marquardt` crate's stateful form, counting evaluations.
struct Theirs<'a> {
    p: &'a Nist,
    x: DVector<f64>,
    nres: Cell<u64>,
    njac: Cell<u64>,
}

impl LeastSquaresProblem<f64, Dyn, Dyn> for Theirs<'_> {
    type ResidualStorage = Owned<f64, Dyn>;
    type JacobianStorage = Owned<f64, Dyn, Dyn>;
    type ParameterStorage = Owned<f64, Dyn>;

    fn set_params(&mut self, x: &DVector<f64>) {
        self.x.copy_from(x);
    }
    fn params(&self) -> DVector<f64> {
        self.x.clone()
    }
    fn residuals(&self) -> Option<DVector<f64>> {
        self.nres.set(self.nres.get() + 1);
        Some(self.p.residuals(&self.x))
    }
    fn jacobian(&self) -> Option<DMatrix<f64>> {
        self.njac.set(self.njac.get() + 1);
        Some(self.p.jacobian(&self.x))
    }
}

/// The same problem for goniofit, counting evaluations the same way.
struct Ours<'a> {
    p: &'a Nist,
    nres: Cell<u64>,
    njac: Cell<u64>,
}

impl goniofit::lm::LeastSquaresProblem for Ours<'_> {
    fn residuals(&self, x: &DVector<f64>) -> DVector<f64> {
        self.nres.set(self.nres.get() + 1);
        self.p.residuals(x)
    }
    fn jacobian(&self, x: &DVector<f64>) -> DMatrix<f64> {
        self.njac.set(self.njac.get() + 1);
        self.p.jacobian(x)
    }
}

#[derive(Clone, Copy, Default)]
struct Outcome {
    nres: u64,
    njac: u64,
    lre: f64,
}

fn worst_lre(x: &DVector<f64>, cert: &[f64]) -> f64 {
    x.iter()
        .zip(cert)
        .map(|(&e, &c)| lre(e, c))
        .fold(11.0, f64::min)
}

fn run_ours(p: &Nist, start: &[f64]) -> Outcome {
    run_ours_with(p, start, true)
}

fn run_ours_with(p: &Nist, start: &[f64], polish: bool) -> Outcome {
    let config = LmConfig {
        polish,
        ftol: 1e-15,
        xtol: 1e-15,
        gtol: 0.0,
        max_iters: 10_000,
        max_evals: 10_000,
        ..LmConfig::default()
    };
    let o = Ours {
        p,
        nres: Cell::new(0),
        njac: Cell::new(0),
    };
    let rep = minimize(&o, DVector::from_column_slice(start), &config);
    Outcome {
        nres: o.nres.get(),
        njac: o.njac.get(),
        lre: worst_lre(&rep.x, &p.certified),
    }
}

fn run_theirs(p: &Nist, start: &[f64]) -> Outcome {
    let t = Theirs {
        p,
        x: DVector::from_column_slice(start),
        nres: Cell::new(0),
        njac: Cell::new(0),
    };
    let (t, _report) = LevenbergMarquardt::new().with_patience(2000).minimize(t);
    Outcome {
        nres: t.nres.get(),
        njac: t.njac.get(),
        lre: worst_lre(&t.x, &p.certified),
    }
}

fn main() {
    // `cargo bench` passes `--bench`; nothing else to parse.
    let repeats: usize = std::env::var("NIST_BENCH_REPEATS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(21)
        .max(1);
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/nist"));
    let problems = Nist::load_all(dir);
    let runs: Vec<(&Nist, usize)> = problems
        .iter()
        .flat_map(|p| (0..2).map(move |k| (p, k)))
        .collect();

    let ours: Vec<Outcome> = runs
        .iter()
        .map(|&(p, k)| run_ours(p, &p.starts[k]))
        .collect();
    let theirs: Vec<Outcome> = runs
        .iter()
        .map(|&(p, k)| run_theirs(p, &p.starts[k]))
        .collect();

    let plain: Vec<Outcome> = runs
        .iter()
        .map(|&(p, k)| run_ours_with(p, &p.starts[k], false))
        .collect();

    println!(
        "{:<10} {:>5} | {:>6} {:>6} {:>6} | {:>6} {:>6} {:>6}",
        "problem", "start", "evals", "jevals", "LRE", "evals", "jevals", "LRE"
    );
    println!(
        "{:<16} | {:^20} | {:^20}",
        "", "goniofit", "levenberg-marquardt"
    );
    for (i, &(p, k)) in runs.iter().enumerate() {
        let (a, b) = (ours[i], theirs[i]);
        println!(
            "{:<10} {:>5} | {:>6} {:>6} {:>6.2} | {:>6} {:>6} {:>6.2}",
            p.name,
            k + 1,
            a.nres,
            a.njac,
            a.lre,
            b.nres,
            b.njac,
            b.lre
        );
    }
    let sum = |v: &[Outcome], f: fn(&Outcome) -> f64| v.iter().map(f).sum::<f64>();
    let solved = |v: &[Outcome]| v.iter().filter(|o| o.lre >= 4.0).count();
    let (r_ours, r_theirs) = (
        sum(&ours, |o| o.nres as f64),
        sum(&theirs, |o| o.nres as f64),
    );
    let (j_ours, j_theirs) = (
        sum(&ours, |o| o.njac as f64),
        sum(&theirs, |o| o.njac as f64),
    );
    let mean = |v: &[Outcome]| sum(v, |o| o.lre) / v.len() as f64;
    // Evaluations on the runs both solve (LRE >= 4), for a like-for-like ratio.
    let both: Vec<usize> = (0..runs.len())
        .filter(|&i| ours[i].lre >= 4.0 && theirs[i].lre >= 4.0)
        .collect();
    let rb_ours: u64 = both.iter().map(|&i| ours[i].nres).sum();
    let rb_theirs: u64 = both.iter().map(|&i| theirs[i].nres).sum();

    // Timing interleaves the solvers run by run (rotating which goes first), so that all
    // see the same machine load; each repeat sums the 54 runs.
    let mut t_ours = Vec::new();
    let mut t_theirs = Vec::new();
    let mut t_plain = Vec::new();
    for rep in 0..repeats {
        let mut acc = [0.0f64; 3];
        for (i, &(p, k)) in runs.iter().enumerate() {
            for s in 0..3 {
                let which = (i + rep + s) % 3;
                let t0 = Instant::now();
                std::hint::black_box(match which {
                    0 => run_ours(p, &p.starts[k]),
                    1 => run_theirs(p, &p.starts[k]),
                    _ => run_ours_with(p, &p.starts[k], false),
                });
                acc[which] += t0.elapsed().as_secs_f64();
            }
        }
        t_ours.push(acc[0]);
        t_theirs.push(acc[1]);
        t_plain.push(acc[2]);
    }
    let mp = median(&t_plain);
    let (mo, mt) = (median(&t_ours), median(&t_theirs));

    println!();
    println!(
        "goniofit:            solved {}/54, mean LRE {:.2}, residual evals {}, Jacobian evals {}, suite time {:.2} ms (median of {repeats})",
        solved(&ours), mean(&ours), r_ours, j_ours, mo * 1e3
    );
    println!(
        "levenberg-marquardt: solved {}/54, mean LRE {:.2}, residual evals {}, Jacobian evals {}, suite time {:.2} ms (median of {repeats})",
        solved(&theirs), mean(&theirs), r_theirs, j_theirs, mt * 1e3
    );
    println!(
        "goniofit, polishing off: solved {}/54, mean LRE {:.2}, residual evals {}, Jacobian evals {}, suite time {:.2} ms (median of {repeats})",
        solved(&plain),
        mean(&plain),
        sum(&plain, |o| o.nres as f64),
        sum(&plain, |o| o.njac as f64),
        mp * 1e3
    );
    println!(
        "ratios goniofit (polishing off)/levenberg-marquardt: residual evals {:.3}, time {:.3}",
        sum(&plain, |o| o.nres as f64) / r_theirs,
        mp / mt
    );
    println!(
        "ratios goniofit/levenberg-marquardt: residual evals {:.3}, Jacobian evals {:.3}, time {:.3}; \
         residual evals on the {} runs both solve {:.3}",
        r_ours / r_theirs,
        j_ours / j_theirs,
        mo / mt,
        both.len(),
        rb_ours as f64 / rb_theirs as f64
    );
}

/// The median of `v` (the mean of the middle two for an even count).
fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let m = s.len() / 2;
    if s.len() % 2 == 0 {
        0.5 * (s[m - 1] + s[m])
    } else {
        s[m]
    }
}
