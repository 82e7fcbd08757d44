//! Statistics of a finished fit: the covariance and what the data determines
//! ([`covariance`]), profile-likelihood intervals ([`profile`]) with the quantiles they
//! need ([`quantile`]), whether the fitted surface meets KBS's assumptions ([`validity`]),
//! and whether the model describes the data ([`adequacy`]); statistics read back from a
//! report's JSON ([`json_number`]).

pub(crate) mod adequacy;
pub(crate) mod covariance;
pub(crate) mod json_number;
pub(crate) mod profile;
pub(crate) mod quantile;
mod restricted;
pub(crate) mod validity;
