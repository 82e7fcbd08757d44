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
//! model sees is [`Sample::from_degrees`] of exactly those numbers. So a file written with
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
//! use goniofit::geometry::Quantity;
//! use goniofit::model::{by_name, parse_params, ModelOptions};
//! use goniofit::synth::{generate, Layout, Noise, NoiseKind};
//!
//! let model = by_name("kbs", &ModelOptions::default())?;
//! let params = parse_params(model.as_ref(), "sigma=0.3,T=2,scale=1")?;
//! let layout = Layout::parse("hemisphere 5x18x36")?;
//! let noise = Noise { kind: NoiseKind::Relative, level: 0.01, seed: 1 };
//! let data = generate(model.as_ref(), &params, &layout.angles(), 1.0, Quantity::Radiance, &noise)?;
//! assert_eq!(data.len(), 3240);
//! assert!((data.value[0] / data.exact[0] - 1.0).abs() < 0.1);
//! # Ok::<(), goniofit::Error>(())
//! ```

use crate::error::{Error, Result};
use crate::geometry::{wrap_phi, Geometry, Quantity, Sample};
use crate::model::domain::short_number;
use crate::model::{EvalMode, Model, ModelOptions};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

/// One direction pair in **degrees**, exactly as written to (or read from) a CSV file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnglesDeg {
    pub theta_i: f64,
    pub theta_r: f64,
    pub phi_r: f64,
}

impl AnglesDeg {
    /// A sample's angles in degrees. `from_sample(s).sample()` may differ from `s` in the
    /// last bit; the data set is then defined by the degrees.
    pub fn from_sample(s: &Sample) -> Self {
        AnglesDeg {
            theta_i: s.theta_i.to_degrees(),
            theta_r: s.theta_r.to_degrees(),
            phi_r: s.phi_r.to_degrees(),
        }
    }

    /// The sample the models evaluate: [`Sample::from_degrees`] of these numbers.
    pub fn sample(&self) -> Sample {
        Sample::from_degrees(self.theta_i, self.theta_r, self.phi_r)
    }
}

/// Default in-plane incidence angles, degrees.
pub const INPLANE_THETA_I_DEG: [f64; 5] = [15.0, 30.0, 45.0, 60.0, 75.0];
/// Default in-plane θr step and largest |θr|, degrees.
pub const INPLANE_STEP_DEG: f64 = 1.0;
pub const INPLANE_THETA_R_MAX_DEG: f64 = 85.0;
/// Default grid (θi, θr, φr counts) of the hemisphere and grazing layouts.
pub const DEFAULT_GRID: (usize, usize, usize) = (5, 18, 36);

/// Where the synthetic instrument looks. See the module documentation for the exact angles.
#[derive(Debug, Clone, PartialEq)]
pub enum Layout {
    /// Scans in the plane of incidence: for each θi, signed θr = k·`step_deg` for every
    /// integer k with |k·step| ≤ `theta_r_max_deg`, ascending (θr < 0 stored as |θr| at
    /// φr = 180°).
    InPlane {
        theta_i_deg: Vec<f64>,
        step_deg: f64,
        theta_r_max_deg: f64,
    },
    /// θi × θr × φr grid over the hemisphere (θi outer, φr inner).
    Hemisphere {
        n_theta_i: usize,
        n_theta_r: usize,
        n_phi_r: usize,
    },
    /// As `Hemisphere`, with θi from 70° to 89°.
    Grazing {
        n_theta_i: usize,
        n_theta_r: usize,
        n_phi_r: usize,
    },
    /// Explicit directions (e.g. from a CSV file, [`Layout::read_csv`]).
    Angles(Vec<AnglesDeg>),
}

impl Layout {
    /// The default in-plane layout (5 × 171 = 855 samples).
    pub fn inplane() -> Layout {
        Layout::InPlane {
            theta_i_deg: INPLANE_THETA_I_DEG.to_vec(),
            step_deg: INPLANE_STEP_DEG,
            theta_r_max_deg: INPLANE_THETA_R_MAX_DEG,
        }
    }

    /// The default hemisphere layout (5 × 18 × 36 = 3240 samples).
    pub fn hemisphere() -> Layout {
        let (a, b, c) = DEFAULT_GRID;
        Layout::Hemisphere {
            n_theta_i: a,
            n_theta_r: b,
            n_phi_r: c,
        }
    }

    /// The default grazing layout (5 × 18 × 36 = 3240 samples).
    pub fn grazing() -> Layout {
        let (a, b, c) = DEFAULT_GRID;
        Layout::Grazing {
            n_theta_i: a,
            n_theta_r: b,
            n_phi_r: c,
        }
    }

    /// The CSV file `--layout` text names, when it names one (not a built-in layout).
    pub fn file_of(text: &str) -> Option<&Path> {
        let first = text.split_whitespace().next().unwrap_or("");
        let builtin = ["inplane", "in-plane", "hemisphere", "grazing"]
            .iter()
            .any(|k| first.eq_ignore_ascii_case(k));
        let path = Path::new(text);
        (!builtin && path.is_file()).then_some(path)
    }

