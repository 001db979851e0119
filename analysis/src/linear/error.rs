//! Bad input to the linear-analysis routines. How an algorithm *ended* (solved, no stabilising
//! solution, iteration limit) is a status in the result, not an error: errors are reserved for
//! input the caller must fix.

/// Input the linear-analysis routines cannot work with.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinearError {
    /// A NaN or infinity where a finite number is required.
    #[error("{what} is not finite")]
    NonFinite {
        /// Which input.
        what: &'static str,
    },
    /// A quantity that must be non-negative (a time constant, a delay) is negative.
    #[error("{what} must be >= 0, got {value}")]
    Negative {
        /// Which input.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// Matrix or vector sizes do not fit together.
    #[error("{what}: expected size {expected}, got {got}")]
    Dimension {
        /// Which input.
        what: &'static str,
        /// The size the other inputs imply.
        expected: usize,
        /// The size given.
        got: usize,
    },
    /// A state name the model does not have.
    #[error("the model has no state named {0:?}")]
    UnknownState(String),
    /// The PID law uses `w_y` as Φ̇; that is only true if the model's Φ row is Φ̇ = w_y.
    #[error(
        "state {phi} is not the integral of state {rate} (need Φ̇ = w_y with no direct input), \
         so Kd·w_y is not Kd·Φ̇"
    )]
    NotPitchStructure {
        /// Index of Φ.
        phi: usize,
        /// Index of w_y.
        rate: usize,
    },
    /// The input direction gives no input at all.
    #[error("the input direction b_dir is zero or does not reach the model")]
    ZeroInput,
    /// A reduced subsystem would drop states that still drive the kept ones.
    #[error("dropped state {dropped:?} drives kept state {kept:?} (A entry {value})")]
    Coupled {
        /// A kept state.
        kept: String,
        /// The dropped state that drives it.
        dropped: String,
        /// The coupling entry of A.
        value: f64,
    },
    /// A weight matrix is not symmetric positive (semi-)definite as the method needs.
    #[error("{what} must be symmetric positive {kind}")]
    Weight {
        /// Which weight.
        what: &'static str,
        /// "definite" or "semidefinite".
        kind: &'static str,
    },
    /// A physical parameter that must be positive is not.
    #[error("parameter {what} must be > 0, got {value}")]
    NonPositive {
        /// Which parameter.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The QR eigenvalue iteration did not converge (only for pathological matrices).
    #[error("the eigenvalue iteration did not converge")]
    Eigen,
}

/// Checks that every entry is finite.
pub(crate) fn check_finite<'a>(
    what: &'static str,
    values: impl IntoIterator<Item = &'a f64>,
) -> Result<(), LinearError> {
    if values.into_iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(LinearError::NonFinite { what })
    }
}
