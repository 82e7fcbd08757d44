//! The solver's one error: an option or parameter value it cannot use.

use std::fmt;

/// An option or parameter value the solver cannot use: `name` is the option (`ftol`,
/// `max_evals`, ...) or the parameter (`#j`, the 0-based index `j`), `message` says what is
/// wrong with the value and what would be accepted.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Invalid {
    /// The option's name, or `#j` for the parameter of 0-based index `j`.
    pub name: String,
    /// What is wrong with the value, and what would be accepted.
    pub message: String,
}

impl Invalid {
    pub(crate) fn new(name: impl Into<String>, message: String) -> Self {
        Invalid {
            name: name.into(),
            message,
        }
    }
}

impl fmt::Display for Invalid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.name, self.message)
    }
}

impl std::error::Error for Invalid {}
