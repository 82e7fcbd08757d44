//! The numeric options of every command, validated in one place before any work starts:
//! the command line and the Python package call these same functions, so a value one
//! refuses the other refuses too, with the same words. A refused value is an
//! [`Error::Usage`] (CLI exit code 2, Python `ValueError`) naming the option as the caller
//! spells it ([`Front`]) and saying what is accepted. [`super::Settings::check`] checks a
//! fit's settings with them.
//!
//! | option | accepted |
//! |---|---|
//! | `timeout` (s) | 0 < t ≤ 1e9 (about 32 years; leave it out for no limit) |
//! | `threads` | ≥ 1; more than the machine's cores is capped at its cores, with a note |
//! | `max_iter` | any count (0: the report of the starting point, not converged) |
//! | `tol` | [1e-16, 0.1] |
//! | `f_scale` | [1e-100, 1e100] (its square, the loss's scale, stays a normal number) |
//! | `floor` | finite, > 0 (and below the largest measured value: `crate::fit::dataset`) |
//! | `wavelength`, `patch` half-sizes | [1e-30, 1e30] |
//! | `init`, `fix` values | finite |
//! | `subsample` | 1 ..= 90 |
//! | `scenes` (recover) | 1 ..= 1,000,000 (every scene is drawn, so the count is memory) |

use crate::error::{Error, Result};
use crate::geometry::LENGTH_RANGE;
use crate::model::domain::short_number;
use crate::model::{EvalMode, ModelOptions, TOL_RANGE};
use std::time::Duration;

/// Who names the option in messages: the command line (`--f-scale`) or the Python
/// package (`f_scale`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Front {
    /// The command line: options spelled `--kebab-case`.
    Cli,
    /// The Python package: keywords spelled `snake_case`.
    Python,
    /// A settings object in JSON (a report's `replay.settings`): keys spelled `snake_case`.
    Json,
}

impl Front {
    /// The option `key` (snake case, as Python spells it) as this front end spells it.
    pub fn name(self, key: &str) -> String {
        match self {
            Front::Cli => format!("--{}", key.replace('_', "-")),
            Front::Python | Front::Json => key.to_string(),
        }
    }

    /// Where a report says a value given through option `key` came from: `--key`,
    /// `key keyword` (Python) or `key setting` (JSON).
    pub fn source(self, key: &str) -> String {
        match self {
            Front::Cli => self.name(key),
            Front::Python => format!("{key} keyword"),
            Front::Json => format!("{key} setting"),
        }
    }

    fn refuse(self, key: &str, value: f64, why: &str) -> Error {
        Error::Usage(format!("{} {}: {why}", self.name(key), short_number(value)))
    }
}

/// The longest time limit, in seconds (about 32 years): beyond it no deadline is computable
/// on every platform, and no run needs one.
pub const MAX_TIMEOUT_SECONDS: f64 = 1e9;

/// A time limit in seconds as a [`Duration`]: finite, > 0, at most
/// [`MAX_TIMEOUT_SECONDS`]. None stays None (no limit).
pub fn timeout(front: Front, seconds: Option<f64>) -> Result<Option<Duration>> {
    let Some(t) = seconds else {
        return Ok(None);
    };
    if !(t > 0.0 && t <= MAX_TIMEOUT_SECONDS) {
        return Err(front.refuse(
            "timeout",
            t,
            &format!(
                "a time limit is a number of seconds > 0 and at most {MAX_TIMEOUT_SECONDS:e} (about 32 years); leave it out for no limit"
            ),
        ));
    }
    Ok(Some(Duration::from_secs_f64(t)))
}

/// The threads to run on: `requested`, at most the machine's cores (then with a note that
/// says so), or all cores when None. Zero is refused.
pub fn threads(front: Front, requested: Option<usize>) -> Result<(usize, Option<String>)> {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    match requested {
        None => Ok((cores, None)),
        Some(0) => Err(Error::Usage(format!(
            "{} 0: at least one thread; leave it out for all {cores} cores",
            front.name("threads")
        ))),
        Some(n) if n > cores => Ok((
            cores,
            Some(format!(
                "{} {n}: this machine has {cores} cores; running on {cores} threads",
                front.name("threads")
            )),
        )),
        Some(n) => Ok((n, None)),
    }
}

/// The robust loss's scale C: within [1e-100, 1e100], so that C² and f²/C² of every
/// residual the fit accepts stay finite.
pub fn f_scale(front: Front, c: f64) -> Result<f64> {
    if !(1e-100..=1e100).contains(&c) {
        return Err(front.refuse(
            "f_scale",
            c,
            "the loss scale must be a finite number > 0 within [1e-100, 1e100], the size of a weighted residual beyond which a sample counts as an outlier (e.g. 0.03 for 3 % with relative residuals)",
        ));
    }
    Ok(c)
}

/// The floor of relative and log residuals: finite and > 0 (None: the default,
/// 1e-6 × max |L|). The fit of a dataset compares it with the data (`crate::fit::dataset`).
pub fn floor(front: Front, floor: Option<f64>) -> Result<Option<f64>> {
    match floor {
        Some(f) if !(f.is_finite() && f > 0.0) => Err(front.refuse(
            "floor",
            f,
            "the floor of relative and log residuals must be a finite number > 0 (default 1e-6 × the largest |L|)",
        )),
        f => Ok(f),
    }
}

