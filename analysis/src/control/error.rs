//! Typed errors of the controller: bad settings, a model the controller cannot drive, and an
//! integration that failed (which names its time and state).

use crate::integrate::IntegrateError;

/// Why a closed-loop run could not be set up or finished.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ControlError {
    /// A setting that is not finite or outside its range.
    #[error("invalid setting {what} = {value:?}: {why}")]
    InvalidSetting {
        /// Which setting.
        what: &'static str,
        /// Its value.
        value: f64,
        /// What it must satisfy.
        why: &'static str,
    },
    /// A reference profile that is not a list of finite (time, value) points with increasing
    /// times.
    #[error("invalid {what} reference profile: {why}")]
    InvalidProfile {
        /// Which loop's reference.
        what: &'static str,
        /// What is wrong.
        why: String,
    },
    /// The model lacks a state the controller measures.
    #[error("model `{model}` has no state `{state}` (states: {states}); the controller measures phi, w_y and, for the outer loops, v_x and w_z")]
    MissingState {
        /// Model name.
        model: String,
        /// The missing state.
        state: &'static str,
        /// The model's states, comma-separated.
        states: String,
    },
    /// The model's inputs are neither (F1[, T2]) nor (tau_L, tau_R).
    #[error("model `{model}` has inputs [{inputs}]: the controller drives F1 (and T2 for yaw) or the wheel torques tau_L, tau_R")]
    UnrecognisedInputs {
        /// Model name.
        model: String,
        /// The model's inputs, comma-separated.
        inputs: String,
    },
    /// A parameter the input map needs (R, c for wheel torques) is missing or not positive.
    #[error("model `{model}`: parameter `{param}` {why} (needed to map the force onto the wheel torques)")]
    MissingParam {
        /// Model name.
        model: String,
        /// Parameter name.
        param: &'static str,
        /// What is wrong with it.
        why: String,
    },
    /// A yaw loop was asked for but the model has no yaw input.
    #[error("model `{model}` has no yaw input (T2, or tau_L and tau_R) for the yaw-rate loop")]
    NoYawInput {
        /// Model name.
        model: String,
    },
    /// The augmented size `NA` given as a const parameter is not NX + (controller states).
    #[error("augmented state size {na} ≠ {nx} model states + {nz} controller states")]
    AugmentedSize {
        /// The const parameter NA.
        na: usize,
        /// Model states.
        nx: usize,
        /// Controller states.
        nz: usize,
    },
    /// An initial state or time span that cannot be run.
    #[error("invalid run: {0}")]
    InvalidRun(String),
    /// The caller cancelled the run.
    #[error("interrupted")]
    Interrupted,
    /// The integration failed (blow-up, step-size underflow …): the message names time and state.
    #[error(transparent)]
    Integrate(#[from] IntegrateError),
}

/// Checks that `value` is finite and satisfies `ok`.
pub(crate) fn check(
    what: &'static str,
    value: f64,
    ok: bool,
    why: &'static str,
) -> Result<(), ControlError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(ControlError::InvalidSetting { what, value, why })
    }
}
