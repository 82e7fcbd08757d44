//! Values in files: a field's number, a sample's angles, lengths and wavelengths, and a
//! value written at full precision.

use crate::error::{Error, Result};
use crate::geometry::Sample;

/// Format a value with full precision: the shortest decimal that parses back to the same
/// `f64`, in scientific notation (`1.2345e-3`, `5e-1`, `NaN`, `inf`).
pub(crate) fn format_value(v: f64) -> String {
    format!("{v:e}")
}

/// Parse a decimal field as a finite number; the message shows the value.
pub(crate) fn parse_finite(field: &str) -> std::result::Result<f64, String> {
    let graphic = |b: Option<&u8>| b.is_some_and(u8::is_ascii_graphic);
    let bytes = field.as_bytes();
    let t = match graphic(bytes.first()) && graphic(bytes.last()) {
        true => field,
        false => field.trim(),
    };
    if t.is_empty() {
        return Err("empty field (a number is needed)".into());
    }
    match t.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        Ok(_) => Err(format!("'{t}' is not a finite number")),
        Err(_) => Err(format!("'{t}' is not a number")),
    }
}

/// Validate one sample's angles (in the file's unit) and convert them to radians in our
/// convention. `signed`: a negative polar angle means the opposite azimuth. Errors name
/// the column and show the value.
pub(crate) fn check_angles(
    theta_i: f64,
    theta_r: f64,
    phi_r: f64,
    radians: bool,
    signed: bool,
) -> std::result::Result<Sample, (&'static str, String)> {
    let (unit, right, full) = if radians {
        (
            " rad",
            std::f64::consts::FRAC_PI_2,
            2.0 * std::f64::consts::PI,
        )
    } else {
        ("°", 90.0, 360.0)
    };
    if !(0.0..right).contains(&theta_i) {
        return Err((
            "theta_i",
            format!(
                "theta_i = {theta_i}{unit} is outside [0, {right}{unit}){}",
                if theta_i < 0.0 && theta_i > -right {
                    " (incidence angles are measured from the normal and are never negative)"
                } else {
                    ""
                }
            ),
        ));
    }
    if theta_r.abs() > right || (theta_r < 0.0 && !signed) {
        return Err((
            "theta_r",
            format!(
                "theta_r = {theta_r}{unit} is outside [0, {right}{unit}]{}",
                if theta_r < 0.0 && theta_r >= -right {
                    " (for signed in-plane view angles use --signed-theta-r)"
                } else {
                    ""
                }
            ),
        ));
    }
    if phi_r.abs() > full * (1.0 + 1e-12) {
        return Err((
            "phi_r",
            format!("phi_r = {phi_r}{unit} is outside [-{full}{unit}, {full}{unit}]"),
        ));
    }
    let to_rad = |x: f64| if radians { x } else { x.to_radians() };
    let mut s = Sample {
        theta_i: to_rad(theta_i),
        theta_r: to_rad(theta_r.abs()),
        phi_r: to_rad(phi_r),
    };
    if theta_r < 0.0 {
        s.phi_r = crate::geometry::wrap_phi(s.phi_r + std::f64::consts::PI);
    }
    // Degrees → radians can round 90° − ε up to π/2 (never at or above it for θi < 90).
    s.theta_r = s.theta_r.min(std::f64::consts::FRAC_PI_2);
    if s.theta_i >= std::f64::consts::FRAC_PI_2 {
        s.theta_i = f64::from_bits(std::f64::consts::FRAC_PI_2.to_bits() - 1);
    }
    Ok(s)
}

/// Length units goniofit understands, as written in reports: nanometres and micrometres.
pub(crate) const LENGTH_UNITS: [(&str, f64); 2] = [("nm", 1.0), ("µm", 1000.0)];

/// Nanometres per `unit` (`nm`, `µm`; 1 for anything else).
pub(crate) fn nm_per(unit: &str) -> f64 {
    LENGTH_UNITS
        .iter()
        .find(|(u, _)| *u == unit)
        .map_or(1.0, |(_, f)| *f)
}

/// A positive length such as `633nm`, `633 nm`, `0.633um`, `0.633µm` or a bare `0.633`:
/// the number and its unit (`nm`, `µm`; None for a bare number), within
/// `crate::geometry::LENGTH_RANGE`. The error says what is accepted.
pub fn parse_length(text: &str) -> Result<(f64, Option<&'static str>)> {
    let t = text.trim();
    let lower = t.to_lowercase();
    let (num, unit) = if let Some(n) = lower.strip_suffix("nm") {
        (n.to_string(), Some("nm"))
    } else if let Some(n) = ["um", "µm", "μm", "micron"]
        .iter()
        .find_map(|s| lower.strip_suffix(s))
    {
        (n.to_string(), Some("µm"))
    } else {
        (lower.clone(), None)
    };
    let (lo, hi) = crate::geometry::LENGTH_RANGE;
    match num.trim().parse::<f64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok((v, unit)),
        Ok(v) if v.is_finite() && v > 0.0 => Err(Error::Usage(format!(
            "'{t}': a length must lie within [{lo:e}, {hi:e}] (in any unit)"
        ))),
        _ => Err(Error::Usage(format!(
            "'{t}' is not a positive length: give a number with nm or um (633nm, 0.633um) or a bare number in the unit of the data's wavelength"
        ))),
    }
}

/// A wavelength from a channel name such as `550nm`, `550 nm`, `0.55um`, `0.55µm` or a bare
/// number (taken as nm); the result is in nm. `None` when the name is not a wavelength.
pub(crate) fn wavelength_nm_of_channel(name: &str) -> Option<f64> {
    let (v, unit) = parse_length(name).ok()?;
    Some(v * unit.map_or(1.0, nm_per))
}