/// A length option (`wavelength`, a `patch` half-size) within `LENGTH_RANGE`.
pub fn length(front: Front, key: &str, v: f64) -> Result<f64> {
    let (lo, hi) = LENGTH_RANGE;
    if !(lo..=hi).contains(&v) {
        return Err(front.refuse(
            key,
            v,
            &format!("a length must be a finite number within [{lo:e}, {hi:e}]"),
        ));
    }
    Ok(v)
}

/// The most scenes `recover` draws (each is drawn, fitted or not, so that a scene keeps its
/// truth and noise whatever `--only` says).
pub const MAX_SCENES: usize = 1_000_000;

/// The number of scenes of a recovery run: 1 ..= [`MAX_SCENES`].
pub fn scenes(front: Front, n: usize) -> Result<usize> {
    if !(1..=MAX_SCENES).contains(&n) {
        return Err(Error::Usage(format!(
            "{} {n}: the number of scenes must lie in 1 ..= {MAX_SCENES}",
            front.name("scenes")
        )));
    }
    Ok(n)
}

/// The relative accuracy target of the KBS evaluation: within `TOL_RANGE`.
pub fn tol(front: Front, tol: f64) -> Result<f64> {
    if !(TOL_RANGE.0..=TOL_RANGE.1).contains(&tol) {
        return Err(front.refuse(
            "tol",
            tol,
            "the relative accuracy target must lie in [1e-16, 0.1]",
        ));
    }
    Ok(tol)
}

/// The model options with `tol` and the `patch` half-sizes checked.
pub fn model_options(
    front: Front,
    mode: EvalMode,
    tol_value: f64,
    patch: Option<(f64, f64)>,
) -> Result<ModelOptions> {
    let patch = match patch {
        Some((x, y)) => Some((length(front, "patch", x)?, length(front, "patch", y)?)),
        None => None,
    };
    Ok(ModelOptions {
        mode,
        tol: tol(front, tol_value)?,
        patch,
        ..ModelOptions::default()
    })
}

/// The largest MERL subsampling step (every K-th θd and φd cell; θd has 90 cells).
pub const MAX_SUBSAMPLE: usize = 90;

impl super::Settings {
    /// Check every value, as the front end spells the options in its messages: the time
    /// limit, the KBS evaluation's tolerance and patch, the loss scale, the floor, the
    /// wavelength, `init` and `fix` (finite numbers), the threads, the CSV columns and the
    /// MERL subsampling. The model's name is checked when the fit starts.
    pub fn check(&self, front: Front) -> Result<()> {
        timeout(front, self.timeout)?;
        model_options(front, self.mode, self.tol, self.patch)?;
        f_scale(front, self.f_scale)?;
        floor(front, self.floor)?;
        if let Some(l) = self.wavelength {
            length(front, "wavelength", l)?;
        }
        for (name, v) in self.init.iter().chain(&self.fix) {
            if !v.is_finite() {
                return Err(Error::Param {
                    name: name.clone(),
                    message: format!("{} is not a finite number", short_number(*v)),
                });
            }
        }
        threads(front, self.threads)?;
        crate::io::csv::parse_columns(self.columns.as_deref().unwrap_or(""))?;
        if !(1..=MAX_SUBSAMPLE).contains(&self.subsample) {
            return Err(Error::Usage(format!(
                "{} {}: every K-th cell, K in 1 ..= {MAX_SUBSAMPLE}",
                front.name("subsample"),
                self.subsample
            )));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_hostile_value_is_refused_with_the_option_named() {
        for v in [f64::NAN, f64::INFINITY, -1.0, 0.0, 1e300, 1e19] {
            let e = timeout(Front::Cli, Some(v)).unwrap_err().to_string();
            assert!(e.starts_with("--timeout "), "{e}");
        }
        for v in [f64::NAN, f64::INFINITY, -1.0, 0.0, 1e-300, 1e160] {
            let e = f_scale(Front::Python, v).unwrap_err().to_string();
            assert!(e.starts_with("f_scale "), "{e}");
            assert!(length(Front::Cli, "wavelength", v).is_err());
        }
        for v in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY, -1.0, 0.0] {
            assert!(floor(Front::Cli, Some(v)).is_err());
        }
        assert!(floor(Front::Cli, Some(1e-300)).is_ok());
        assert_eq!(
            timeout(Front::Cli, Some(1e9)).unwrap().unwrap().as_secs(),
            1e9 as u64
        );
    }

    #[test]
    fn threads_are_capped_at_the_cores() {
        let cores = std::thread::available_parallelism().unwrap().get();
        assert_eq!(threads(Front::Cli, None).unwrap(), (cores, None));
        let (n, note) = threads(Front::Cli, Some(usize::MAX)).unwrap();
        assert_eq!(n, cores);
        assert!(note.unwrap().contains("cores"));
        assert!(threads(Front::Python, Some(0)).is_err());
    }
}
