//! Integrators for the variational system ẋ = F(t, x), Ẇ = J(t, x) W.
//!
//! The Lyapunov spectrum, closed-loop simulation and stability maps all integrate a state `x`
//! together with `K` tangent vectors `W = [w_0, …, w_{K−1}]` (stored as `[[f64; N]; K]`, one row
//! per vector), with the Jacobian re-evaluated at every stage. This module provides:
//!
//! - [`VectorField`]: the seam between "what is integrated" and "how". An open-loop model
//!   ([`OpenLoop`]), a model under a static feedback law ([`ClosedLoop`] with a [`FeedbackLaw`],
//!   e.g. [`LinearStateFeedback`]), or later a model plus a dynamic controller (an augmented
//!   state; see [`field`] for the recipe) are integrated by the same code.
//! - [`Rk4`]: the classical fixed-step Runge–Kutta method (the study's setting).
//! - [`Dopri5`]: the adaptive Dormand–Prince 5(4) pair with its standard continuous extension
//!   (dense output), optionally with the tangent vectors in the error control.
//! - [`Stepper`]: the step-by-step driver both implement: the caller sets a stop time and calls
//!   `step()`, which reports why it returned ([`StopReason`]).
//!
//! Both steppers can also integrate the quadrature ∫ tr(∂F/∂x) dt with the same stages (the
//! `trace_integral` component of [`VarState`]), so that the identity Σλ = ⟨tr J⟩ can be checked
//! against exactly the trajectory the exponents came from.
//!
//! Nothing in a step allocates: every buffer is a fixed-size array inside the stepper.

mod closed_loop;
mod dopri5;
mod error;
pub mod field;
mod lane_states;
mod linear_feedback;
mod open_loop;
mod projected;
mod rk4;
mod state;
mod stepper;

pub use closed_loop::{ClosedLoop, FeedbackLaw};
pub use dopri5::{Dopri5, DopriOptions};
pub use error::{BlowUpPart, IntegrateError};
pub use field::VectorField;
pub use lane_states::LaneStates;
pub(crate) use lane_states::{one_row, rk4_step_lanes, LaneField, LaneRk4Scratch};
pub use linear_feedback::LinearStateFeedback;
pub use open_loop::OpenLoop;
pub use projected::{project, Projected};
pub(crate) use rk4::equal_steps;
pub use rk4::Rk4;
pub(crate) use state::eval_stage;
pub use state::VarState;
pub use stepper::{Stepper, StopReason};

/// The most integrator steps one run may take (fixed steps are refused up front by the settings
/// that ask for more, adaptive ones stop with [`IntegrateError::TooManySteps`]): minutes
/// (about ten for a vehicle's full variational system), so no input can make a run hang.
pub const MAX_STEPS: u64 = 1_000_000_000;
