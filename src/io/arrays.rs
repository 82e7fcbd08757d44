//! Measurements handed over as arrays (the Python package): the checks of the file readers
//! (angles in the domain of MODEL.md, finite values, positive weights, uncertainties and
//! wavelengths), with errors that name the array and the 0-based index
//! ([`Error::Element`]) instead of a file line.

use super::{check_angles, Dataset};
use crate::error::{Error, Result};
use std::path::PathBuf;

/// Per-sample arrays; every present array has the length of `theta_i`.
#[derive(Debug, Clone, Copy, Default)]
pub struct Columns<'a> {
    /// Incidence angle from the normal (degrees, or radians with `radians`).
    pub theta_i: &'a [f64],
    /// View angle from the normal.
    pub theta_r: &'a [f64],
    /// View azimuth, φr = 0 the forward (specular) side.
    pub phi_r: &'a [f64],
    /// Measured radiance or BRDF.
    pub value: Option<&'a [f64]>,
    /// Weights w > 0.
    pub weight: Option<&'a [f64]>,
    /// Standard uncertainties of the value (> 0); the weights become 1/σ².
    pub sigma_l: Option<&'a [f64]>,
    /// Wavelength per sample (> 0, the unit of σ and T).
    pub wavelength: Option<&'a [f64]>,
    /// Channel label per sample (a joint fit over channels, or groups to split).
    pub channel: Option<&'a [String]>,
}

/// A [`Dataset`] named `name` from arrays, checked as a file's rows are: the first bad
/// element is an [`Error::Element`] naming its array and index; arrays of different
/// lengths, no samples, both weights and sigma_L, or values that are all zero are an
/// [`Error::Usage`]. `signed_theta_r`: θr < 0 is the back side (φr + 180°).
pub fn dataset(name: &str, cols: &Columns, radians: bool, signed_theta_r: bool) -> Result<Dataset> {
    let n = cols.theta_i.len();
    check_lengths(cols, n)?;
    if cols.weight.is_some() && cols.sigma_l.is_some() {
        return Err(Error::Usage(
            "both weights and sigma_L given: give one (weights are 1/sigma_L²)".into(),
        ));
    }
    for (array, v) in [
        ("theta_i", Some(cols.theta_i)),
        ("theta_r", Some(cols.theta_r)),
        ("phi_r", Some(cols.phi_r)),
        ("L", cols.value),
    ] {
        if let Some(v) = v {
            finite(array, v)?;
        }
    }
    let mut samples = Vec::with_capacity(n);
    for i in 0..n {
        let s = check_angles(
            cols.theta_i[i],
            cols.theta_r[i],
            cols.phi_r[i],
            radians,
            signed_theta_r,
        )
        .map_err(|(array, message)| Error::element(array, i, message))?;
        samples.push(s);
    }
    if let Some(v) = cols.value {
        if v.iter().all(|&x| x == 0.0) {
            return Err(Error::Usage(format!(
                "all {n} values of L are zero: nothing to fit"
            )));
        }
    }
    let weight = match (cols.weight, cols.sigma_l) {
        (Some(w), _) => Some(positive("weights", w)?.to_vec()),
        (None, Some(s)) => Some(inverse_variances(positive("sigma_L", s)?)?),
        (None, None) => None,
    };
    let wavelength = cols
        .wavelength
        .map(|w| positive("wavelength", w).map(<[f64]>::to_vec))
        .transpose()?;
    Ok(Dataset {
        path: PathBuf::from(name),
        headers: Vec::new(),
        rows: vec![Vec::new(); n],
        lines: (0..n).collect(),
        samples,
        value: cols.value.map(<[f64]>::to_vec),
        weight,
        sigma_l: cols.sigma_l.map(<[f64]>::to_vec),
        wavelength,
        wavelength_unit: None,
        wavelength_origin: cols.wavelength.map(|_| "wavelength array"),
        channel: cols.channel.map(<[String]>::to_vec),
        quantity: None,
    })
}

