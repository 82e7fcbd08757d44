//! The geometries a design may choose from: the rows of a file, or a grid within the
//! instrument's reach.

use crate::error::{Error, Result};
use crate::geometry::layout::{AnglesDeg, Layout};
use std::path::Path;

/// Most candidates a design considers (a 0.5° hemisphere grid to 85° has 2.6 M: choose a
/// coarser step or a file).
pub(crate) const MAX_CANDIDATES: usize = 1_000_000;

/// A grid of reachable geometries: θi and θr from 0 to `theta_max_deg` in steps of
/// `step_deg`; φr either 0 and 180° (`in_plane`: the plane of incidence, specular and back
/// side) or 0 to 180° in the same step (the models are isotropic: φr and −φr measure the
/// same). Where θi or θr is 0, φr does not change the geometry and only φr = 0 is kept.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// Largest θi and θr of the grid, degrees.
    pub theta_max_deg: f64,
    /// Spacing of θi, θr (and φr off the plane) in degrees.
    pub step_deg: f64,
    /// Whether φr is only 0° and 180° (the plane of incidence) rather than 0° to 180°.
    pub in_plane: bool,
}

impl Default for Grid {
    fn default() -> Self {
        Grid {
            theta_max_deg: 85.0,
            step_deg: 2.5,
            in_plane: false,
        }
    }
}

impl Grid {
    /// The grid's geometries, in θi, θr, φr order. Errors: a limit outside (0, 90), a step
    /// that is not positive, or more than `MAX_CANDIDATES` points.
    pub fn angles(&self) -> Result<Vec<AnglesDeg>> {
        let (max, step) = (self.theta_max_deg, self.step_deg);
        if !(max.is_finite() && max > 0.0 && max < 90.0) {
            return Err(Error::Usage(format!(
                "--theta-max {max}: the largest angle must be in (0, 90) degrees"
            )));
        }
        if !(step.is_finite() && step > 0.0 && step <= max) {
            return Err(Error::Usage(format!(
                "--step {step}: the grid step must be positive and at most --theta-max ({max}°)"
            )));
        }
        let thetas = ladder(0.0, max, step);
        let phis = if self.in_plane {
            vec![0.0, 180.0]
        } else {
            ladder(0.0, 180.0, step)
        };
        let count = thetas.len() * thetas.len() * phis.len();
        if count > MAX_CANDIDATES {
            return Err(Error::Usage(format!(
                "the grid of step {step}° has {count} candidates, more than {MAX_CANDIDATES}: choose a larger --step or --in-plane"
            )));
        }
        let mut out = Vec::with_capacity(count);
        for &theta_i in &thetas {
            for &theta_r in &thetas {
                let fold = theta_i == 0.0 || theta_r == 0.0;
                for &phi_r in if fold { &phis[..1] } else { &phis[..] } {
                    out.push(AnglesDeg {
                        theta_i,
                        theta_r,
                        phi_r,
                    });
                }
            }
        }
        Ok(out)
    }
}

/// from, from + step, … up to `to` (inclusive within 1e-9 of a step), as exact multiples.
fn ladder(from: f64, to: f64, step: f64) -> Vec<f64> {
    let n = ((to - from) / step + 1e-9).floor() as usize;
    (0..=n).map(|k| from + k as f64 * step).collect()
}

/// The candidate geometries of a CSV file with columns theta_i, theta_r, phi_r in degrees
/// (the layout files of `goniofit synth`: any column order, other columns ignored, a signed
/// θr < 0 taken as |θr| on the other side). Errors name the file, line and column.
pub(crate) fn read(path: &Path) -> Result<Vec<AnglesDeg>> {
    let file_err = |message: String| Error::File {
        path: path.to_path_buf(),
        message,
    };
    let Layout::Angles(a) = Layout::read_csv(path)? else {
        return Err(file_err("not a table of angles".into()));
    };
    if a.len() > MAX_CANDIDATES {
        return Err(file_err(format!(
            "{} candidate rows, more than {MAX_CANDIDATES}",
            a.len()
        )));
    }
    Ok(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn in_plane_grid_counts() {
        let g = Grid {
            theta_max_deg: 80.0,
            step_deg: 10.0,
            in_plane: true,
        };
        let a = g.angles().unwrap();
        // θ ∈ {0, 10, …, 80}: 9 values; 8 × 8 pairs with both non-zero take φr 0 and 180,
        // the 17 pairs with a zero angle one φr.
        assert_eq!(a.len(), 8 * 8 * 2 + 17);
        assert!(a.iter().all(|x| x.theta_i <= 80.0 && x.theta_r <= 80.0));
        assert!(Grid {
            theta_max_deg: 90.0,
            ..g
        }
        .angles()
        .is_err());
        assert!(Grid { step_deg: 0.0, ..g }.angles().is_err());
    }
}
