//! A stepper wrapper that stops integrating once the vehicle has fallen over, so a Lyapunov
//! run from a point that falls costs only the time to the fall instead of the full horizon.

use std::cell::Cell;

use crate::integrate::{IntegrateError, Stepper, StopReason, VarState};

/// Wraps a stepper; after |x[phi]| first exceeds `limit` every step is a no-op that reports the
/// stop time as reached (the Benettin driver then runs through its remaining intervals without
/// integrating) and `fell` is set, so the caller discards the (meaningless) estimate.
pub struct FallStop<'c, S> {
    pub inner: S,
    pub phi: usize,
    pub limit: f64,
    pub fell: &'c Cell<bool>,
}

impl<S: Stepper<N, K>, const N: usize, const K: usize> Stepper<N, K> for FallStop<'_, S> {
    type Field = S::Field;

    fn field(&self) -> &Self::Field {
        self.inner.field()
    }

    fn t(&self) -> f64 {
        self.inner.t()
    }

    fn state(&self) -> &VarState<N, K> {
        self.inner.state()
    }

    fn set_tangents(&mut self, w: &[[f64; N]; K]) {
        self.inner.set_tangents(w)
    }

    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), IntegrateError> {
        self.inner.set_stop_time(t_stop)
    }

    fn step(&mut self) -> Result<StopReason, IntegrateError> {
        if self.fell.get() {
            return Ok(StopReason::StopTimeReached);
        }
        let reason = self.inner.step()?;
        if self.inner.state().x[self.phi].abs() > self.limit {
            self.fell.set(true);
            return Ok(StopReason::StopTimeReached);
        }
        Ok(reason)
    }

    fn steps(&self) -> u64 {
        self.inner.steps()
    }

    fn integrates_trace(&self) -> bool {
        self.inner.integrates_trace()
    }
}
