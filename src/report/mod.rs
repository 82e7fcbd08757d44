//! Reporters for a finished fit: one per output format, and what they share (the setting
//! and units of a fit, the input's checksum).

pub mod batch_html;
pub mod checksum;
pub mod design;
pub mod html;
pub mod json;
pub mod outcome;
pub mod setting;
pub mod summary;
pub mod text;

pub use setting::{Setting, Units};

/// How the fit was run, for reproducing it.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct RunInfo {
    /// The input file (as named on the command line, with a `[group]` for a group).
    pub input: String,
    /// The full command line.
    pub command: String,
    /// goniofit version.
    pub version: String,
    /// The fit's setting: input path and checksum, wavelength and units, quantity,
    /// residual, floor, weights, loss.
    pub setting: Setting,
    /// Profile-likelihood intervals of the parameters and derived quantities (empty when
    /// not computed).
    #[serde(skip)]
    pub intervals: Vec<crate::fit::stats::profile::Interval>,
    /// Wall-clock seconds the intervals took (0 when not computed).
    pub interval_seconds: f64,
}