    /// A layout by name, with optional sizes in the form [`Layout::describe`] writes, or else
    /// the path of a CSV file of angles ([`Layout::read_csv`]). Names are case-insensitive
    /// and win over a file of the same name (write `./hemisphere` for the file):
    ///
    /// - `hemisphere`, `hemisphere 5x18x36`, `grazing`, `grazing 10x9x12` (θi × θr × φr counts);
    /// - `inplane`, `inplane theta_i=15,45 theta_r=-80..80 step=0.5` (any subset of the keys;
    ///   `max=80` is the same as `theta_r=-80..80`).
    ///
    /// So `Layout::parse(&layout.describe())` gives back `layout` for every generated layout.
    pub fn parse(text: &str) -> Result<Layout> {
        let mut words = text.split_whitespace();
        let first = words.next().unwrap_or("").to_ascii_lowercase();
        let rest: Vec<&str> = words.collect();
        let bad = |m: String| Err(Error::Usage(format!("layout '{}': {m}", text.trim())));
        let mut layout = match first.as_str() {
            "inplane" | "in-plane" => Layout::inplane(),
            "hemisphere" => Layout::hemisphere(),
            "grazing" => Layout::grazing(),
            _ => {
                let path = Path::new(text);
                if !path.is_file() {
                    return bad(
                        "neither inplane, hemisphere, grazing nor an existing CSV file".into(),
                    );
                }
                return Layout::read_csv(path);
            }
        };
        match &mut layout {
            Layout::InPlane {
                theta_i_deg,
                step_deg,
                theta_r_max_deg,
            } => {
                for w in rest {
                    let Some((k, v)) = w.split_once('=') else {
                        return bad(format!(
                            "'{w}': expected key=value (theta_i, theta_r, step, max)"
                        ));
                    };
                    let num = |x: &str| {
                        x.trim().parse::<f64>().map_err(|_| {
                            Error::Usage(format!("layout '{}': '{x}' is not a number", text.trim()))
                        })
                    };
                    match k.to_ascii_lowercase().as_str() {
                        "theta_i" => {
                            *theta_i_deg = v.split(',').map(num).collect::<Result<Vec<f64>>>()?
                        }
                        "step" => *step_deg = num(v)?,
                        "max" | "theta_r_max" => *theta_r_max_deg = num(v)?,
                        "theta_r" => match v.rsplit_once("..") {
                            Some((_, m)) => *theta_r_max_deg = num(m)?,
                            None => return bad(format!("'{w}': expected theta_r=-MAX..MAX")),
                        },
                        _ => {
                            return bad(format!(
                                "unknown key '{k}' (inplane takes theta_i, theta_r, step, max)"
                            ))
                        }
                    }
                }
            }
            Layout::Hemisphere { .. } | Layout::Grazing { .. } => match rest[..] {
                [] => {}
                [g] => {
                    let (a, b, c) = parse_grid(g)?;
                    layout = layout.with_grid(a, b, c)?;
                }
                _ => return bad("expected at most one grid NIxNRxNP, e.g. 5x18x36".into()),
            },
            Layout::Angles(_) => unreachable!("named layouts only"),
        }
        layout.validate()?;
        Ok(layout)
    }

    /// Replace the grid sizes of a `Hemisphere` or `Grazing` layout; an error for the others.
    pub fn with_grid(self, n_theta_i: usize, n_theta_r: usize, n_phi_r: usize) -> Result<Layout> {
        match self {
            Layout::Hemisphere { .. } => Ok(Layout::Hemisphere {
                n_theta_i,
                n_theta_r,
                n_phi_r,
            }),
            Layout::Grazing { .. } => Ok(Layout::Grazing {
                n_theta_i,
                n_theta_r,
                n_phi_r,
            }),
            _ => Err(Error::Usage(
                "a grid applies only to the hemisphere and grazing layouts".into(),
            )),
        }
    }

    /// Read directions from a CSV file with a header naming `theta_i`, `theta_r`, `phi_r`
    /// (degrees; any order; other columns ignored; lines starting with `#` skipped).
    /// A signed θr < 0 is taken as |θr| at φr + 180° (wrapped to (−180°, 180°]).
    pub fn read_csv(path: &Path) -> Result<Layout> {
        let io_err = |source| Error::Io {
            path: path.to_path_buf(),
            source,
        };
        let file = std::fs::File::open(path).map_err(io_err)?;
        let mut rdr = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .flexible(true)
            .from_reader(file);
        let file_err = |message: String| Error::File {
            path: path.to_path_buf(),
            message,
        };
        let headers = rdr
            .headers()
            .map_err(|e| file_err(format!("cannot read the header: {e}")))?
            .clone();
        let col = |name: &str| {
            headers
                .iter()
                .position(|h| h.eq_ignore_ascii_case(name))
                .ok_or_else(|| {
                    file_err(format!(
                        "no column '{name}' in the header (found: {}); a layout file needs theta_i,theta_r,phi_r in degrees",
                        headers.iter().collect::<Vec<_>>().join(",")
                    ))
                })
        };
        let cols = [col("theta_i")?, col("theta_r")?, col("phi_r")?];
        let names = ["theta_i", "theta_r", "phi_r"];
        let mut out = Vec::new();
        for rec in rdr.records() {
            let rec = rec.map_err(|e| file_err(format!("malformed CSV: {e}")))?;
            let line = rec.position().map_or(0, |p| p.line() as usize);
            let mut v = [0.0; 3];
            for k in 0..3 {
                let field = rec.get(cols[k]).unwrap_or("");
                v[k] = field.parse().map_err(|_| Error::Input {
                    path: path.to_path_buf(),
                    line,
                    column: names[k].into(),
                    message: format!("'{field}' is not a number"),
                })?;
            }
            let mut a = AnglesDeg {
                theta_i: v[0],
                theta_r: v[1],
                phi_r: v[2],
            };
            if a.theta_r < 0.0 {
                a.theta_r = -a.theta_r;
                a.phi_r = wrap_phi((a.phi_r + 180.0).to_radians()).to_degrees();
                // Keep the round numbers of in-plane data exact.
                if (a.phi_r - 180.0).abs() < 1e-9 {
                    a.phi_r = 180.0;
                } else if a.phi_r.abs() < 1e-9 {
                    a.phi_r = 0.0;
                }
            }
            a.sample().validate().map_err(|m| Error::Input {
                path: path.to_path_buf(),
                line,
                column: "theta_i,theta_r,phi_r".into(),
                message: m,
            })?;
            out.push(a);
        }
        if out.is_empty() {
            return Err(file_err("no data rows".into()));
        }
        Ok(Layout::Angles(out))
    }

