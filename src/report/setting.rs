//! What a fit was run on and how: the whole setting a report carries (so a reader, or
//! `goniofit plot`, needs nothing else), and the units of every reported quantity.

use crate::fit::problem::weights::WeightsInfo;
use crate::fit::problem::ResidualKind;
use crate::geometry::Quantity;
use serde::{Deserialize, Serialize};

/// Units of a fit's quantities.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Units {
    /// Unit of λ, σ, T and patch sizes (`nm`, `µm`); None when nothing states it.
    pub length: Option<String>,
    /// The measured quantity.
    pub quantity: Quantity,
    /// Unit of a measured radiance as the file states it; None when it does not.
    pub radiance: Option<String>,
}

impl Units {
    /// The length unit as written in reports (`nm`, or `unit of λ`).
    pub fn length_name(&self) -> String {
        self.length.clone().unwrap_or_else(|| "unit of λ".into())
    }

    /// The unit of the measured value (and of the linear scales): sr⁻¹ for a BRDF, the
    /// file's unit for a radiance (`unit of L` when the file states none).
    pub fn value_name(&self) -> String {
        match self.quantity {
            Quantity::Brdf => "sr⁻¹".into(),
            Quantity::Radiance => self.radiance.clone().unwrap_or_else(|| "unit of L".into()),
        }
    }

    /// The unit of a fit parameter by name (a `[channel]` suffix is ignored): σ, T in the
    /// length unit, scales in the value's unit, the lobe strength B in value·rad, w in rad.
    pub fn of_param(&self, name: &str) -> String {
        match base_name(name) {
            "sigma" | "T" => self.length_name(),
            "scale" | "scale_d" => self.value_name(),
            "B" => format!("{}·rad", self.value_name()),
            "w" => "rad".into(),
            _ => "1".into(),
        }
    }

    /// The unit of a derived quantity by name: T/σ, Beckmann's α and reflectance factors
    /// are pure numbers; the rough amplitude s(T/σ)² has the scale's unit, the smooth one
    /// s·σ² the scale's unit times length².
    pub fn of_derived(&self, name: &str, smooth: bool) -> String {
        match base_name(name) {
            "amplitude" if smooth => format!("{}·{}²", self.value_name(), self.length_name()),
            "amplitude" => self.value_name(),
            _ => "1".into(),
        }
    }
}

pub(crate) use crate::fit::driver::base_name;

/// The input file as fitted.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct InputInfo {
    /// Absolute path (so the report can be used from any directory).
    pub path: String,
    /// SHA-256 of the file's bytes.
    pub sha256: String,
    /// The file's size in bytes.
    pub bytes: u64,
}

/// The wavelength of the fit.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct WavelengthInfo {
    /// The distinct wavelengths of the fitted samples (one for a single-channel fit).
    pub values: Vec<f64>,
    /// Their unit (`nm`, `µm`), or None when nothing states it (σ, T are then in the same
    /// unknown unit).
    pub unit: Option<String>,
    /// `--wavelength`, `channel name`, `wavelength column`, or `none` (models without λ).
    pub source: String,
}

/// The floor of relative and log residuals.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct FloorInfo {
    /// The floor (unit of the measured value).
    pub value: f64,
    /// How many measured values it raised (|L| < floor for relative, L < floor for log).
    pub raised: usize,
    /// Whether the residual kind uses a floor at all.
    pub used: bool,
}

/// The whole setting of a fit.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Setting {
    /// The input file as fitted: absolute path, SHA-256 and size.
    pub input: InputInfo,
    /// The distinct wavelengths of the samples, their unit and where they came from.
    pub wavelength: WavelengthInfo,
    /// `--channel` as given (None when not given).
    pub channel: Option<String>,
    /// What the values are: a BRDF (sr⁻¹) or a radiance.
    pub quantity: Quantity,
    /// `--quantity`, `file (MEAS_NAME BRDF)`, `file (NIST f_r11)` or `default`.
    pub quantity_source: String,
    /// The residual kind the fit minimised: absolute, relative or log.
    pub residual: ResidualKind,
    /// The floor of relative and log residuals and how many values it raised.
    pub floor: FloorInfo,
    /// Where the weights came from and how they were transformed for the residual.
    pub weights: WeightsInfo,
    /// The robust loss (`linear` = plain least squares; scipy's names).
    pub loss: String,
    /// Its scale C (`--f-scale`), in the unit of the weighted residual; None for linear.
    pub f_scale: Option<f64>,
    /// Standard errors and intervals from the stated uncertainties as they are (scipy's
    /// `absolute_sigma=True`), not rescaled by the residual scatter.
    pub absolute_sigma: bool,
    /// The units of the reported quantities (length, measured value).
    pub units: Units,
}

impl Default for Setting {
    fn default() -> Self {
        Setting {
            input: InputInfo::default(),
            wavelength: WavelengthInfo::default(),
            channel: None,
            quantity: Quantity::Radiance,
            quantity_source: "default".into(),
            residual: ResidualKind::Absolute,
            floor: FloorInfo::default(),
            weights: WeightsInfo {
                source: "none".into(),
                transform: "1 for every sample".into(),
            },
            loss: "linear".into(),
            f_scale: None,
            absolute_sigma: false,
            units: Units::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_follow_the_quantity_and_the_length_unit() {
        let u = Units {
            length: Some("nm".into()),
            quantity: Quantity::Brdf,
            radiance: None,
        };
        assert_eq!(u.of_param("sigma"), "nm");
        assert_eq!(u.of_param("scale_d[550nm]"), "sr⁻¹");
        assert_eq!(u.of_param("B"), "sr⁻¹·rad");
        assert_eq!(u.of_derived("amplitude[550nm]", true), "sr⁻¹·nm²");
        let r = Units::default();
        assert_eq!(r.of_param("T"), "unit of λ");
        assert_eq!(r.of_param("scale"), "unit of L");
    }
}
