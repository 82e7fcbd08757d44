//! The 27 NIST StRD nonlinear regression problems: a parser for the NIST `.dat` files and
//! each model with its analytic Jacobian. Shared by `tests/lib/nist.rs` and `benches/nist.rs`.
#![allow(dead_code, clippy::needless_range_loop)]

use goniofit_lm::LeastSquaresProblem;
use nalgebra::{DMatrix, DVector};
use std::f64::consts::PI;
use std::path::Path;

/// The 27 problems in NIST's order of difficulty (lower, average, higher).
pub(super) const NAMES: [&str; 27] = [
    "Misra1a", "Chwirut2", "Chwirut1", "Lanczos3", "Gauss1", "Gauss2", "DanWood", "Misra1b",
    "Kirby2", "Hahn1", "Nelson", "MGH17", "Lanczos1", "Lanczos2", "Gauss3", "Misra1c", "Misra1d",
    "Roszman1", "ENSO", "MGH09", "Thurber", "BoxBOD", "Rat42", "MGH10", "Eckerle4", "Rat43",
    "Bennett5",
];

/// Model value and gradient at one observation: `(b, x1, x2, grad) -> f`.
type ModelFn = fn(&[f64], f64, f64, &mut [f64]) -> f64;

/// One NIST problem: data, starts, certified values.
#[derive(Clone)]
pub(super) struct Nist {
    pub name: String,
    pub starts: [Vec<f64>; 2],
    pub certified: Vec<f64>,
    pub certified_sd: Vec<f64>,
    pub certified_rss: f64,
    /// Response (for Nelson: ln y, as the model is stated for log[y]).
    pub y: Vec<f64>,
    pub x1: Vec<f64>,
    pub x2: Vec<f64>,
    model: ModelFn,
}

fn num(tok: &str) -> f64 {
    tok.parse::<f64>()
        .unwrap_or_else(|_| panic!("not a number: {tok:?}"))
}

impl Nist {
    /// Parse `dir/<name>.dat`.
    pub(super) fn load(dir: &Path, name: &str) -> Nist {
        let text = std::fs::read_to_string(dir.join(format!("{name}.dat")))
            .unwrap_or_else(|e| panic!("{name}.dat: {e}"));
        let lines: Vec<&str> = text.lines().map(|l| l.trim_end()).collect();
        let (mut s1, mut s2, mut cert, mut sd) = (vec![], vec![], vec![], vec![]);
        let mut rss = f64::NAN;
        let mut data_start = None;
        for (i, l) in lines.iter().enumerate() {
            let t = l.trim_start();
            let toks: Vec<&str> = t.split_whitespace().collect();
            if toks.len() == 6 && toks[0].starts_with('b') && toks[1] == "=" {
                s1.push(num(toks[2]));
                s2.push(num(toks[3]));
                cert.push(num(toks[4]));
                sd.push(num(toks[5]));
            } else if t.starts_with("Residual Sum of Squares:") {
                rss = num(toks[toks.len() - 1]);
            } else if t.starts_with("Data:") && toks.get(1) == Some(&"y") {
                data_start = Some(i + 1);
            }
        }
        let data_start = data_start.expect("Data: y ... line");
        let (mut y, mut x1, mut x2) = (vec![], vec![], vec![]);
        for l in &lines[data_start..] {
            let toks: Vec<&str> = l.split_whitespace().collect();
            if toks.is_empty() {
                continue;
            }
            y.push(num(toks[0]));
            x1.push(num(toks[1]));
            x2.push(toks.get(2).map_or(0.0, |t| num(t)));
        }
        if name == "Nelson" {
            y.iter_mut().for_each(|v| *v = v.ln());
        }
        let model = model_fn(name);
        assert_eq!(s1.len(), cert.len());
        Nist {
            name: name.to_string(),
            starts: [s1, s2],
            certified: cert,
            certified_sd: sd,
            certified_rss: rss,
            y,
            x1,
            x2,
            model,
        }
    }

    /// All 27 problems from `dir`.
    pub(super) fn load_all(dir: &Path) -> Vec<Nist> {
        NAMES.iter().map(|n| Nist::load(dir, n)).collect()
    }

    pub(super) fn n_params(&self) -> usize {
        self.certified.len()
    }

    pub(super) fn n_obs(&self) -> usize {
        self.y.len()
    }

    /// Model value at observation `i`, writing `∂f/∂b` into `grad`.
    pub(super) fn eval(&self, b: &[f64], i: usize, grad: &mut [f64]) -> f64 {
        (self.model)(b, self.x1[i], self.x2[i], grad)
    }
}

impl LeastSquaresProblem for Nist {
    /// `rᵢ = f(b; xᵢ) − yᵢ` (unweighted).
    fn residuals(&self, b: &DVector<f64>) -> DVector<f64> {
        let mut g = vec![0.0; b.len()];
        DVector::from_iterator(
            self.n_obs(),
            (0..self.n_obs()).map(|i| self.eval(b.as_slice(), i, &mut g) - self.y[i]),
        )
    }

