//! Control of the pitch: the study's PID on Φ driving the motor force, as a closed-loop vector
//! field with its exact Jacobian, so it runs through the same integrators and Lyapunov code as
//! the open loop; simulations, the study's scenarios, and response metrics.
//!
//! - [`ControllerSettings`]: F = Kp e + Ki ∫e + Kd Φ̇ with e = Φ − Φ_ref (setpoint 0, a
//!   constant, or the study's 0.03·sin Φ), derivative on the measured rate (optionally
//!   filtered), saturation |F| ≤ F_max with anti-windup; optional outer loops on the forward
//!   velocity (it leans Φ_ref) and the yaw rate (T2 or differential wheel torque).
//! - [`Plant`]: which states are measured and which input directions F and T act along, from the
//!   model's names (F1/T2, or τ_L = τ_R = F R/2 for segway7).
//! - [`PidLoop`]: the augmented field on NA = NX + NZ states; `VectorField<NA>`.
//! - [`simulate`], [`run_closed_loop`]: sampled runs, stopping when the vehicle falls over;
//!   [`response_metrics`], [`LoopMetrics`]: overshoot, settling, IAE/ISE, peak force, drift.
//! - [`scenario`]: the study's four gain sets, tilts, the maneuver.
//!
//! ```no_run
//! # use twv_analysis::control::*;
//! # fn demo<M: twv_model::Model<8, 2>>(model: &M) -> Result<(), ControlError> {
//! let settings = ControllerSettings::default(); // the study's PD and setpoint
//! let plant = Plant::<2>::from_info(&model.info(), &|_| None)?;
//! let field = PidLoop::<_, 8, 2, 8>::new(model, &settings, plant)?; // PD: no controller state
//! let x0 = scenario::tilted::<8>(model.info().states, 0.1)?;
//! let run = run_closed_loop(&field, &x0, &RunSettings::default(), &twv_analysis::progress::Silent)?;
//! println!("settled after {:?} s", run.metrics.phi.settling_time);
//! # Ok(()) }
//! ```

mod error;
mod field;
mod loop_states;
mod metrics;
mod plant;
mod record;
mod reference;
pub mod scenario;
mod settings;
mod simulate;
pub mod steer;

pub use error::ControlError;
pub use field::{Command, Layout, LoopLanes, PidLoop};
pub use loop_states::loop_states;
pub use metrics::{response_metrics, LoopMetrics, ResponseMetrics};
pub use plant::{InputMap, Measured, Plant, PITCH_STATES};
pub use record::{loop_metrics, run_closed_loop, ClosedLoopRun};
pub use reference::Profile;
pub use settings::{
    check_tilt, AntiWindup, ControllerSettings, PitchPid, Setpoint, VelocityLoop, YawLoop, STUDY_PD,
};
pub use simulate::{simulate, RunEnd, RunSettings, Trajectory};
