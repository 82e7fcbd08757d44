//! Statistics of a finished fit: the covariance and what the data determines
//! ([`covariance`]), profile-likelihood intervals ([`profile`]) with the quantiles they
//! need ([`quantile`]), whether the fitted surface meets KBS's assumptions ([`validity`]),
//! and whether the model describes the data ([`adequacy`]); statistics read back from a
//! report's JSON ([`json_number`]).

pub mod adequacy;
pub mod covariance;
pub mod json_number;
pub mod profile;
pub mod quantile;
mod restricted;
pub mod validity;