    fn jacobian(&self, b: &DVector<f64>) -> DMatrix<f64> {
        let p = b.len();
        let mut jac = DMatrix::zeros(self.n_obs(), p);
        let mut g = vec![0.0; p];
        for i in 0..self.n_obs() {
            self.eval(b.as_slice(), i, &mut g);
            for j in 0..p {
                jac[(i, j)] = g[j];
            }
        }
        jac
    }
}

/// The log relative error `−log10(|est − cert| / |cert|)`, capped at 11 (and 11 when equal).
pub(super) fn lre(est: f64, cert: f64) -> f64 {
    if !est.is_finite() {
        return 0.0;
    }
    let rel = (est - cert).abs() / cert.abs();
    if rel == 0.0 {
        11.0
    } else {
        (-rel.log10()).clamp(0.0, 11.0)
    }
}

fn model_fn(name: &str) -> ModelFn {
    match name {
        "Misra1a" | "BoxBOD" => misra1a,
        "Chwirut1" | "Chwirut2" => chwirut,
        "Lanczos1" | "Lanczos2" | "Lanczos3" => lanczos,
        "Gauss1" | "Gauss2" | "Gauss3" => gauss,
        "DanWood" => danwood,
        "Misra1b" => misra1b,
        "Kirby2" => kirby2,
        "Hahn1" | "Thurber" => rational33,
        "Nelson" => nelson,
        "MGH17" => mgh17,
        "Misra1c" => misra1c,
        "Misra1d" => misra1d,
        "Roszman1" => roszman1,
        "ENSO" => enso,
        "MGH09" => mgh09,
        "Rat42" => rat42,
        "MGH10" => mgh10,
        "Eckerle4" => eckerle4,
        "Rat43" => rat43,
        "Bennett5" => bennett5,
        _ => panic!("unknown NIST problem {name}"),
    }
}

/// y = b1*(1-exp[-b2*x])
fn misra1a(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let e = (-b[1] * x).exp();
    g[0] = -(-b[1] * x).exp_m1();
    g[1] = b[0] * x * e;
    b[0] * g[0]
}

/// y = exp[-b1*x]/(b2+b3*x)
fn chwirut(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let e = (-b[0] * x).exp();
    let d = b[1] + b[2] * x;
    let f = e / d;
    g[0] = -x * f;
    g[1] = -f / d;
    g[2] = -x * f / d;
    f
}

/// y = b1*exp(-b2*x) + b3*exp(-b4*x) + b5*exp(-b6*x)
fn lanczos(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let mut f = 0.0;
    for k in 0..3 {
        let e = (-b[2 * k + 1] * x).exp();
        g[2 * k] = e;
        g[2 * k + 1] = -x * b[2 * k] * e;
        f += b[2 * k] * e;
    }
    f
}

/// y = b1*exp(-b2*x) + b3*exp(-(x-b4)²/b5²) + b6*exp(-(x-b7)²/b8²)
fn gauss(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let e = (-b[1] * x).exp();
    g[0] = e;
    g[1] = -x * b[0] * e;
    let mut f = b[0] * e;
    for k in [2usize, 5] {
        let (a, c, w) = (b[k], b[k + 1], b[k + 2]);
        let d = x - c;
        let q = (-(d * d) / (w * w)).exp();
        g[k] = q;
        g[k + 1] = a * q * 2.0 * d / (w * w);
        g[k + 2] = a * q * 2.0 * d * d / (w * w * w);
        f += a * q;
    }
    f
}

/// y = b1*x**b2
fn danwood(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let p = x.powf(b[1]);
    g[0] = p;
    g[1] = b[0] * p * x.ln();
    b[0] * p
}

/// y = b1 * (1-(1+b2*x/2)**(-2))
fn misra1b(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let u = 1.0 + b[1] * x / 2.0;
    g[0] = 1.0 - 1.0 / (u * u);
    g[1] = b[0] * x / (u * u * u);
    b[0] * g[0]
}

/// y = (b1 + b2*x + b3*x²) / (1 + b4*x + b5*x²)
fn kirby2(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let n = b[0] + x * (b[1] + x * b[2]);
    let d = 1.0 + x * (b[3] + x * b[4]);
    let f = n / d;
    g[0] = 1.0 / d;
    g[1] = x / d;
    g[2] = x * x / d;
    g[3] = -f * x / d;
    g[4] = -f * x * x / d;
    f
}

/// y = (b1+b2*x+b3*x²+b4*x³) / (1+b5*x+b6*x²+b7*x³)  (Hahn1, Thurber)
fn rational33(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let n = b[0] + x * (b[1] + x * (b[2] + x * b[3]));
    let d = 1.0 + x * (b[4] + x * (b[5] + x * b[6]));
    let f = n / d;
    let mut xp = 1.0;
    for k in 0..4 {
        g[k] = xp / d;
        xp *= x;
    }
    let mut xp = x;
    for k in 4..7 {
        g[k] = -f * xp / d;
        xp *= x;
    }
    f
}