    /// Check sizes and ranges (counts ≥ 1, step > 0, angles in the valid domain).
    pub fn validate(&self) -> Result<()> {
        let usage = |m: String| Err(Error::Usage(m));
        match self {
            Layout::InPlane {
                theta_i_deg,
                step_deg,
                theta_r_max_deg,
            } => {
                if theta_i_deg.is_empty() {
                    return usage("the in-plane layout needs at least one theta_i".into());
                }
                if let Some(t) = theta_i_deg
                    .iter()
                    .find(|t| !(t.is_finite() && (0.0..90.0).contains(*t)))
                {
                    return usage(format!("in-plane theta_i = {t}° is outside [0°, 90°)"));
                }
                if !(step_deg.is_finite() && *step_deg > 0.0) {
                    return usage(format!("in-plane step {step_deg}° must be positive"));
                }
                if !(theta_r_max_deg.is_finite() && (0.0..=90.0).contains(theta_r_max_deg)) {
                    return usage(format!(
                        "in-plane theta_r max {theta_r_max_deg}° is outside [0°, 90°]"
                    ));
                }
                if theta_r_max_deg / step_deg > 5e6 {
                    return usage(format!(
                        "in-plane step {step_deg}° is too small (over 10 million samples per scan)"
                    ));
                }
                Ok(())
            }
            Layout::Hemisphere {
                n_theta_i,
                n_theta_r,
                n_phi_r,
            }
            | Layout::Grazing {
                n_theta_i,
                n_theta_r,
                n_phi_r,
            } => {
                if *n_theta_i == 0 || *n_theta_r == 0 || *n_phi_r == 0 {
                    return usage(format!(
                        "grid {n_theta_i}x{n_theta_r}x{n_phi_r}: every count must be at least 1"
                    ));
                }
                match n_theta_i
                    .checked_mul(*n_theta_r)
                    .and_then(|n| n.checked_mul(*n_phi_r))
                {
                    Some(n) if n <= 100_000_000 => Ok(()),
                    _ => usage(format!(
                        "grid {n_theta_i}x{n_theta_r}x{n_phi_r} is too large (over 100 million samples)"
                    )),
                }
            }
            Layout::Angles(a) => {
                if a.is_empty() {
                    return usage("the layout has no angles".into());
                }
                for (i, s) in a.iter().enumerate() {
                    s.sample()
                        .validate()
                        .map_err(|m| Error::Usage(format!("layout angle {}: {m}", i + 1)))?;
                }
                Ok(())
            }
        }
    }

    /// The directions in degrees, in layout order (θi outer, then θr, then φr).
    pub fn angles(&self) -> Vec<AnglesDeg> {
        match self {
            Layout::InPlane {
                theta_i_deg,
                step_deg,
                theta_r_max_deg,
            } => {
                // θr = k·step, |k| ≤ K: symmetric about 0, 0 included, and each negative
                // value is exactly the negation of a positive one.
                let kmax = (theta_r_max_deg / step_deg + 1e-9).floor() as i64;
                let mut out = Vec::with_capacity(theta_i_deg.len() * (2 * kmax as usize + 1));
                for &ti in theta_i_deg {
                    for k in -kmax..=kmax {
                        // min: k·step may round one ulp past max (e.g. 900 × 0.1 > 90).
                        let tr = (k.unsigned_abs() as f64 * step_deg).min(*theta_r_max_deg);
                        out.push(AnglesDeg {
                            theta_i: ti,
                            theta_r: tr,
                            phi_r: if k < 0 { 180.0 } else { 0.0 },
                        });
                    }
                }
                out
            }
            Layout::Hemisphere {
                n_theta_i,
                n_theta_r,
                n_phi_r,
            } => grid(&midpoints(*n_theta_i, 90.0), *n_theta_r, *n_phi_r),
            Layout::Grazing {
                n_theta_i,
                n_theta_r,
                n_phi_r,
            } => {
                let ti: Vec<f64> = if *n_theta_i == 1 {
                    vec![89.0]
                } else {
                    (0..*n_theta_i)
                        .map(|k| 70.0 + 19.0 * k as f64 / (*n_theta_i - 1) as f64)
                        .collect()
                };
                grid(&ti, *n_theta_r, *n_phi_r)
            }
            Layout::Angles(a) => a.clone(),
        }
    }

    /// The directions as radian samples ([`AnglesDeg::sample`] of [`Layout::angles`]).
    pub fn samples(&self) -> Vec<Sample> {
        self.angles().iter().map(AnglesDeg::sample).collect()
    }

