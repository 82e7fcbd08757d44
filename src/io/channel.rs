//! `--channel` on a CSV dataset: a group, a wavelength, or every wavelength as a channel.

use super::{nm_per, parse_length, Dataset};
use crate::error::{Error, Result};

/// `--channel` on a CSV dataset. With a `group` column: `all` keeps every group, a label
/// keeps that group. Without one: `all` labels each sample by its wavelength (one channel per
/// wavelength, e.g. `0.532µm`), and a wavelength (`0.532` in the file's unit, or with a unit
/// such as `532nm` when the file's unit is known) keeps the rows whose `wavelength` equals it
/// to 1e-9 relative. A channel that selects nothing is an error listing what there is.
pub(crate) fn select_csv_channel(ds: Dataset, channel: Option<&str>) -> Result<Dataset> {
    let Some(want) = channel.map(str::trim) else {
        return Ok(ds);
    };
    let all = want.eq_ignore_ascii_case("all");
    if ds.channel.is_some() {
        if all {
            return Ok(ds);
        }
        let names = ds.channel_names();
        let idx = ds.channel_indices(want);
        if idx.is_empty() {
            return Err(Error::Usage(format!(
                "{}: no group '{want}' (groups: {}; or 'all')",
                ds.path.display(),
                names.join(", ")
            )));
        }
        return Ok(ds.subset(&idx));
    }
    let Some(wl) = ds.wavelength.clone() else {
        return Err(Error::Usage(format!(
            "{}: --channel '{want}' needs a group column or a wavelength column to select by (the file has neither)",
            ds.path.display()
        )));
    };
    let unit = ds.wavelength_unit.clone().unwrap_or_default();
    let distinct = distinct_values(&wl);
    let label = |v: f64| format!("{v}{unit}");
    if all {
        let mut ds = ds;
        ds.channel = Some(wl.iter().map(|&v| label(v)).collect());
        return Ok(ds);
    }
    let listing = || {
        distinct
            .iter()
            .map(|&v| label(v))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let (value, given_unit) = parse_length(want).map_err(|_| {
        Error::Usage(format!(
            "{}: --channel '{want}' is neither 'all' nor a wavelength (wavelengths: {})",
            ds.path.display(),
            listing()
        ))
    })?;
    let target = match (given_unit, ds.wavelength_unit.as_deref()) {
        (None, _) => value,
        (Some(u), Some(file_unit)) => value * nm_per(u) / nm_per(file_unit),
        (Some(u), None) => {
            return Err(Error::Usage(format!(
                "{}: --channel '{want}' has a unit ({u}) but the file's wavelength column states none: give the number in the column's unit (wavelengths: {})",
                ds.path.display(),
                listing()
            )))
        }
    };
    let idx: Vec<usize> = (0..wl.len())
        .filter(|&i| (wl[i] - target).abs() <= 1e-9 * target.abs())
        .collect();
    if idx.is_empty() {
        return Err(Error::Usage(format!(
            "{}: no rows at wavelength {want} (wavelengths: {})",
            ds.path.display(),
            listing()
        )));
    }
    let mut sub = ds.subset(&idx);
    sub.channel = Some(vec![label(target); idx.len()]);
    Ok(sub)
}

/// The distinct values of `v` in first-appearance order.
fn distinct_values(v: &[f64]) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    for &x in v {
        if !out.contains(&x) {
            out.push(x);
        }
    }
    out
}
