//! Fitting a model to a dataset with the Levenberg–Marquardt solver of [`goniofit_lm`].
//!
//! [`driver::fit`] runs one fit as a pipeline of stages, one file each:
//! 1. prepare (`prepare.rs`): the parameter layout from the model, the data and the user's
//!    fixed and starting values, and the refusal of data that cannot be fitted;
//! 2. start (`start/`): the starting-value grid with its linear amplitudes, refined on a
//!    subsample, and the choice of where the full fit begins;
//! 3. solve (`solve.rs`): Levenberg–Marquardt on the whole data from that point;
//! 4. identify (`identify.rs`): the covariance and what the data determines;
//! 5. reduce (`reduce.rs`): the refit of a regime's determined combinations;
//! 6. accept (`accept.rs`): whether the point reached is a usable optimum;
//! 7. assemble (`assemble.rs`): the [`driver::FitResult`] the reports show.
//!
//! What the stages share: the request (`config.rs`), the least-squares problem with its
//! layout, channels, weights, losses, bounds and edges ([`problem`]), the statistics of a
//! finished fit — covariance, profile intervals, validity, adequacy ([`stats`]) — and the
//! result types (`result.rs`). A dataset's fit with model selection, shared by the CLI and
//! the Python package, is [`dataset`].
//!
//! Imports run one way: [`problem`] uses nothing else of `fit`; [`stats`] uses
//! [`problem`]; [`start`] uses both and the solve stage; the stages use all three;
//! [`dataset`] uses the stages through [`driver`].

pub(crate) mod dataset;
pub(crate) mod driver;
pub(crate) mod problem;
pub(crate) mod start;
pub(crate) mod stats;

mod accept;
mod assemble;
mod config;
mod identify;
mod prepare;
mod reduce;
mod result;
mod solve;
