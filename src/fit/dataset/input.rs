//! A dataset's fit input: the geometry of its samples, its values and weights for the
//! residual kind, and its channels; the checks that the values can be fitted in double
//! precision.

use super::DatasetFit;
use crate::error::{Error, Result};
use crate::fit::driver::{self, FitConfig, FitInput};
use crate::fit::problem::weights::residual_weights;
use crate::fit::problem::{Channels, ResidualKind};
use crate::geometry::{Geometry, Sample};
use crate::io::{self, Dataset};
use crate::model::domain::short_number;

impl DatasetFit {
    /// The fit input of a dataset with this fit's quantity, wavelength, residual and floor
    /// (angles, values, weights for the residual kind, channels).
    pub fn input(&self, ds: &Dataset, needs_wavelength: bool) -> Result<FitInput> {
        check_magnitudes(ds)?;
        let y = ds.value.clone();
        self.input_of(ds, &ds.samples, y, needs_wavelength)
    }

    /// [`DatasetFit::input`], taking the dataset's samples, values and source lines into
    /// the input rather than copying them (a one-channel fit needs them no more), and a
    /// wavelength column of one value kept as that value once: the table as read and the
    /// prepared geometry are not held side by side in full.
    pub(super) fn input_taking(
        &self,
        ds: &mut Dataset,
        needs_wavelength: bool,
    ) -> Result<FitInput> {
        check_magnitudes(ds)?;
        ds.lines = Vec::new();
        // A wavelength column of one value: that value once (the geometry holds it so).
        if let Some(w) = ds.wavelength.as_mut() {
            if w.iter().all(|l| l.to_bits() == w[0].to_bits()) {
                w.truncate(1);
                w.shrink_to_fit();
            }
        }
        let y = ds.value.take();
        let samples = std::mem::take(&mut ds.samples);
        self.input_of(ds, &samples, y, needs_wavelength)
    }

    /// The fit's data from a dataset's `samples` and values `y` (the caller checked them
    /// with [`check_magnitudes`]): geometry (λ from this fit's wavelength, else the
    /// dataset's own, else 1 unless `needs_wavelength`), values, the weights transformed
    /// for the residual kind ([`crate::fit::problem::weights`]), and the channel index of
    /// every sample with the channel names (as printed: control and bidi characters
    /// escaped) in first-appearance order.
    fn input_of(
        &self,
        ds: &Dataset,
        samples: &[Sample],
        y: Option<Vec<f64>>,
        needs_wavelength: bool,
    ) -> Result<FitInput> {
        let (residual, floor) = (self.config.residual, self.config.floor);
        let y = y.ok_or_else(|| Error::File {
            path: ds.path.clone(),
            message: "no measured value column (L)".into(),
        })?;
        let n = samples.len();
        let lambda: Vec<f64> = match (&ds.wavelength, self.wavelength) {
            (_, Some(l)) => vec![l],
            (Some(w), None) => w.clone(),
            (None, None) if needs_wavelength => {
                return Err(Error::Usage(format!(
                    "{}: KBS models need a wavelength: give --wavelength, a wavelength column, or an ASTM channel such as 550nm",
                    io::shown(&ds.path)
                )))
            }
            (None, None) => vec![1.0],
        };
        let geo = Geometry::new(samples, &lambda, self.quantity)?;
        if let (Some(f), ResidualKind::Relative | ResidualKind::Log) = (floor, residual) {
            check_floor(f, y.iter().fold(0.0f64, |m, v| m.max(v.abs())))?;
        }
        let floor = floor_for(floor, &y);
        let (weight, _) = residual_weights(
            ds.weight.as_deref().filter(|_| ds.sigma_l.is_none()),
            ds.sigma_l.as_deref(),
            &y,
            residual,
            floor,
        );
        let (channel, channel_names) = match &ds.channel {
            Some(labels) => {
                let (index, names) = channel_index(labels);
                (index.into(), names)
            }
            None => (Channels::single(n), vec![String::new()]),
        };
        Ok(FitInput {
            geo,
            y: y.into(),
            weight,
            channel,
            channel_names,
        })
    }
}