/// Every array as long as `theta_i`, and at least one sample.
fn check_lengths(cols: &Columns, n: usize) -> Result<()> {
    if n == 0 {
        return Err(Error::Usage("no samples: theta_i is empty".into()));
    }
    let lengths = [
        ("theta_r", Some(cols.theta_r.len())),
        ("phi_r", Some(cols.phi_r.len())),
        ("L", cols.value.map(<[f64]>::len)),
        ("weights", cols.weight.map(<[f64]>::len)),
        ("sigma_L", cols.sigma_l.map(<[f64]>::len)),
        ("wavelength", cols.wavelength.map(<[f64]>::len)),
        ("channel", cols.channel.map(<[String]>::len)),
    ];
    for (array, len) in lengths {
        if let Some(len) = len.filter(|&len| len != n) {
            return Err(Error::Usage(format!(
                "{array} has {len} elements, theta_i has {n}: give one value per sample"
            )));
        }
    }
    Ok(())
}

/// The first non-finite element of `v` as an error.
fn finite(array: &str, v: &[f64]) -> Result<()> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => Err(Error::element(
            array,
            i,
            format!("{} is not a finite number", v[i]),
        )),
        None => Ok(()),
    }
}

/// `v` if every element is finite and positive; else the first that is not, as an error.
fn positive<'a>(array: &str, v: &'a [f64]) -> Result<&'a [f64]> {
    match v.iter().position(|&x| !(x.is_finite() && x > 0.0)) {
        Some(i) => Err(Error::element(
            array,
            i,
            format!("{} must be finite and positive", v[i]),
        )),
        None => Ok(v),
    }
}

/// Weights 1/σ² of positive uncertainties; an error where 1/σ² is not finite.
fn inverse_variances(sigma: &[f64]) -> Result<Vec<f64>> {
    sigma
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let w = 1.0 / (s * s);
            if w.is_finite() && w > 0.0 {
                Ok(w)
            } else {
                Err(Error::element(
                    "sigma_L",
                    i,
                    format!("{s}: 1/sigma_L² is not a finite positive weight"),
                ))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cols<'a>(ti: &'a [f64], tr: &'a [f64], pr: &'a [f64], l: &'a [f64]) -> Columns<'a> {
        Columns {
            theta_i: ti,
            theta_r: tr,
            phi_r: pr,
            value: Some(l),
            ..Columns::default()
        }
    }

    #[test]
    fn angles_become_radians_as_in_a_file() {
        let ds = dataset(
            "arrays",
            &cols(&[30.0, 0.0], &[45.0, 10.0], &[180.0, 0.0], &[1.0, 2.0]),
            false,
            false,
        )
        .unwrap();
        assert_eq!(ds.len(), 2);
        let s = ds.samples[0];
        assert!((s.theta_i - 30f64.to_radians()).abs() < 1e-15);
        assert!((s.theta_r - 45f64.to_radians()).abs() < 1e-15);
        assert_eq!(ds.value.unwrap(), vec![1.0, 2.0]);
    }

    #[test]
    fn errors_name_array_and_index() {
        let e = dataset(
            "arrays",
            &cols(&[30.0, 95.0], &[45.0, 10.0], &[0.0, 0.0], &[1.0, 2.0]),
            false,
            false,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("theta_i[1]: theta_i = 95° is outside [0, 90°)"),
            "{e}"
        );
        let e = dataset(
            "arrays",
            &cols(&[30.0, 10.0], &[45.0, 10.0], &[0.0, f64::NAN], &[1.0, 2.0]),
            false,
            false,
        )
        .unwrap_err()
        .to_string();
        assert_eq!(e, "phi_r[1]: NaN is not a finite number");
        let w = [1.0, -2.0];
        let c = Columns {
            weight: Some(&w),
            ..cols(&[30.0, 10.0], &[45.0, 10.0], &[0.0, 0.0], &[1.0, 2.0])
        };
        let e = dataset("arrays", &c, false, false).unwrap_err().to_string();
        assert_eq!(e, "weights[1]: -2 must be finite and positive");
        let e = dataset(
            "arrays",
            &cols(&[30.0, 10.0], &[45.0], &[0.0, 0.0], &[1.0, 2.0]),
            false,
            false,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.starts_with("theta_r has 1 elements, theta_i has 2"),
            "{e}"
        );
    }
}
