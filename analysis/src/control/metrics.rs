//! Response metrics: overshoot, 2 % settling time, IAE, ISE on a sampled signal, and the
//! closed-loop summary (peak force, final drift).

use serde::Serialize;

/// Metrics of a signal y(t) that should go from y0 to `target`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ResponseMetrics {
    /// Largest excursion beyond the target, on the far side from y0, as a fraction of
    /// |y0 − target| (0.1 = 10 %); `None` when y0 = target (no step to overshoot).
    pub overshoot: Option<f64>,
    /// First time after which |y − target| stays within `band`·A, A = max(|y0 − target|,
    /// max |y − target|) [s]; `None` if the last sample is still outside (not settled).
    pub settling_time: Option<f64>,
    /// The band used (fraction of A).
    pub band: f64,
    /// ∫|y − target| dt (trapezoid rule).
    pub iae: f64,
    /// ∫(y − target)² dt (trapezoid rule).
    pub ise: f64,
    /// max |y − target|.
    pub peak_error: f64,
}

/// Metrics of the samples `(t, y)` with respect to `target`, with y0 = y[0] and a settling band
/// of `band` (0.02 for the 2 % settling time).
///
/// The band is relative to the largest deviation, not only to the initial error, so the metric
/// also means something for a response that starts at its target (a maneuver from rest).
/// Settling is judged at the samples: sample finely enough for the dynamics.
pub fn response_metrics(t: &[f64], y: &[f64], target: f64, band: f64) -> ResponseMetrics {
    let n = t.len().min(y.len());
    let err: Vec<f64> = y[..n].iter().map(|v| v - target).collect();
    let e0 = err.first().copied().unwrap_or(0.0);
    let peak_error = err.iter().fold(0.0_f64, |m, e| m.max(e.abs()));
    let overshoot = (e0 != 0.0).then(|| {
        // Past the target means the error has the opposite sign of the initial error.
        let beyond = err.iter().fold(0.0_f64, |m, e| m.max(-e * e0.signum()));
        beyond / e0.abs()
    });
    let amplitude = e0.abs().max(peak_error);
    let tol = band * amplitude;
    let settling_time = match err.iter().rposition(|e| e.abs() > tol) {
        None => t.first().copied(),
        Some(i) if i + 1 < n => Some(t[i + 1]),
        Some(_) => None,
    };
    let (mut iae, mut ise) = (0.0, 0.0);
    for i in 1..n {
        let dt = t[i] - t[i - 1];
        iae += 0.5 * dt * (err[i].abs() + err[i - 1].abs());
        ise += 0.5 * dt * (err[i] * err[i] + err[i - 1] * err[i - 1]);
    }
    ResponseMetrics {
        overshoot,
        settling_time,
        band,
        iae,
        ise,
        peak_error,
    }
}

/// The closed-loop summary of a run.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LoopMetrics {
    /// Metrics of Φ against its rest setpoint.
    pub phi: ResponseMetrics,
    /// max |F| applied [N].
    pub peak_force: f64,
    /// max |F_cmd| before saturation [N].
    pub peak_force_command: f64,
    /// Fraction of samples with a saturated force.
    pub saturated_fraction: f64,
    /// Φ at the end [rad].
    pub final_phi: f64,
    /// Forward velocity at the end [m/s]: the drift a pitch-only loop leaves.
    pub final_v_x: Option<f64>,
    /// Lateral velocity at the end [m/s] (vehicle8 only).
    pub final_v_y: Option<f64>,
    /// Yaw rate at the end [rad/s].
    pub final_w_z: Option<f64>,
    /// Yaw angle at the end [rad].
    pub final_theta: Option<f64>,
    /// Distance between the first and last hinge positions in the plane [m].
    pub drift_distance: Option<f64>,
    /// x displacement (inertial X) from start to end [m].
    pub x_displacement: Option<f64>,
}
