//! What the controller is: the PID pitch loop and the optional outer loops, with defaults beside
//! each field and a `validate()` that runs before any work.

use serde::{Deserialize, Serialize, Serializer};

use super::error::{check, ControlError};
use super::reference::Profile;
use crate::linear::PidGains;

/// The pitch setpoint Φ_ref of the inner loop (before the velocity loop adds its lean).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Setpoint {
    /// Φ_ref = 0: upright.
    Zero,
    /// Φ_ref = c [rad]: a constant lean (the vehicle then accelerates for ever; for a cruise
    /// use the velocity loop).
    Constant {
        /// The lean [rad].
        value: f64,
    },
    /// Φ_ref = A·sin Φ: the study's state-dependent "expectation" 0.03·sin Φ (A = 0.03). It
    /// feeds back part of Φ itself, so it scales the effective proportional gain by
    /// (1 − A cos Φ), and its derivative enters the closed-loop Jacobian.
    Sine {
        /// The amplitude A.
        amplitude: f64,
    },
}

impl Setpoint {
    /// The study's 0.03·sin Φ.
    pub const STUDY: Setpoint = Setpoint::Sine { amplitude: 0.03 };

    /// Φ_ref(Φ) and dΦ_ref/dΦ.
    #[inline(always)]
    pub fn eval(&self, phi: f64) -> (f64, f64) {
        // Inline, as in the generated kernels (a C library call here cost 7 % of a sweep).
        self.eval_with(|| twv_kernels::trig::sin_cos(phi))
    }

    /// [`eval`](Self::eval) with (sin Φ, cos Φ) from `sin_cos`, called only by the sine (the
    /// maps compute eight at once).
    #[inline(always)]
    pub fn eval_with(&self, sin_cos: impl FnOnce() -> (f64, f64)) -> (f64, f64) {
        match *self {
            Setpoint::Zero => (0.0, 0.0),
            Setpoint::Constant { value } => (value, 0.0),
            Setpoint::Sine { amplitude } => {
                let (s, c) = sin_cos();
                (amplitude * s, amplitude * c)
            }
        }
    }

    /// A setpoint from its text (`study`, `zero`, `sine:A`, an angle in rad), a number (an
    /// angle) or its JSON object (`{"kind": "sine", "amplitude": 0.03}`).
    pub fn from_value(v: &serde_json::Value) -> Result<Self, crate::Error> {
        let bad = |what: String| {
            crate::Error::input(
                "setpoint",
                format!("{what}: use study, zero, sine:A or an angle in rad"),
            )
        };
        match v {
            serde_json::Value::String(text) => text.parse().map_err(|_| bad(format!("`{text}`"))),
            serde_json::Value::Number(n) => Ok(Setpoint::Constant {
                value: n.as_f64().ok_or_else(|| bad(n.to_string()))?,
            }),
            other => serde_json::from_value(other.clone()).map_err(|e| bad(e.to_string())),
        }
    }

    /// The angle the loop regulates Φ to at rest (0 unless a constant lean is asked for).
    pub fn rest_value(&self) -> f64 {
        match *self {
            Setpoint::Constant { value } => value,
            _ => 0.0,
        }
    }
}

impl std::str::FromStr for Setpoint {
    type Err = ();

    /// `study` (0.03·sin Φ), `zero`, `sine:A` or a constant angle in rad.
    fn from_str(text: &str) -> Result<Self, ()> {
        let t = text.trim();
        Ok(match t {
            "study" => Setpoint::STUDY,
            "zero" | "0" => Setpoint::Zero,
            _ => match t.strip_prefix("sine:") {
                Some(a) => Setpoint::Sine {
                    amplitude: a.trim().parse().map_err(|_| ())?,
                },
                None => Setpoint::Constant {
                    value: t.parse().map_err(|_| ())?,
                },
            },
        })
    }
}

impl std::fmt::Display for Setpoint {
    /// The text [`FromStr`](std::str::FromStr) reads back.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            s if s == Setpoint::STUDY => f.write_str("study"),
            Setpoint::Zero => f.write_str("zero"),
            Setpoint::Sine { amplitude } => write!(f, "sine:{amplitude}"),
            Setpoint::Constant { value } => write!(f, "{value}"),
        }
    }
}

