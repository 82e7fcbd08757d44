//! Measurement layouts: which directions a data set is measured at, for synthetic data
//! sets ([`crate::harness::synth`], whose module documentation has the table of layouts)
//! and for the candidates of a measurement design ([`crate::design`]).

use crate::error::{Error, Result};
use crate::geometry::{wrap_phi, Sample};

use std::path::Path;

/// One direction pair in **degrees**, exactly as written to (or read from) a CSV file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnglesDeg {
    /// Incidence polar angle θi from the surface normal, degrees.
    pub theta_i: f64,
    /// Reflection (view) polar angle θr from the surface normal, degrees.
    pub theta_r: f64,
    /// View azimuth φr from the plane of incidence, degrees (0: the forward, mirror side;
    /// 180: back towards the source).
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
pub(crate) const INPLANE_THETA_I_DEG: [f64; 5] = [15.0, 30.0, 45.0, 60.0, 75.0];
/// Default in-plane θr step and largest |θr|, degrees.
pub(crate) const INPLANE_STEP_DEG: f64 = 1.0;
/// Default largest |θr| of the in-plane scans, degrees.
pub(crate) const INPLANE_THETA_R_MAX_DEG: f64 = 85.0;
/// Default grid (θi, θr, φr counts) of the hemisphere and grazing layouts.
pub(crate) const DEFAULT_GRID: (usize, usize, usize) = (5, 18, 36);

/// Where the synthetic instrument looks. See the module documentation for the exact angles.
#[derive(Debug, Clone, PartialEq)]
pub enum Layout {
    /// Scans in the plane of incidence: for each θi, signed θr = k·`step_deg` for every
    /// integer k with |k·step| ≤ `theta_r_max_deg`, ascending (θr < 0 stored as |θr| at
    /// φr = 180°).
    InPlane {
        /// Incidence angles θi of the scans, degrees, one scan each.
        theta_i_deg: Vec<f64>,
        /// Spacing of the signed θr values, degrees.
        step_deg: f64,
        /// Largest |θr|, degrees.
        theta_r_max_deg: f64,
    },
    /// θi × θr × φr grid over the hemisphere (θi outer, φr inner).
    Hemisphere {
        /// Number of θi values: cell midpoints of [0°, 90°).
        n_theta_i: usize,
        /// Number of θr values: cell midpoints of (0°, 90°).
        n_theta_r: usize,
        /// Number of φr values: −180° + 360° l/n for l = 0…n − 1.
        n_phi_r: usize,
    },
    /// As `Hemisphere`, with θi from 70° to 89°.
    Grazing {
        /// Number of θi values, evenly from 70° to 89° inclusive (89° alone for one).
        n_theta_i: usize,
        /// Number of θr values: cell midpoints of (0°, 90°).
        n_theta_r: usize,
        /// Number of φr values: −180° + 360° l/n for l = 0…n − 1.
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
pub(crate) fn parse_grid(text: &str) -> Result<(usize, usize, usize)> {
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
pub(crate) fn subsample(angles: &[AnglesDeg], n: usize) -> Result<Vec<AnglesDeg>> {
    let len = angles.len();
    if n == 0 || n > len {
        return Err(Error::Usage(format!(
            "--samples {n}: must be between 1 and the layout's {len} samples (use --grid or --step for a denser layout)"
        )));
    }
    Ok((0..n).map(|k| angles[k * len / n]).collect())
}