/// log[y] = b1 - b2*x1 * exp[-b3*x2]
fn nelson(b: &[f64], x1: f64, x2: f64, g: &mut [f64]) -> f64 {
    let e = (-b[2] * x2).exp();
    g[0] = 1.0;
    g[1] = -x1 * e;
    g[2] = b[1] * x1 * x2 * e;
    b[0] - b[1] * x1 * e
}

/// y = b1 + b2*exp[-x*b4] + b3*exp[-x*b5]
fn mgh17(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let e4 = (-x * b[3]).exp();
    let e5 = (-x * b[4]).exp();
    g[0] = 1.0;
    g[1] = e4;
    g[2] = e5;
    g[3] = -x * b[1] * e4;
    g[4] = -x * b[2] * e5;
    b[0] + b[1] * e4 + b[2] * e5
}

/// y = b1 * (1-(1+2*b2*x)**(-.5))
fn misra1c(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let u = 1.0 + 2.0 * b[1] * x;
    let s = u.sqrt();
    g[0] = 1.0 - 1.0 / s;
    g[1] = b[0] * x / (u * s);
    b[0] * g[0]
}

/// y = b1*b2*x*((1+b2*x)**(-1))
fn misra1d(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let u = 1.0 + b[1] * x;
    g[0] = b[1] * x / u;
    g[1] = b[0] * x / (u * u);
    b[0] * g[0]
}

/// y = b1 - b2*x - arctan[b3/(x-b4)]/pi  (plain arctan, as NIST; not atan2)
fn roszman1(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let d = x - b[3];
    let t = b[2] / d;
    let s = 1.0 / (PI * (1.0 + t * t));
    g[0] = 1.0;
    g[1] = -x;
    g[2] = -s / d;
    g[3] = -s * t / d;
    b[0] - b[1] * x - t.atan() / PI
}

/// y = b1 + b2*cos(2πx/12) + b3*sin(2πx/12) + b5*cos(2πx/b4) + b6*sin(2πx/b4)
///        + b8*cos(2πx/b7) + b9*sin(2πx/b7)
fn enso(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let a0 = 2.0 * PI * x / 12.0;
    g[0] = 1.0;
    g[1] = a0.cos();
    g[2] = a0.sin();
    let mut f = b[0] + b[1] * g[1] + b[2] * g[2];
    for k in [3usize, 6] {
        let a = 2.0 * PI * x / b[k];
        let (s, c) = a.sin_cos();
        g[k + 1] = c;
        g[k + 2] = s;
        g[k] = (-b[k + 1] * s + b[k + 2] * c) * (-a / b[k]);
        f += b[k + 1] * c + b[k + 2] * s;
    }
    f
}

/// y = b1*(x²+x*b2) / (x²+x*b3+b4)
fn mgh09(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let n = x * (x + b[1]);
    let d = x * (x + b[2]) + b[3];
    let f = b[0] * n / d;
    g[0] = n / d;
    g[1] = b[0] * x / d;
    g[2] = -f * x / d;
    g[3] = -f / d;
    f
}

/// y = b1 / (1+exp[b2-b3*x])
fn rat42(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let e = (b[1] - b[2] * x).exp();
    let u = 1.0 + e;
    g[0] = 1.0 / u;
    g[1] = -b[0] * e / (u * u);
    g[2] = b[0] * x * e / (u * u);
    b[0] / u
}

/// y = b1 * exp[b2/(x+b3)]
fn mgh10(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let d = x + b[2];
    let e = (b[1] / d).exp();
    g[0] = e;
    g[1] = b[0] * e / d;
    g[2] = -b[0] * e * b[1] / (d * d);
    b[0] * e
}

/// y = (b1/b2) * exp[-0.5*((x-b3)/b2)²]
fn eckerle4(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let z = (x - b[2]) / b[1];
    let e = (-0.5 * z * z).exp();
    let f = b[0] / b[1] * e;
    g[0] = e / b[1];
    g[1] = f * (z * z - 1.0) / b[1];
    g[2] = f * z / b[1];
    f
}

/// y = b1 / ((1+exp[b2-b3*x])**(1/b4))
fn rat43(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let e = (b[1] - b[2] * x).exp();
    let l = e.ln_1p();
    let p = (-l / b[3]).exp();
    let f = b[0] * p;
    let q = f / (b[3] * (1.0 + e));
    g[0] = p;
    g[1] = -q * e;
    g[2] = q * e * x;
    g[3] = f * l / (b[3] * b[3]);
    f
}

/// y = b1 * (b2+x)**(-1/b3)
fn bennett5(b: &[f64], x: f64, _: f64, g: &mut [f64]) -> f64 {
    let u = b[1] + x;
    let l = u.ln();
    let p = (-l / b[2]).exp();
    let f = b[0] * p;
    g[0] = p;
    g[1] = -f / (b[2] * u);
    g[2] = f * l / (b[2] * b[2]);
    f
}
