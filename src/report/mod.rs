//! Reporters for a finished fit: one per output format.

pub mod html;
pub mod json;
pub mod outcome;
pub mod text;

/// How the fit was run, for reproducing it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct RunInfo {
    /// The input file.
    pub input: String,
    /// The full command line.
    pub command: String,
    /// goniofit version.
    pub version: String,
}