    /// A one-line description for reports and the truth file, e.g. `hemisphere 5x18x36`.
    pub fn describe(&self) -> String {
        match self {
            Layout::InPlane {
                theta_i_deg,
                step_deg,
                theta_r_max_deg,
            } => format!(
                "inplane theta_i={} theta_r=-{theta_r_max_deg}..{theta_r_max_deg} step={step_deg}",
                theta_i_deg
                    .iter()
                    .map(|t| t.to_string())
                    .collect::<Vec<_>>()
                    .join(",")
            ),
            Layout::Hemisphere {
                n_theta_i,
                n_theta_r,
                n_phi_r,
            } => format!("hemisphere {n_theta_i}x{n_theta_r}x{n_phi_r}"),
            Layout::Grazing {
                n_theta_i,
                n_theta_r,
                n_phi_r,
            } => format!("grazing {n_theta_i}x{n_theta_r}x{n_phi_r}"),
            Layout::Angles(a) => format!("angles ({} directions)", a.len()),
        }
    }
}

/// `5x18x36` as (θi, θr, φr) counts.
pub fn parse_grid(text: &str) -> Result<(usize, usize, usize)> {
    let bad = || {
        Error::Usage(format!(
            "grid '{text}': expected three counts NIxNRxNP, e.g. 5x18x36"
        ))
    };
    let v: Vec<usize> = text
        .split(['x', 'X'])
        .map(|s| s.trim().parse::<usize>().map_err(|_| bad()))
        .collect::<Result<_>>()?;
    match v[..] {
        [a, b, c] => Ok((a, b, c)),
        _ => Err(bad()),
    }
}

/// `n` cell midpoints of [0, width): width (k + ½)/n.
fn midpoints(n: usize, width: f64) -> Vec<f64> {
    (0..n)
        .map(|k| width * (k as f64 + 0.5) / n as f64)
        .collect()
}

/// θi list × θr midpoints of (0, 90) × φr = −180 + 360 l/n.
fn grid(theta_i: &[f64], n_theta_r: usize, n_phi_r: usize) -> Vec<AnglesDeg> {
    let tr = midpoints(n_theta_r, 90.0);
    let pr: Vec<f64> = (0..n_phi_r)
        .map(|l| -180.0 + 360.0 * l as f64 / n_phi_r as f64)
        .collect();
    let mut out = Vec::with_capacity(theta_i.len() * tr.len() * pr.len());
    for &ti in theta_i {
        for &r in &tr {
            for &p in &pr {
                out.push(AnglesDeg {
                    theta_i: ti,
                    theta_r: r,
                    phi_r: p,
                });
            }
        }
    }
    out
}

/// Keep `n` of the angles, evenly spread over the layout order (indices ⌊k·len/n⌋), so a
/// subsample still covers every θi. An error if `n` is 0 or exceeds the layout's size.
pub fn subsample(angles: &[AnglesDeg], n: usize) -> Result<Vec<AnglesDeg>> {
    let len = angles.len();
    if n == 0 || n > len {
        return Err(Error::Usage(format!(
            "--samples {n}: must be between 1 and the layout's {len} samples (use --grid or --step for a denser layout)"
        )));
    }
    Ok((0..n).map(|k| angles[k * len / n]).collect())
}

/// The shape of the noise (see the module documentation for the formulas).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum NoiseKind {
    /// L (1 + ε z): constant relative error.
    #[default]
    Relative,
    /// L + ε max|L| z: constant error, ε a fraction of the peak value.
    Absolute,
    /// L + ε √(|L| max|L|) z: Poisson-like, variance ∝ L.
    Poisson,
}

impl NoiseKind {
    /// Lower-case name (`relative`, `absolute`, `poisson`).
    pub fn name(self) -> &'static str {
        match self {
            NoiseKind::Relative => "relative",
            NoiseKind::Absolute => "absolute",
            NoiseKind::Poisson => "poisson",
        }
    }
}

/// Seeded noise: kind, level ε ≥ 0 and seed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Noise {
    pub kind: NoiseKind,
    pub level: f64,
    pub seed: u64,
}

impl Noise {
    /// No noise: the exact model values.
    pub fn none() -> Noise {
        Noise {
            kind: NoiseKind::Relative,
            level: 0.0,
            seed: 0,
        }
    }
}

/// Noisy values and their standard deviations (one per exact value).
#[derive(Debug, Clone, PartialEq)]
pub struct Noisy {
    pub value: Vec<f64>,
    pub sigma_l: Vec<f64>,
}

