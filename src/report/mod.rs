//! Reporters for a finished fit: one per output format, and what they share (the setting
//! and units of a fit, the input's checksum).

pub(crate) mod batch_html;
pub(crate) mod checksum;
pub(crate) mod design;
pub(crate) mod html;
pub(crate) mod json;
pub(crate) mod outcome;
pub(crate) mod setting;
pub(crate) mod summary;
pub(crate) mod text;

pub use design::{json as design_json, Run as DesignRun};
pub use html::fragment as html_fragment;
pub use json::termination_name;
pub use outcome::{comparison, report as fit_report, setting, to_text, Candidate};
pub use setting::{InputInfo, Setting, Units};

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
