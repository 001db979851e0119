//! Typed integration errors: what went wrong, when, and from which state.

use std::fmt;

/// Which part of the variational state became non-finite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BlowUpPart {
    /// The state x (the trajectory itself diverged).
    State,
    /// A tangent vector (overflow: re-orthonormalise more often).
    Tangent,
    /// The ∫ tr J quadrature.
    Trace,
}

impl fmt::Display for BlowUpPart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BlowUpPart::State => "state",
            BlowUpPart::Tangent => "tangent vectors",
            BlowUpPart::Trace => "trace quadrature",
        })
    }
}

/// Why an integration could not go on. Every blow-up names the time and the last finite state,
/// so a user can reproduce it from that point.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum IntegrateError {
    /// A step produced NaN or ±∞.
    #[error("integration blew up: the {part} became non-finite in the step of size {h:e} from t = {t} (last finite state x = {x:?})")]
    BlowUp {
        /// Which part became non-finite.
        part: BlowUpPart,
        /// Start time of the failing step.
        t: f64,
        /// Size of the failing step.
        h: f64,
        /// The (finite) state at `t`.
        x: Vec<f64>,
    },
    /// The adaptive step size fell below the resolution of t (or below `h_min`): a finite-time
    /// singularity, a discontinuity, or an impossibly tight tolerance.
    #[error("step size underflow at t = {t}: h = {h:e} (state x = {x:?})")]
    StepSizeUnderflow {
        /// Time at which the step size collapsed.
        t: f64,
        /// The rejected step size.
        h: f64,
        /// The state at `t`.
        x: Vec<f64>,
    },
    /// The adaptive integrator took more steps than its budget: the step size collapsed over a
    /// long stretch (stiffness, a near-singularity) or the horizon is too long for the tolerance.
    #[error("more than {max_steps} integrator steps by t = {t} (h = {h:e}, state x = {x:?}): loosen the tolerances or shorten the run")]
    TooManySteps {
        /// Time reached.
        t: f64,
        /// Last step size tried.
        h: f64,
        /// The budget.
        max_steps: u64,
        /// The state at `t`.
        x: Vec<f64>,
    },
    /// The initial state is not finite.
    #[error("non-finite initial {part} at t = {t}: x = {x:?}")]
    NonFiniteInitial {
        /// Which part is non-finite.
        part: BlowUpPart,
        /// Initial time.
        t: f64,
        /// The initial state.
        x: Vec<f64>,
    },
    /// A fixed step size that is not finite and positive.
    #[error("invalid step size {h}: must be finite and > 0")]
    InvalidStepSize {
        /// The step size given.
        h: f64,
    },
    /// An invalid adaptive-step option (tolerances, step bounds, controller factors).
    #[error("invalid integrator option: {0}")]
    InvalidOption(String),
    /// A stop time that is not finite or lies behind the current time.
    #[error("stop time {t_stop} is not ahead of the current time {t}")]
    StopTimeNotAhead {
        /// Current time.
        t: f64,
        /// Requested stop time.
        t_stop: f64,
    },
    /// Dense output asked for a time outside the last step.
    #[error("dense output at t = {t} outside the last step [{t_start}, {t_end}]")]
    OutsideLastStep {
        /// Requested time.
        t: f64,
        /// Start of the last step.
        t_start: f64,
        /// End of the last step.
        t_end: f64,
    },
}
