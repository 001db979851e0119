//! The typed API: one function per job, each from a resolved model and settings (defaults
//! beside each field, `validate()`) to a serde-serialisable result with its verdict. The CLI,
//! the report, the Python package and the live page all call these; nothing here parses
//! arguments or writes files (see [`crate::output`] for that shared step).
//!
//! | job | settings | function | result |
//! |---|---|---|---|
//! | eval | [`EvalSettings`] | [`evaluate`] | [`EvalResult`] |
//! | codegen | [`CodegenSettings`] | [`generate`] | the source |
//! | audit | [`crate::audit::AuditSettings`] | [`audit_model`] | [`crate::audit::AuditReport`] |
//! | lyap | [`SpectrumSettings`] | [`spectrum()`] | [`SpectrumResult`] |
//! | sim, disturb | [`SimSettings`] | [`simulate()`] | [`SimResult`] |
//! | ride | [`RideSettings`] | [`ride()`] | [`RideResult`] |
//! | phase | [`PhaseSettings`] | [`portraits`] | [`PhaseResult`] |
//! | linear | [`LinearSettings`] | [`analyse`] | [`LinearReport`] |
//! | tune | [`TuneSettings`] | [`tune_model`] | [`TuneReport`] |
//! | sweep | [`SweepSettings`] | [`sweep()`], [`run_shard`] | points, [`ShardOutcome`] |
//! | uncertainty | [`UncertaintySettings`] | [`uncertainty()`], [`merge_uncertainty`] | [`UncertaintyResult`] |
//!
//! [`json`] runs any of them with settings and result as JSON (the Python package, the page).

mod audit;
mod codegen;
mod eval;
pub mod json;
mod linear;
mod loop_figures;
mod phase;
mod ride;
mod simulate;
mod spectrum;
mod steady;
mod steer;
mod steer_map;
mod sweep;
mod tune;
mod uncertainty;

pub use crate::progress::{CancelFlag, Progress, Silent};
pub use audit::{
    audit_hand, audit_model, HandAuditJob, HandSource, AUDITED, MAX_HAND_FILE_BYTES, MAX_SAMPLES,
};
pub use codegen::{camel, generate, CodegenSettings};
pub use eval::{evaluate, evaluate_batch, Batch, EvalResult, EvalSettings, Quantity};
pub use linear::{
    analyse, complex, equilibrium_tolerance, pitch_loop, At, LinearReport, LinearSettings,
    LoopVerdict, PhaseMargin, PitchReport, StableMargins, SteerReport, FIGURE_FREQUENCY_POINTS,
    LQR_STATES, MAX_FREQUENCY_POINTS,
};
pub use loop_figures::{bode, nyquist, NYQUIST_CLIP};
pub use phase::{portraits, Drive, PhaseResult, PhaseRun, PhaseSettings, Portrait, DEFAULT_TILTS};
pub use ride::{ride, ride_verdict, RideResult, RideSettings, RideVerdict, RIDE_DECAY, RIDE_TAIL};
pub use simulate::{
    recovery_of, simulate, InputDirections, Maneuver, Recovery, SimResult, SimSettings,
    MANEUVER_V_LOOP, RECOVERED_PHI,
};
pub use spectrum::{drift_states, spectrum, SpectrumResult, SpectrumSettings, Timing};
pub use steady::{
    check_speed, modal_plant, steady_motion, steady_state, Crossing, ModalPlant, SpeedPoint,
    StableRange, SteadyResult, SteadySettings, SteadyVerdict, MAX_SPEEDS,
};
pub use steer::{
    steer, steer_input, steer_loop, SteerLoopSettings, SteerPoint, SteerResult, SteerVerdict,
    SteeredRide,
};
pub use steer_map::{
    steer_map, StabilisingRange, SteerMapResult, SteerMapSettings, SteerMapVerdict,
};
pub use sweep::{
    compute_points, run_shard, status_counts, sweep, Computed, ShardOptions, ShardOutcome,
    SweepSettings, MAX_POINTS,
};
pub use tune::{
    tilt_check, tune_model, tune_model_with, TiltCheck, TuneReport, TuneSettings, TuneVerdict,
};
pub use uncertainty::{
    draw, merge as merge_uncertainty, merge_dir as merge_uncertainty_dir,
    shard_files as uncertainty_shard_files, uncertainty, Evaluation, Sample, SampleStatus, Spread,
    UncertaintyResult, UncertaintySettings, UncertaintyVerdict, Varied, MAX_DRAWS,
};
