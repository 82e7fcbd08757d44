//! Termination reasons of a run.

/// Which stopping rule ended a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
pub enum Termination {
    /// Relative reduction of the cost (actual and predicted) at most `ftol`, or at machine
    /// precision.
    Ftol,
    /// Relative size of the trust region at most `xtol`, or at machine precision.
    Xtol,
    /// Both `Ftol` and `Xtol` hold.
    FtolXtol,
    /// The Gauss–Newton step from the current point predicts a relative cost reduction of
    /// at most `ftol`, and the linear model predicted the last step well (see
    /// [`super::LevenbergMarquardt::with_predicted_stop`]).
    Predicted,
    /// Residual orthogonal to the columns of the Jacobian to within `gtol` (includes a zero
    /// residual or a zero gradient).
    Gtol,
    /// The iteration budget ran out.
    MaxIterations,
    /// The residual evaluation budget ran out.
    MaxEvaluations,
    /// The wall-clock budget ran out.
    Timeout,
    /// Ctrl-C (SIGINT), SIGTERM or SIGHUP, or the caller's interrupt flag.
    Interrupted,
    /// The residuals at the starting point are not all finite.
    NonFiniteStart,
    /// The Jacobian at an accepted point is not all finite (or not `m × n`); the run stops
    /// there.
    NonFiniteJacobian,
    /// The trust region collapsed without any other criterion holding (e.g. every trial
    /// point has non-finite residuals).
    NoProgress,
    /// Set by the fit, not the solver: the point reached is not a usable optimum — a
    /// parameter ran to an edge of the model's physical domain, or the Jacobian lost rank
    /// without a declared reduction (the report's notes say which, in plain words).
    Degenerate,
}

impl Termination {
    /// Whether the run ended at a (local) minimum according to the tolerances.
    pub fn converged(self) -> bool {
        matches!(
            self,
            Termination::Ftol
                | Termination::Xtol
                | Termination::FtolXtol
                | Termination::Gtol
                | Termination::Predicted
        )
    }

    /// One line for a human.
    pub fn describe(self) -> &'static str {
        match self {
            Termination::Ftol => "converged: relative reduction of the cost below ftol",
            Termination::Xtol => "converged: relative step size below xtol",
            Termination::FtolXtol => {
                "converged: relative cost reduction below ftol and step size below xtol"
            }
            Termination::Gtol => "converged: gradient (residual-column cosine) below gtol",
            Termination::Predicted => {
                "converged: the Gauss–Newton step predicts a relative cost reduction below ftol"
            }
            Termination::MaxIterations => "stopped: maximum number of iterations reached",
            Termination::MaxEvaluations => "stopped: maximum number of evaluations reached",
            Termination::Timeout => "stopped: time limit reached",
            Termination::Interrupted => "stopped: interrupted",
            Termination::NonFiniteStart => "failed: residuals at the starting point are not finite",
            Termination::NonFiniteJacobian => "stopped: Jacobian is not finite",
            Termination::NoProgress => {
                "stopped: no further progress possible (trust region collapsed)"
            }
            Termination::Degenerate => {
                "not converged: degenerate — the fit ran to an edge of the model's domain or the data do not determine it (see the notes)"
            }
        }
    }
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.describe())
    }
}