/// Add seeded noise to `exact` (see the module documentation). `level` must be finite and
/// ≥ 0; with `level = 0` the values are `exact` bit for bit and every σ_L is 0.
pub fn add_noise(exact: &[f64], noise: &Noise) -> Result<Noisy> {
    if !(noise.level.is_finite() && noise.level >= 0.0) {
        return Err(Error::Usage(format!(
            "noise level {} must be finite and non-negative",
            noise.level
        )));
    }
    if noise.level == 0.0 {
        return Ok(Noisy {
            value: exact.to_vec(),
            sigma_l: vec![0.0; exact.len()],
        });
    }
    let eps = noise.level;
    let peak = exact.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let mut rng = rand::rngs::StdRng::seed_from_u64(noise.seed);
    let mut value = Vec::with_capacity(exact.len());
    let mut sigma_l = Vec::with_capacity(exact.len());
    for &l in exact {
        let z: f64 = StandardNormal.sample(&mut rng);
        let sd = match noise.kind {
            NoiseKind::Relative => eps * l.abs(),
            NoiseKind::Absolute => eps * peak,
            NoiseKind::Poisson => eps * (l.abs() * peak).sqrt(),
        };
        value.push(match noise.kind {
            // Written as L(1 + εz) so that the relative error is exactly εz.
            NoiseKind::Relative => l * (1.0 + eps * z),
            _ => l + sd * z,
        });
        sigma_l.push(sd);
    }
    let bad = (0..value.len()).find(|&i| !(value[i].is_finite() && sigma_l[i].is_finite()));
    if let Some(i) = bad {
        return Err(Error::Usage(format!(
            "noise level {} overflows double precision: sample {} would get the value {} (standard deviation {}) from the exact {}; give a smaller --noise",
            short_number(eps),
            i + 1,
            short_number(value[i]),
            short_number(sigma_l[i]),
            short_number(exact[i])
        )));
    }
    Ok(Noisy { value, sigma_l })
}

/// A synthetic data set: the directions, the model's exact values and the noisy values.
/// All vectors have one entry per sample, in layout order.
#[derive(Debug, Clone)]
pub struct SynthData {
    /// Directions in degrees, as written to the CSV.
    pub angles: Vec<AnglesDeg>,
    /// The same directions as the model saw them ([`AnglesDeg::sample`]).
    pub samples: Vec<Sample>,
    /// Wavelength (unit of σ, T), the same for every sample.
    pub wavelength: f64,
    /// Radiance or BRDF.
    pub quantity: Quantity,
    /// The model's values (the measured quantity, per `quantity`).
    pub exact: Vec<f64>,
    /// `exact` plus noise.
    pub value: Vec<f64>,
    /// Standard deviation of the noise of each value.
    pub sigma_l: Vec<f64>,
}

/// Evaluate `model` at `params` (in the order of `model.params()`) on `angles` and add
/// `noise`. Errors: a parameter vector of the wrong length, angles or wavelength outside
/// the domain, a bad noise level ([`Error::Usage`]), or a non-finite model value
/// ([`Error::Numerical`]).
pub fn generate(
    model: &dyn Model,
    params: &[f64],
    angles: &[AnglesDeg],
    wavelength: f64,
    quantity: Quantity,
    noise: &Noise,
) -> Result<SynthData> {
    let samples: Vec<Sample> = angles.iter().map(AnglesDeg::sample).collect();
    let geo = Geometry::new(&samples, &[wavelength], quantity)?;
    let exact = evaluate(model, params, &geo)?;
    let Noisy { value, sigma_l } = add_noise(&exact, noise)?;
    Ok(SynthData {
        angles: angles.to_vec(),
        samples,
        wavelength,
        quantity,
        exact,
        value,
        sigma_l,
    })
}

/// The model's values on a prepared batch, checked: right parameter count, every value
/// finite ([`crate::model::domain::evaluate_checked`]).
pub fn evaluate(model: &dyn Model, params: &[f64], geo: &Geometry) -> Result<Vec<f64>> {
    crate::model::domain::evaluate_checked(model, params, geo)
}

/// Which optional columns [`SynthData::write_csv`] writes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct CsvOptions {
    /// Add a `sigma_L` column (the noise standard deviation of each value).
    pub sigma: bool,
    /// Add a `wavelength` column.
    pub wavelength: bool,
    /// Write rows at |φr| = 180° as signed θr = −|θr| at φr = 0 (the in-plane convention of
    /// many instruments). θr = 0 stays 0.
    pub signed_theta_r: bool,
}

impl SynthData {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.value.len()
    }

    /// Whether there are no samples.
    pub fn is_empty(&self) -> bool {
        self.value.is_empty()
    }

    /// Write `theta_i,theta_r,phi_r,L[,sigma_L][,wavelength]` (degrees; `L` is the noisy
    /// value). Every number is written in Rust's shortest round-trip form, so parsing it
    /// gives back the same f64.
    pub fn write_csv<W: Write>(&self, w: W, opts: &CsvOptions) -> std::io::Result<()> {
        let mut wtr = csv::Writer::from_writer(w);
        let mut header = vec!["theta_i", "theta_r", "phi_r", "L"];
        if opts.sigma {
            header.push("sigma_L");
        }
        if opts.wavelength {
            header.push("wavelength");
        }
        wtr.write_record(&header)?;
        let mut row: Vec<String> = Vec::with_capacity(header.len());
        for (i, a) in self.angles.iter().enumerate() {
            let (tr, pr) = if opts.signed_theta_r && a.phi_r.abs() == 180.0 && a.theta_r != 0.0 {
                (-a.theta_r, 0.0)
            } else {
                (a.theta_r, a.phi_r)
            };
            row.clear();
            row.push(num(a.theta_i));
            row.push(num(tr));
            row.push(num(pr));
            row.push(num(self.value[i]));
            if opts.sigma {
                row.push(num(self.sigma_l[i]));
            }
            if opts.wavelength {
                row.push(num(self.wavelength));
            }
            wtr.write_record(&row)?;
        }
        wtr.flush()
    }
}

/// Shortest round-trip decimal (`{:?}` switches to exponent form for tiny and huge values,
/// where `{}` would print hundreds of digits).
fn num(x: f64) -> String {
    format!("{x:?}")
}

