//! The study's experiments as data: its four phase-portrait gain sets, tilt disturbances, and
//! the maneuver reference.

use serde::Serialize;

use super::error::ControlError;
use super::reference::Profile;
use super::settings::STUDY_PD;
use crate::linear::PidGains;

/// A labelled gain set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GainSet {
    /// Short label for figures.
    pub label: &'static str,
    /// What it shows.
    pub note: &'static str,
    /// The gains.
    pub gains: PidGains,
}

/// Four gain sets that retrace the study's Fig. 4 a–d progression: it started from a PID whose
/// phase portrait was "chaotic", reduced the integral gain (better, still not stable), set it to
/// zero (an apparent fixed point "with a downward extension of the line"), then tuned Kp and Kd
/// to the PD (3860, 0, 1980). The study's first three gains are not in its text, so these are
/// chosen to show each regime on the paper vehicle (M_x g ≈ 1207 N/rad, Routh–Hurwitz limit
/// Ki < m_p l Kd (Kp − M_x g)/Δ ≈ 6.1·10⁴ at Kp = 3860, Kd = 1980):
///
/// - (a) Ki = 1.2·10⁵ above the Routh–Hurwitz limit: a growing oscillation (unstable);
/// - (b) Ki = 3·10⁴ below it: stable but slow and oscillatory;
/// - (c) PD with Kp = 1000 < M_x g: a saddle — the trajectory first heads for the origin along
///   the stable direction, then runs away along a straight line (the "extension of the line");
/// - (d) the study's PD: both poles real and negative, a node at the origin.
pub const STUDY_GAIN_SETS: [GainSet; 4] = [
    GainSet {
        label: "(a) Kp 3860, Ki 1.2e5, Kd 1980",
        note: "integral gain above the Routh-Hurwitz limit: growing oscillation",
        gains: PidGains {
            kp: 3860.0,
            ki: 1.2e5,
            kd: 1980.0,
        },
    },
    GainSet {
        label: "(b) Kp 3860, Ki 3e4, Kd 1980",
        note: "integral gain reduced below the limit: stable, slow oscillation",
        gains: PidGains {
            kp: 3860.0,
            ki: 3.0e4,
            kd: 1980.0,
        },
    },
    GainSet {
        label: "(c) Kp 1000, Ki 0, Kd 300",
        note: "PD with Kp below M_x g: a saddle, the trajectory leaves along a line",
        gains: PidGains {
            kp: 1000.0,
            ki: 0.0,
            kd: 300.0,
        },
    },
    GainSet {
        label: "(d) Kp 3860, Ki 0, Kd 1980 (study PD)",
        note: "the study's PD: a stable node",
        gains: STUDY_PD,
    },
];

/// Direction of a tilt disturbance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Tilt {
    /// Φ0 > 0: the study's Fig. 5 (the vehicle accelerates).
    Forward,
    /// Φ0 < 0: the study's Fig. 6 (the vehicle decelerates).
    Backward,
}

impl Tilt {
    /// The signed initial pitch for a tilt of `magnitude` rad.
    pub fn phi0(self, magnitude: f64) -> f64 {
        match self {
            Tilt::Forward => magnitude.abs(),
            Tilt::Backward => -magnitude.abs(),
        }
    }
}

/// A state of `states` (by name) at rest with only Φ set: the initial condition of a tilt
/// disturbance.
pub fn tilted<const NX: usize>(states: &[&str], phi0: f64) -> Result<[f64; NX], ControlError> {
    let i = states
        .iter()
        .position(|s| *s == "phi")
        .ok_or_else(|| ControlError::MissingState {
            model: String::new(),
            state: "phi",
            states: states.join(", "),
        })?;
    let mut x = [0.0; NX];
    x[i] = phi0;
    Ok(x)
}

/// The maneuver of `twv sim --scenario maneuver`: at rest for 1 s, accelerate to `v_cruise`
/// over `t_ramp`, cruise for `t_cruise`, decelerate over `t_ramp`, stop.
pub fn maneuver(v_cruise: f64, t_ramp: f64, t_cruise: f64) -> Result<Profile, ControlError> {
    Profile::trapezoid(1.0, t_ramp, t_cruise, v_cruise)
}
