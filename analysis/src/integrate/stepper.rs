//! The step-by-step driver shared by the integrators.

use super::{IntegrateError, VarState, VectorField};

/// Why [`Stepper::step`] returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// One internal step was taken; the stop time (if any) is still ahead.
    InternalStep,
    /// The step landed exactly on the stop time, which is then cleared.
    StopTimeReached,
}

/// A one-step integrator of the variational system, driven by the caller (diffsol style):
/// set a stop time, call [`step`](Self::step) until it says [`StopReason::StopTimeReached`],
/// inspect or modify the state, repeat.
pub trait Stepper<const N: usize, const K: usize> {
    /// The vector field being integrated.
    type Field: VectorField<N>;

    /// The field.
    fn field(&self) -> &Self::Field;

    /// Current time.
    fn t(&self) -> f64;

    /// Current state, tangents and trace quadrature.
    fn state(&self) -> &VarState<N, K>;

    /// Replaces the tangent vectors (after re-orthonormalisation). The state and time are kept;
    /// cached derivatives of the old tangents are discarded.
    fn set_tangents(&mut self, w: &[[f64; N]; K]);

    /// Makes a later step land exactly on `t_stop` (> current time).
    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), IntegrateError>;

    /// Takes one step.
    fn step(&mut self) -> Result<StopReason, IntegrateError>;

    /// Accepted steps so far.
    fn steps(&self) -> u64;

    /// Whether the ∫ tr J quadrature is integrated (`state().trace_integral` is meaningful).
    fn integrates_trace(&self) -> bool;

    /// Steps until exactly `t_end` (no-op if already there).
    fn advance_to(&mut self, t_end: f64) -> Result<(), IntegrateError> {
        if t_end == self.t() {
            return Ok(());
        }
        self.set_stop_time(t_end)?;
        while self.step()? != StopReason::StopTimeReached {}
        Ok(())
    }
}

/// Checks a stop time against the current time.
pub(crate) fn check_stop(t: f64, t_stop: f64) -> Result<(), IntegrateError> {
    if t_stop.is_finite() && t_stop > t {
        Ok(())
    } else {
        Err(IntegrateError::StopTimeNotAhead { t, t_stop })
    }
}

/// Rejects a non-finite initial state.
pub(crate) fn check_initial<const N: usize, const K: usize>(
    t: f64,
    y: &VarState<N, K>,
) -> Result<(), IntegrateError> {
    match y.non_finite_part() {
        Some(part) => Err(IntegrateError::NonFiniteInitial {
            part,
            t,
            x: y.x.to_vec(),
        }),
        None => Ok(()),
    }
}