/// What a synthetic data set was made from, written beside it as JSON
/// (`data.truth.json` next to `data.csv`). Everything needed to regenerate the file or to
/// judge a fit of it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Model name as given to [`crate::model::by_name`].
    pub model: String,
    /// Every parameter of the model, by name.
    pub params: BTreeMap<String, f64>,
    /// Wavelength, in the unit of σ and T.
    pub wavelength: f64,
    /// That unit, when `--wavelength` named one (`nm`, `µm`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wavelength_unit: Option<String>,
    /// `radiance` or `brdf`.
    pub quantity: Quantity,
    /// KBS evaluation mode (`auto`, `series`, `smooth`, `rough`).
    pub mode: String,
    /// KBS relative tolerance.
    pub tol: f64,
    /// Patch half-sizes (X, Y), when the coherent term was included.
    pub patch: Option<(f64, f64)>,
    /// Fresnel factor on the KBS lobe (`none` when the file does not say).
    #[serde(default)]
    pub fresnel: crate::model::fresnel::Fresnel,
    /// Shadowing factor on the KBS lobe (`none` when the file does not say).
    #[serde(default)]
    pub shadowing: crate::model::shadowing::Shadowing,
    /// [`Layout::describe`] of the layout, or the layout file's path as given: either way
    /// [`Layout::parse`] reads it back.
    pub layout: String,
    /// `--samples`, when the layout was subsampled.
    pub subsample: Option<usize>,
    pub noise: Noise,
    /// Number of samples written.
    pub n: usize,
    /// Whether the CSV stores signed θr at φr = 0 for the φr = 180° rows.
    pub signed_theta_r: bool,
    /// File name of the data beside this file.
    pub data: String,
    /// goniofit version that wrote it.
    pub goniofit_version: String,
}

impl Truth {
    /// The parameters in the order of `model.params()`; an error names any parameter the
    /// truth file lacks.
    pub fn param_vector(&self, model: &dyn Model) -> Result<Vec<f64>> {
        model
            .params()
            .iter()
            .map(|s| {
                self.params
                    .iter()
                    .find(|(k, _)| k.eq_ignore_ascii_case(s.name))
                    .map(|(_, v)| *v)
                    .ok_or_else(|| Error::Param {
                        name: s.name.into(),
                        message: "missing from the truth file".into(),
                    })
            })
            .collect()
    }

    /// Name → value for every parameter of `model`.
    pub fn params_by_name(model: &dyn Model, params: &[f64]) -> BTreeMap<String, f64> {
        model
            .params()
            .iter()
            .zip(params)
            .map(|(s, v)| (s.name.to_string(), *v))
            .collect()
    }

    /// The model options the data were made with (`mode`, `tol`, `patch`).
    pub fn model_options(&self) -> Result<ModelOptions> {
        Ok(ModelOptions {
            mode: parse_eval_mode(&self.mode)?,
            tol: self.tol,
            patch: self.patch,
            fresnel: self.fresnel,
            shadowing: self.shadowing,
        })
    }

    /// The directions of the data: `layout` parsed again ([`Layout::parse`]; a layout file
    /// is looked up relative to the current folder), then subsampled as recorded.
    pub fn angles(&self) -> Result<Vec<AnglesDeg>> {
        let angles = Layout::parse(&self.layout)?.angles();
        match self.subsample {
            Some(n) => subsample(&angles, n),
            None => Ok(angles),
        }
    }

    /// Make the data set again from this truth: the same model, parameters, directions and
    /// noise, so the same values bit for bit.
    pub fn regenerate(&self) -> Result<SynthData> {
        let model = crate::model::by_name(&self.model, &self.model_options()?)?;
        let params = self.param_vector(model.as_ref())?;
        generate(
            model.as_ref(),
            &params,
            &self.angles()?,
            self.wavelength,
            self.quantity,
            &self.noise,
        )
    }

    /// Read a truth file.
    pub fn read(path: &Path) -> Result<Truth> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.to_path_buf(),
            source,
        })?;
        serde_json::from_str(&text).map_err(|e| Error::File {
            path: path.to_path_buf(),
            message: format!("not a goniofit truth file: {e}"),
        })
    }
}

/// Lower-case name of a KBS evaluation mode, as in the truth file and `--mode`.
pub fn eval_mode_name(mode: EvalMode) -> &'static str {
    match mode {
        EvalMode::Auto => "auto",
        EvalMode::Series => "series",
        EvalMode::Smooth => "smooth",
        EvalMode::Rough => "rough",
    }
}

/// Inverse of [`eval_mode_name`] (case-insensitive).
pub fn parse_eval_mode(text: &str) -> Result<EvalMode> {
    match text.to_ascii_lowercase().as_str() {
        "auto" => Ok(EvalMode::Auto),
        "series" => Ok(EvalMode::Series),
        "smooth" => Ok(EvalMode::Smooth),
        "rough" => Ok(EvalMode::Rough),
        _ => Err(Error::Usage(format!(
            "unknown evaluation mode '{text}' (known: auto, series, smooth, rough)"
        ))),
    }
}