/// How the integral state is kept from winding up while the force saturates.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum AntiWindup {
    /// None: the integral runs on while saturated.
    None,
    /// Conditional integration (clamping): the integral stops while the force is saturated and
    /// the error would drive it further into saturation. Default.
    #[default]
    Conditional,
    /// Back-calculation: ż_I = e + (F − F_cmd)/(Ki T_t); the integral is pulled back towards
    /// the value that would just reach the limit, with time constant T_t [s].
    BackCalculation {
        /// Tracking time T_t [s] (> 0; a common choice is √(Ti·Td) or Td).
        tracking_time: f64,
    },
}

impl AntiWindup {
    /// Back-calculation with its default tracking time, 0.3 s.
    pub const fn back_calculation() -> Self {
        AntiWindup::BackCalculation { tracking_time: 0.3 }
    }
}

/// The inner loop: F = Kp e + Ki ∫e + Kd Φ̇_f with e = Φ − Φ_ref, saturated to |F| ≤ F_max.
///
/// Derivative on the measurement: the rate term uses the measured pitch rate w_y = Φ̇ (a gyro),
/// never a differentiated error, so setpoint changes cause no derivative kick and no numerical
/// differentiation is needed. With a filter the rate term is Kd·d, ḋ = (w_y − d)/τ_f, a state.
///
/// Sign (docs/src/conventions.md): Φ > 0 is a forward lean and F1 > 0 pushes the base forward, so the base
/// must push *towards* the lean: F = +Kp Φ + Kd Φ̇ stabilises the upright iff Kd > 0 and
/// Kp > M_x g (Routh–Hurwitz, [`crate::linear::CartPendulum::routh_hurwitz_stable`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PitchPid {
    /// Gains (N/rad, N/(rad s), N s/rad). Default the study's PD (3860, 0, 1980).
    #[serde(serialize_with = "ser_gains")]
    pub gains: PidGains,
    /// Setpoint. Default the study's 0.03·sin Φ.
    pub setpoint: Setpoint,
    /// Time constant τ_f [s] of a first-order filter on the measured rate; `None` (default):
    /// no filter.
    pub derivative_filter: Option<f64>,
    /// Force limit F_max [N]: |F| ≤ F_max; `None` (default): unlimited.
    pub saturation: Option<f64>,
    /// Anti-windup when saturated (only matters with Ki ≠ 0 and a limit). Default conditional.
    pub anti_windup: AntiWindup,
}

/// The study's PD gains: Kp = 3860 N/rad, Kd = 1980 N s/rad.
pub const STUDY_PD: PidGains = PidGains {
    kp: 3860.0,
    ki: 0.0,
    kd: 1980.0,
};

impl Default for PitchPid {
    fn default() -> Self {
        Self {
            gains: STUDY_PD,
            setpoint: Setpoint::STUDY,
            derivative_filter: None,
            saturation: None,
            anti_windup: AntiWindup::default(),
        }
    }
}

/// Outer loop on the forward velocity: it leans the pitch setpoint,
/// Φ_ref += kp (v_ref − v_x) + ki ∫(v_ref − v_x) dt.
///
/// A forward lean is what accelerates the vehicle forward (the inner loop has to push the base
/// under a leaning pendulum), so the lean grows with the velocity shortfall: kp, ki ≥ 0. In
/// terms of the force this is F ∋ +Kp·kp·v_x, the "positive" velocity feedback every
/// cart–pendulum regulator has; the linearised loop needs 0 < Kp·kp < m_p l Kd / I_p.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VelocityLoop {
    /// Proportional gain [rad per m/s].
    pub kp: f64,
    /// Integral gain [rad per m]; 0: no integral state.
    pub ki: f64,
    /// Forward-velocity reference v_ref(t) [m/s]. Default 0.
    #[serde(default = "Profile::zero")]
    pub reference: Profile,
    /// Largest lean the loop may ask for, |kp·e_v + ki·∫e_v| ≤ lean_max [rad]; its integral
    /// stops while the limit holds and the error pushes further (conditional anti-windup).
    /// Without it a large velocity step asks for a lean whose recovery force saturates the
    /// motor and the vehicle falls.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lean_max: Option<f64>,
}

