//! What defines a sweep — model, parameters, metric and its settings, grid, initial state,
//! controller — and the hash that tells whether two shards belong to the same sweep.

use serde::{Deserialize, Serialize};

use super::error::SweepError;
use super::grid::Grid;

/// The quantity mapped over the grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Metric {
    /// Largest Lyapunov exponent of the nonlinear closed loop's pitch-loop states (the drift
    /// directions projected off), from the tilt, after a transient, study sampling
    MaxLyapunov,
    /// Largest real part of the linear pitch loop's poles at the upright
    SpectralAbscissa,
    /// 2 % settling time of Φ after the tilt
    SettlingTime,
}

impl Metric {
    /// Name and unit for tables and figures.
    pub fn label(&self) -> &'static str {
        match self {
            Metric::MaxLyapunov => "largest Lyapunov exponent of the pitch loop λ1 [1/s]",
            Metric::SpectralAbscissa => "spectral abscissa max Re s [1/s]",
            Metric::SettlingTime => "2 % settling time of Φ [s]",
        }
    }
}

/// The fixed numerical settings of the nonlinear metrics (the study's preset), recorded so a
/// shard computed by another build with other defaults is not mixed in. Fields left out of a
/// JSON request take their defaults.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MetricSettings {
    /// RK4 step [s].
    pub h: f64,
    /// Lyapunov re-orthonormalisation interval T [s].
    pub t_sample: f64,
    /// Lyapunov iterations K (averaged after the transient).
    pub iterations: usize,
    /// Lyapunov transient [s]: the tangent aligns with the slowest loop mode before averaging
    /// starts, so a stable loop's λ1 is its slowest decay rate rather than a mix with the
    /// initial basis.
    pub transient: f64,
    /// Settling-time run length [s].
    pub t_end: f64,
    /// Settling-time sample interval [s].
    pub sample: f64,
    /// |Φ| beyond which the vehicle has fallen [rad].
    pub fall_angle: f64,
    /// The max-Lyapunov metric's settled-tail shortcut: once the loop is at rest — its
    /// pitch-loop state has at most this distance [state units] left to go at the rate its
    /// tangent decays — the rest of the horizon is computed from the linearisation there in one
    /// go (`sweep::settle`; λ1 moves by at most [`SETTLED_TAIL_TOLERANCE`](super::SETTLED_TAIL_TOLERANCE)).
    /// `None` (JSON `null`, `twv sweep --full-horizon`) steps every point to the end.
    pub settle_distance: Option<f64>,
}

/// The settled-tail shortcut's default distance (README, Stability maps: the 100 × 100 map's
/// largest change of λ1 with it).
fn default_settle_distance() -> Option<f64> {
    Some(3e-3)
}

impl MetricSettings {
    /// Checks what a point cannot report as its status (the rest ends a point's run as
    /// `blew_up` or `failed`, like any other run that cannot go on).
    pub fn validate(&self) -> Result<(), SweepError> {
        let positive: [(&'static str, f64); 5] = [
            ("h", self.h),
            ("t_sample", self.t_sample),
            ("t_end", self.t_end),
            ("sample", self.sample),
            ("fall_angle", self.fall_angle),
        ];
        for (field, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(SweepError::Setting {
                    field,
                    reason: format!("{v} must be finite and > 0"),
                });
            }
        }
        if !(self.transient.is_finite() && self.transient >= 0.0) {
            return Err(SweepError::Setting {
                field: "transient",
                reason: format!("{} must be finite and ≥ 0", self.transient),
            });
        }
        if self.iterations == 0 {
            return Err(SweepError::Setting {
                field: "iterations",
                reason: "must be at least 1".into(),
            });
        }
        if self.sample > self.t_end || self.h > self.t_sample {
            return Err(SweepError::Setting {
                field: if self.h > self.t_sample {
                    "h"
                } else {
                    "sample"
                },
                reason: format!(
                    "h = {} must be ≤ t_sample = {}, and sample = {} ≤ t_end = {}",
                    self.h, self.t_sample, self.sample, self.t_end
                ),
            });
        }
        match self.settle_distance {
            Some(d) if !(d.is_finite() && d > 0.0) => Err(SweepError::Setting {
                field: "settle_distance",
                reason: format!("{d} must be a finite distance > 0 (null turns the shortcut off)"),
            }),
            _ => Ok(()),
        }
    }
}

impl Default for MetricSettings {
    /// The study's sampling (h = 1 ms, T = 0.1 s, K = 100) after a 1 s transient; 10 s runs
    /// sampled every 10 ms; π/2; the settled tail from 3·10⁻³.
    fn default() -> Self {
        Self {
            h: 1e-3,
            t_sample: 0.1,
            iterations: 100,
            transient: 1.0,
            t_end: 10.0,
            sample: 0.01,
            fall_angle: std::f64::consts::FRAC_PI_2,
            settle_distance: default_settle_distance(),
        }
    }
}

/// Everything a point's result depends on besides its index.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SweepConfig {
    /// Model name.
    pub model: String,
    /// Where the model came from (`shipped` or the IR file).
    pub source: String,
    /// Parameter values in the model's order.
    pub params: Vec<f64>,
    pub metric: Metric,
    pub grid: Grid,
    /// Initial model state of the nonlinear metrics (the tilt).
    pub x0: Vec<f64>,
    /// The controller apart from the swept gains (as `twv sim` reports it).
    pub controller: serde_json::Value,
    pub settings: MetricSettings,
}

impl SweepConfig {
    /// FNV-1a (64 bit) of the canonical JSON, as 16 hex digits: stable across builds and
    /// machines (serde_json prints floats exactly), no extra dependency.
    pub fn hash(&self) -> String {
        let json = serde_json::to_string(self).expect("a sweep config serialises");
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        for b in json.bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
        format!("{h:016x}")
    }
}