/// The truth file that goes beside a data file: `data.csv` → `data.truth.json`.
pub fn truth_path(data: &Path) -> std::path::PathBuf {
    let stem = data
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "data".into());
    data.with_file_name(format!("{stem}.truth.json"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{by_name, ModelOptions};

    #[test]
    fn default_sizes() {
        assert_eq!(Layout::inplane().angles().len(), 5 * 171);
        assert_eq!(Layout::hemisphere().angles().len(), 3240);
        assert_eq!(Layout::grazing().angles().len(), 3240);
    }

    #[test]
    fn inplane_signed_theta_r() {
        let a = Layout::inplane().angles();
        // First scan, θi = 15: θr = −85 … 85.
        assert_eq!(
            a[0],
            AnglesDeg {
                theta_i: 15.0,
                theta_r: 85.0,
                phi_r: 180.0
            }
        );
        assert_eq!(
            a[85],
            AnglesDeg {
                theta_i: 15.0,
                theta_r: 0.0,
                phi_r: 0.0
            }
        );
        assert_eq!(
            a[170],
            AnglesDeg {
                theta_i: 15.0,
                theta_r: 85.0,
                phi_r: 0.0
            }
        );
        for x in &a {
            assert!(x.phi_r == 0.0 || x.phi_r == 180.0);
            assert!(x.theta_r >= 0.0 && x.theta_r <= 85.0);
            assert_eq!(x.theta_r.fract(), 0.0, "integer steps stay exact");
        }
        assert_eq!(a.iter().filter(|x| x.phi_r == 180.0).count(), 5 * 85);
    }

    #[test]
    fn grids_cover_the_ranges() {
        let h = Layout::Hemisphere {
            n_theta_i: 3,
            n_theta_r: 4,
            n_phi_r: 8,
        }
        .angles();
        assert_eq!(h.len(), 96);
        let ti: Vec<f64> = h.iter().step_by(32).map(|a| a.theta_i).collect();
        assert_eq!(ti, vec![15.0, 45.0, 75.0]);
        let tr: Vec<f64> = h[..32].iter().step_by(8).map(|a| a.theta_r).collect();
        assert_eq!(tr, vec![11.25, 33.75, 56.25, 78.75]);
        let pr: Vec<f64> = h[..8].iter().map(|a| a.phi_r).collect();
        assert_eq!(
            pr,
            vec![-180.0, -135.0, -90.0, -45.0, 0.0, 45.0, 90.0, 135.0]
        );
        let g = Layout::Grazing {
            n_theta_i: 20,
            n_theta_r: 2,
            n_phi_r: 2,
        }
        .angles();
        let gi: Vec<f64> = g.iter().step_by(4).map(|a| a.theta_i).collect();
        assert_eq!(gi.len(), 20);
        assert_eq!(gi[0], 70.0);
        assert_eq!(gi[19], 89.0);
        for w in gi.windows(2) {
            assert!((w[1] - w[0] - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn subsample_spreads_over_the_layout() {
        let a = Layout::hemisphere().angles();
        let s = subsample(&a, 100).unwrap();
        assert_eq!(s.len(), 100);
        assert_eq!(s[0], a[0]);
        let mut ti: Vec<f64> = s.iter().map(|x| x.theta_i).collect();
        ti.dedup();
        assert_eq!(ti.len(), 5, "every θi is kept");
        assert!(subsample(&a, 0).is_err());
        assert!(subsample(&a, 3241).is_err());
        assert_eq!(subsample(&a, 3240).unwrap(), a);
    }

    #[test]
    fn zero_noise_is_exact() {
        let exact = vec![1.0, 2.5, 1e-300, 0.0];
        let n = add_noise(&exact, &Noise::none()).unwrap();
        assert_eq!(n.value, exact);
        assert_eq!(n.sigma_l, vec![0.0; 4]);
    }

    #[test]
    fn noise_kinds_have_the_documented_sigma() {
        let exact = vec![4.0, 1.0, 0.0];
        let mk = |kind| Noise {
            kind,
            level: 0.1,
            seed: 7,
        };
        let r = add_noise(&exact, &mk(NoiseKind::Relative)).unwrap();
        assert_eq!(r.sigma_l, vec![0.4, 0.1, 0.0]);
        assert_eq!(r.value[2], 0.0);
        let a = add_noise(&exact, &mk(NoiseKind::Absolute)).unwrap();
        assert_eq!(a.sigma_l, vec![0.4, 0.4, 0.4]);
        let p = add_noise(&exact, &mk(NoiseKind::Poisson)).unwrap();
        assert_eq!(p.sigma_l, vec![0.4, 0.2, 0.0]);
        // Same z stream for every kind: (value − L)/σ agrees.
        let z = (r.value[0] - 4.0) / 0.4;
        assert!(((a.value[0] - 4.0) / 0.4 - z).abs() < 1e-12);
        assert!(((p.value[1] - 1.0) / 0.2 - (a.value[1] - 1.0) / 0.4).abs() < 1e-12);
        assert!(add_noise(
            &exact,
            &Noise {
                level: -1.0,
                ..mk(NoiseKind::Relative)
            }
        )
        .is_err());
        assert!(add_noise(
            &exact,
            &Noise {
                level: f64::NAN,
                ..mk(NoiseKind::Relative)
            }
        )
        .is_err());
    }

    #[test]
    fn relative_noise_statistics() {
        let exact: Vec<f64> = (1..=20_000).map(|i| i as f64).collect();
        let eps = 0.05;
        let n = add_noise(
            &exact,
            &Noise {
                kind: NoiseKind::Relative,
                level: eps,
                seed: 3,
            },
        )
        .unwrap();
        let r: Vec<f64> = n
            .value
            .iter()
            .zip(&exact)
            .map(|(v, l)| v / l - 1.0)
            .collect();
        let mean = r.iter().sum::<f64>() / r.len() as f64;
        let sd = (r.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (r.len() - 1) as f64).sqrt();
        // Standard error of the mean is ε/√n ≈ 3.5e-4; of the sd about 0.5 %.
        assert!(
            mean.abs() < 4.0 * eps / (r.len() as f64).sqrt(),
            "mean {mean}"
        );
        assert!((sd / eps - 1.0).abs() < 0.03, "sd {sd}");
    }

    #[test]
    fn generate_matches_the_model() {
        let m = by_name("kbs", &ModelOptions::default()).unwrap();
        let p = [0.3, 2.0, 1.0];
        let layout = Layout::inplane();
        let d = generate(
            m.as_ref(),
            &p,
            &layout.angles(),
            1.0,
            Quantity::Radiance,
            &Noise::none(),
        )
        .unwrap();
        let geo = Geometry::new(&layout.samples(), &[1.0], Quantity::Radiance).unwrap();
        let mut want = vec![0.0; geo.len()];
        m.eval(&geo, &p, &mut want, None);
        assert_eq!(d.exact, want);
        assert_eq!(d.value, want);
        assert!(generate(
            m.as_ref(),
            &p[..2],
            &layout.angles(),
            1.0,
            Quantity::Radiance,
            &Noise::none()
        )
        .is_err());
        assert!(generate(
            m.as_ref(),
            &p,
            &layout.angles(),
            -1.0,
            Quantity::Radiance,
            &Noise::none()
        )
        .is_err());
    }

    #[test]
    fn parse_reads_back_describe() {
        let layouts = [
            Layout::inplane(),
            Layout::hemisphere(),
            Layout::grazing(),
            Layout::Hemisphere {
                n_theta_i: 2,
                n_theta_r: 3,
                n_phi_r: 4,
            },
            Layout::Grazing {
                n_theta_i: 1,
                n_theta_r: 30,
                n_phi_r: 7,
            },
            Layout::InPlane {
                theta_i_deg: vec![0.0, 12.5, 89.0],
                step_deg: 0.1,
                theta_r_max_deg: 90.0,
            },
        ];
        for l in layouts {
            assert_eq!(Layout::parse(&l.describe()).unwrap(), l, "{}", l.describe());
        }
        assert_eq!(
            Layout::parse("InPlane max=10 step=5")
                .unwrap()
                .angles()
                .len(),
            5 * 5
        );
        for bad in [
            "hemisphere 5x18",
            "hemisphere 5x18x36 7",
            "inplane theta_r=80",
            "inplane foo=1",
            "inplane step=x",
            "inplane step=0",
            "grazing 0x1x1",
        ] {
            assert!(Layout::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn inplane_non_dividing_step_is_symmetric() {
        let a = Layout::parse("inplane theta_i=30 max=85 step=0.7")
            .unwrap()
            .angles();
        assert_eq!(a.len(), 2 * 121 + 1);
        assert_eq!((a[0].theta_r, a[0].phi_r), (121.0 * 0.7, 180.0));
        assert_eq!((a[242].theta_r, a[242].phi_r), (121.0 * 0.7, 0.0));
        assert_eq!((a[121].theta_r, a[121].phi_r), (0.0, 0.0));
        // 900 × 0.1 rounds above 90: kept at 90.
        let a = Layout::parse("inplane theta_i=30 max=90 step=0.1")
            .unwrap()
            .angles();
        assert_eq!(a.len(), 1801);
        assert_eq!(a[1800].theta_r, 90.0);
        assert!(a.iter().all(|x| x.sample().validate().is_ok()));
    }

    proptest::proptest! {
        #[test]
        fn every_generated_layout_is_valid_and_reads_back(
            ni in 1usize..9, nr in 1usize..9, np in 1usize..9, grazing: bool,
            step in 0.05f64..40.0, max in 0.0f64..=90.0,
            ti in proptest::collection::vec(0.0f64..89.999, 1..4),
        ) {
            let grid = if grazing {
                Layout::Grazing { n_theta_i: ni, n_theta_r: nr, n_phi_r: np }
            } else {
                Layout::Hemisphere { n_theta_i: ni, n_theta_r: nr, n_phi_r: np }
            };
            let inplane = Layout::InPlane { theta_i_deg: ti.clone(), step_deg: step, theta_r_max_deg: max };
            for l in [grid, inplane] {
                proptest::prop_assert!(l.validate().is_ok());
                let a = l.angles();
                proptest::prop_assert!(!a.is_empty());
                for x in &a {
                    proptest::prop_assert!(x.sample().validate().is_ok(), "{:?}", x);
                }
                proptest::prop_assert_eq!(Layout::parse(&l.describe()).unwrap(), l.clone());
            }
            proptest::prop_assert_eq!(Layout::Hemisphere { n_theta_i: ni, n_theta_r: nr, n_phi_r: np }.angles().len(), ni * nr * np);
            let k = (max / step + 1e-9).floor() as usize;
            proptest::prop_assert_eq!(
                Layout::InPlane { theta_i_deg: ti.clone(), step_deg: step, theta_r_max_deg: max }.angles().len(),
                ti.len() * (2 * k + 1)
            );
        }
    }

    #[test]
    fn truth_path_sits_beside_the_data() {
        assert_eq!(
            truth_path(Path::new("/tmp/x/data.csv")),
            Path::new("/tmp/x/data.truth.json")
        );
        assert_eq!(truth_path(Path::new("data")), Path::new("data.truth.json"));
    }
}