/// The largest |L|·√w, |L| and w (and the smallest w) a fit accepts: the cost ½Σw r² and
/// the Jacobian products square these, so beyond them double precision overflows (cost
/// = inf, R² = NaN). The fit is the same in any unit of L (amplitudes scale with it) and
/// under any common factor of the weights, so rescaling the file loses nothing.
pub(crate) const MAGNITUDE_LIMIT: f64 = 1e100;

/// Refuse values and weights the fit cannot square in double precision (see
/// `MAGNITUDE_LIMIT`), naming the file, line and column of the first one (for arrays,
/// which have no header: the array and its 0-based index, [`Error::Element`]).
pub fn check_magnitudes(ds: &Dataset) -> Result<()> {
    let Some(y) = &ds.value else { return Ok(()) };
    let column = |i: usize, what: &str| match &ds.channel {
        Some(ch) if ds.headers.iter().any(|h| h == "channel") => ch[i].clone(),
        _ => what.to_string(),
    };
    let lim = MAGNITUDE_LIMIT;
    for (i, &v) in y.iter().enumerate() {
        let w = ds.weight.as_ref().map_or(1.0, |w| w[i]);
        let (col, msg) = if v.abs() > lim {
            (
                column(i, "L"),
                format!(
                    "value {} is beyond ±{lim:e}: the fit squares values (cost ½Σw r²) and would overflow double precision; express L in another unit (the fit is the same in any unit of L)",
                    short_number(v)
                ),
            )
        } else if !(1.0 / lim..=lim).contains(&w) || v.abs() * w.sqrt() > lim {
            let col = if ds.sigma_l.is_some() {
                "sigma_L"
            } else if ds.headers.is_empty() {
                "weights"
            } else {
                "weight"
            };
            (
                col.to_string(),
                format!(
                    "weight {} (with L = {}) is outside what the fit can square (weights in [{:e}, {lim:e}], |L|·√w ≤ {lim:e}); scale every weight or uncertainty by one factor (the fitted parameters do not change)",
                    short_number(w),
                    short_number(v),
                    1.0 / lim
                ),
            )
        } else {
            continue;
        };
        return Err(if ds.headers.is_empty() {
            Error::element(&col, i, msg)
        } else {
            Error::input(&ds.path, ds.lines[i], &col, msg)
        });
    }
    Ok(())
}

/// The channel index of every label and the distinct names in first-appearance order (as
/// printed: control and bidi characters escaped).
fn channel_index(labels: &[String]) -> (Vec<usize>, Vec<String>) {
    let mut names: Vec<String> = Vec::new();
    let idx = labels
        .iter()
        .map(|l| match names.iter().position(|x| x == l) {
            Some(i) => i,
            None => {
                names.push(l.clone());
                names.len() - 1
            }
        })
        .collect();
    let names = names
        .iter()
        .map(|n| io::shown_text(n).into_owned())
        .collect();
    (idx, names)
}

/// The residual floor: `floor`, or 1e-6 × max |y| (as the fit computes it).
pub(crate) fn floor_for(floor: Option<f64>, y: &[f64]) -> f64 {
    driver::residual_floor(
        &FitConfig {
            floor,
            ..FitConfig::default()
        },
        y,
    )
}

/// Refuse a `floor` at or above the largest |value| of the data (`max_abs`): every value
/// would be raised to it and every residual would be 0.
fn check_floor(floor: f64, max_abs: f64) -> Result<()> {
    if floor >= max_abs {
        return Err(Error::Usage(format!(
            "floor {} is not below the largest measured value ({}): every value would be raised to it and every residual be 0; give a floor well below the data (default 1e-6 × the largest |L|)",
            short_number(floor),
            short_number(max_abs)
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::check_floor;

    #[test]
    fn a_floor_must_lie_below_the_largest_measured_value() {
        assert!(check_floor(2.0, 2.0).is_err() && check_floor(1.0, 2.0).is_ok());
    }
}