/// Outer loop on the yaw rate: T = kp (r_ref − w_z), on T2 (or as differential wheel torque).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct YawLoop {
    /// Proportional gain [N m per rad/s] (> 0).
    pub kp: f64,
    /// Yaw-rate reference r_ref(t) [rad/s]. Default 0.
    #[serde(default = "Profile::zero")]
    pub reference: Profile,
}

/// The whole controller. Default: the study's PD with its 0.03·sin Φ setpoint, no outer loops.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ControllerSettings {
    /// The pitch loop.
    pub pitch: PitchPid,
    /// Optional forward-velocity loop (drift regulation, maneuvers).
    pub velocity: Option<VelocityLoop>,
    /// Optional yaw-rate loop.
    pub yaw: Option<YawLoop>,
}

fn ser_gains<S: Serializer>(g: &PidGains, s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct Gains {
        kp: f64,
        ki: f64,
        kd: f64,
    }
    Gains {
        kp: g.kp,
        ki: g.ki,
        kd: g.kd,
    }
    .serialize(s)
}

impl ControllerSettings {
    /// A PID pitch loop with these gains and the study's setpoint, nothing else.
    pub fn pid(gains: PidGains) -> Self {
        Self {
            pitch: PitchPid {
                gains,
                ..PitchPid::default()
            },
            ..Self::default()
        }
    }

    /// Checks every setting; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ControlError> {
        let p = &self.pitch;
        let g = &p.gains;
        check("Kp", g.kp, true, "must be finite")?;
        check("Ki", g.ki, g.ki >= 0.0, "must be finite and ≥ 0")?;
        check("Kd", g.kd, true, "must be finite")?;
        match p.setpoint {
            Setpoint::Zero => {}
            Setpoint::Constant { value } => check("setpoint", value, true, "must be finite")?,
            Setpoint::Sine { amplitude } => check(
                "setpoint amplitude",
                amplitude,
                amplitude.abs() < 1.0,
                "must be finite with |A| < 1",
            )?,
        }
        if let Some(tau) = p.derivative_filter {
            check(
                "derivative filter τ_f [s]",
                tau,
                tau > 0.0,
                "must be finite and > 0",
            )?;
        }
        if let Some(f) = p.saturation {
            check("F_max [N]", f, f > 0.0, "must be finite and > 0")?;
        }
        if let AntiWindup::BackCalculation { tracking_time } = p.anti_windup {
            check(
                "back-calculation tracking time [s]",
                tracking_time,
                tracking_time > 0.0,
                "must be finite and > 0",
            )?;
        }
        if let Some(v) = &self.velocity {
            check("velocity kp", v.kp, v.kp >= 0.0, "must be finite and ≥ 0")?;
            check("velocity ki", v.ki, v.ki >= 0.0, "must be finite and ≥ 0")?;
            if let Some(lean) = v.lean_max {
                check(
                    "lean limit [rad]",
                    lean,
                    lean > 0.0 && lean < core::f64::consts::FRAC_PI_2,
                    "must be in (0, π/2)",
                )?;
            }
        }
        if let Some(y) = &self.yaw {
            check("yaw kp", y.kp, y.kp > 0.0, "must be finite and > 0")?;
        }
        Ok(())
    }

    /// Number of controller states: ∫e if Ki ≠ 0, the rate filter, ∫(v_ref − v_x) if the
    /// velocity loop has ki ≠ 0.
    pub fn n_states(&self) -> usize {
        usize::from(self.pitch.gains.ki != 0.0)
            + usize::from(self.pitch.derivative_filter.is_some())
            + usize::from(self.velocity.as_ref().is_some_and(|v| v.ki != 0.0))
    }
}

/// An initial tilt `value` [rad] of the setting `field`: finite and at most a half turn.
pub fn check_tilt(field: &str, value: f64) -> Result<(), crate::Error> {
    if value.is_finite() && value.abs() <= core::f64::consts::PI {
        return Ok(());
    }
    Err(crate::Error::input(
        field,
        format!(
            "{value} rad must be finite and at most a half turn (|Φ0| ≤ π; beyond it the \
             pendulum is below its hinge: give the whole initial state x0 instead)"
        ),
    ))
}
