//! The three metrics at one grid point. Each is a pure function of the gains and the fixed
//! sweep config (identity tangent basis, fixed tilt, fixed-step RK4), so a point's result
//! depends only on its index; a point that falls or blows up gets a status, not an error.

use twv_model::Model;

use super::config::MetricSettings;
use super::point::{PointResult, Status};
use crate::control::{run_closed_loop, ControlError, PidLoop, RunEnd, RunSettings};
use crate::linear::{LoopOptions, PidGains, PitchLoop};
use crate::lyapunov::{InitialBasis, IntegratorChoice, LyapunovSettings};

pub use super::lanes::max_lyapunov;

/// The point's record: a non-finite value counts as `Failed`.
pub(super) fn result(
    index: usize,
    g: &PidGains,
    value: Option<f64>,
    status: Status,
) -> PointResult {
    let value = value.filter(|v| v.is_finite());
    let status = if status == Status::Ok && value.is_none() {
        Status::Failed
    } else {
        status
    };
    PointResult {
        index,
        kp: g.kp,
        ki: g.ki,
        kd: g.kd,
        value,
        status,
        settled_at: None,
    }
}

/// Spectral abscissa of the linear pitch loop (no lag, no delay).
pub fn spectral_abscissa(pitch: &PitchLoop, index: usize, g: &PidGains) -> PointResult {
    match pitch.closed_loop(g, &LoopOptions::default()) {
        Ok(cl) => result(index, g, Some(cl.spectral_abscissa), Status::Ok),
        Err(_) => result(index, g, None, Status::Failed),
    }
}

/// The Lyapunov settings for one exponent: T, K, the transient and h from `s`, identity basis,
/// no trace check and no running estimates (neither is looked at, and the trace costs a dense
/// Jacobian per stage).
pub fn lyapunov_settings(s: &MetricSettings) -> LyapunovSettings {
    LyapunovSettings {
        t_sample: s.t_sample,
        iterations: s.iterations,
        transient: s.transient,
        integrator: IntegratorChoice::Rk4 { h: s.h },
        basis: InitialBasis::Identity,
        trace_check: false,
        record_running: false,
        ..LyapunovSettings::preset_paper()
    }
}

/// The 2 % settling time of Φ from the model state `x0`.
pub fn settling_time<M, const NX: usize, const NU: usize, const NA: usize>(
    field: &PidLoop<'_, M, NX, NU, NA>,
    x0: &[f64; NX],
    s: &MetricSettings,
    index: usize,
) -> PointResult
where
    M: Model<NX, NU>,
{
    let g = field.settings().pitch.gains;
    let run = RunSettings {
        t_end: s.t_end,
        sample: s.sample,
        integrator: IntegratorChoice::Rk4 { h: s.h },
        fall_angle: Some(s.fall_angle),
    };
    match run_closed_loop(field, x0, &run, &crate::progress::Silent) {
        Ok(r) => match (r.trajectory.end, r.metrics.phi.settling_time) {
            (RunEnd::Fell { .. }, _) => result(index, &g, None, Status::Fell),
            (RunEnd::Completed, Some(t)) => result(index, &g, Some(t), Status::Ok),
            (RunEnd::Completed, None) => result(index, &g, None, Status::NotSettled),
        },
        Err(ControlError::Integrate(_)) => result(index, &g, None, Status::BlewUp),
        Err(_) => result(index, &g, None, Status::Failed),
    }
}
