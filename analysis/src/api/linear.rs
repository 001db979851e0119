//! Linearisation at an equilibrium or a steady motion: modes, the pitch loop's closed-loop
//! poles and — only when that loop is stable — its margins, an LQR design for comparison, and
//! for a two-wheeler with a steer input the steer loop's poles and margins: `twv linear`.

use nalgebra::{Complex, DMatrix};
use serde::{Deserialize, Serialize};
use twv_model::{Model, ModelInfo};

use crate::control::steer::{filter_state, SteerSettings};
use crate::control::{Plant, PITCH_STATES};
use crate::error::{Error, Result};
use crate::linear::steer::steer_closed_loop;
use crate::linear::{
    analyse_pitch, linearize, loop_response, lqr, modes, CareStatus, HiddenPart, Linearization,
    LoopOptions, LoopResponse, Lqr, Margins, Mode, ModeKind, OperatingPoint, PidGains, PitchLoop,
    SteerClosedLoop,
};
use crate::model::{dispatch, state_vector, ModelTask, ResolvedModel};
use crate::output::Files;

/// The cart–pendulum part of a vehicle, on which the LQR is designed (y, θ, v_y, w_z are not
/// reachable by the pitch force).
pub const LQR_STATES: [&str; 4] = ["phi", "x", "w_y", "v_x"];

/// Where to linearise.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum At {
    /// Everything zero: the pendulum upright at rest.
    #[default]
    Upright,
    /// Φ = π, the rest zero.
    Hanging,
    /// A given state (SI units, rad).
    State(Vec<f64>),
}

/// What to analyse. Defaults: upright, the study's PD, no lag or delay, LQR weights Q = I,
/// R = 1e-4 I, no steer law.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LinearSettings {
    /// The operating point.
    pub at: At,
    /// Linearise about the model's steady motion at this speed [m/s] instead of `at` (models
    /// whose IR describes one: the bicycle running straight and upright).
    pub speed: Option<f64>,
    /// A steer-torque law to close (a two-wheeler with a steer input, at a `speed`): its
    /// closed-loop poles and its margins at the steer torque. A torque limit is not active at
    /// the steady motion (the law commands 0 there), so the linear loop is the unsaturated one.
    pub steer: Option<SteerSettings>,
    /// Pitch PID gains.
    pub gains: PidGains,
    /// Actuator lag and delay in the loop.
    pub loop_options: LoopOptions,
    /// LQR state weight (the same for phi, x, w_y, v_x).
    pub lqr_q: f64,
    /// LQR input weight [1/N²].
    pub lqr_r: f64,
    /// Accept an operating point that is not an equilibrium (then the eigenvalues describe a
    /// frozen-time linearisation along a trajectory, not a rest point).
    pub allow_non_equilibrium: bool,
    /// Points of the loop's frequency response L(jω) to return (Bode and Nyquist plots); 0:
    /// none, at most [`MAX_FREQUENCY_POINTS`].
    pub frequency_points: usize,
}

/// Points of the frequency response when its figures are written (`twv linearize --out`) and
/// none were asked for.
pub const FIGURE_FREQUENCY_POINTS: usize = 400;

/// The most frequency-response points one analysis returns.
pub const MAX_FREQUENCY_POINTS: usize = 100_000;

impl Default for LinearSettings {
    fn default() -> Self {
        Self {
            at: At::Upright,
            speed: None,
            steer: None,
            gains: crate::control::STUDY_PD,
            loop_options: LoopOptions::default(),
            lqr_q: 1.0,
            lqr_r: 1e-4,
            allow_non_equilibrium: false,
            frequency_points: 0,
        }
    }
}

impl LinearSettings {
    /// Checks the settings that do not depend on the model.
    pub fn validate(&self) -> Result<()> {
        for (field, v) in [("lqr_q", self.lqr_q), ("lqr_r", self.lqr_r)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::input(field, format!("{v} must be finite and > 0")));
            }
        }
        self.loop_options.check()?;
        if let Some(v) = self.speed {
            super::check_speed(v)?;
            if self.at != At::Upright {
                return Err(Error::input(
                    "speed",
                    "give either an operating point (at) or a speed, not both",
                ));
            }
        }
        if let Some(law) = &self.steer {
            law.validate()?;
            if self.speed.is_none() {
                return Err(Error::input(
                    "steer_gains",
                    "the steer loop is closed about a steady motion: give its speed too",
                ));
            }
        }
        if self.frequency_points > MAX_FREQUENCY_POINTS {
            return Err(Error::input(
                "frequency_points",
                format!(
                    "{} is more than {MAX_FREQUENCY_POINTS}",
                    self.frequency_points
                ),
            ));
        }
        for (field, v) in [
            ("kp", self.gains.kp),
            ("ki", self.gains.ki),
            ("kd", self.gains.kd),
        ] {
            if !v.is_finite() {
                return Err(Error::input(field, format!("{v} is not finite")));
            }
        }
        Ok(())
    }
}

/// What the pitch loop is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LoopVerdict {
    /// Every loop pole has Re < 0 (and the delay is below the delay margin).
    Stable,
    /// A loop pole has Re ≥ 0, or the delay exceeds the delay-free loop's delay margin.
    Unstable,
    /// The force does not reach Φ (e.g. a pendulum centroid on the hinge, b = 0): there is no
    /// loop to close.
    NoLoop,
}

/// A phase margin and where it is attained.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PhaseMargin {
    /// Degrees.
    pub deg: f64,
    /// Gain crossover [rad/s].
    pub frequency: f64,
}

/// The margins of a stable loop; `None` in an optional field means unbounded.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StableMargins {
    /// Factor to which the loop gain may shrink before instability (M_x g / Kp for the pitch
    /// loop; 0: any).
    pub gain_margin_lower: f64,
    /// Factor by which it may grow; `None`: any.
    pub gain_margin_upper: Option<f64>,
    /// Smallest phase margin over the gain crossovers; `None`: no gain crossover.
    pub phase_margin: Option<PhaseMargin>,
    /// Extra delay tolerated [s]; `None`: any.
    pub delay_margin: Option<f64>,
    /// Balanced disk margin α.
    pub disk_alpha: f64,
    /// The disk's gain interval: lower factor.
    pub disk_gain_low: f64,
    /// The disk's gain interval: upper factor; `None`: unbounded (α ≥ 2).
    pub disk_gain_high: Option<f64>,
    /// The disk's phase margin ±deg.
    pub disk_phase_deg: f64,
    /// Where |S − ½| peaks [rad/s]; `None`: at infinity.
    pub disk_frequency: Option<f64>,
    /// Peak sensitivity ‖S‖∞.
    pub peak_sensitivity: f64,
}

fn finite(v: f64) -> Option<f64> {
    v.is_finite().then_some(v)
}

impl StableMargins {
    /// The margins of a stable loop (`None` for an unstable one: margins are then undefined).
    pub fn of(m: &Margins) -> Option<Self> {
        m.stable.then(|| Self {
            gain_margin_lower: m.gain_margin_lower,
            gain_margin_upper: finite(m.gain_margin_upper),
            phase_margin: finite(m.phase_margin_deg)
                .zip(finite(m.phase_margin_frequency))
                .map(|(deg, frequency)| PhaseMargin { deg, frequency }),
            delay_margin: finite(m.delay_margin),
            disk_alpha: m.disk.alpha,
            disk_gain_low: m.disk.gain_low,
            disk_gain_high: finite(m.disk.gain_high),
            disk_phase_deg: m.disk.phase_deg,
            disk_frequency: finite(m.disk.frequency),
            peak_sensitivity: m.peak_sensitivity,
        })
    }
}

/// The pitch loop with its verdict.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PitchReport {
    /// Stable, unstable, or no loop.
    pub verdict: LoopVerdict,
    /// Poles of the loop itself (minimal plant with the controller and lag states).
    pub loop_poles: Vec<Complex<f64>>,
    /// Largest real part of the loop poles; `None` without a loop.
    pub spectral_abscissa: Option<f64>,
    /// Modes the loop cannot move or see (the drift x, v_x, y, θ, …): open-loop eigenvalues.
    pub hidden: Vec<HiddenPart>,
    /// The margins, only for a stable loop.
    pub margins: Option<StableMargins>,
    /// L(jω), when asked for (`frequency_points` > 0) and there is a loop.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub response: Option<LoopResponse>,
}

impl PitchReport {
    /// The pitch loop of `lp` with `gains`, and its frequency response at `frequency_points`
    /// frequencies (0: none).
    pub fn of(
        lp: &PitchLoop,
        gains: &PidGains,
        options: &LoopOptions,
        frequency_points: usize,
    ) -> Result<Self> {
        let analysis = analyse_pitch(lp, gains, options)?;
        let cl = &analysis.closed_loop;
        let verdict = if lp.plant().order() == 0 {
            LoopVerdict::NoLoop
        } else if analysis.margins.stable {
            LoopVerdict::Stable
        } else {
            LoopVerdict::Unstable
        };
        Ok(Self {
            verdict,
            loop_poles: cl.loop_eigenvalues.clone(),
            spectral_abscissa: finite(cl.spectral_abscissa),
            hidden: cl.hidden.clone(),
            margins: match verdict {
                LoopVerdict::Stable => StableMargins::of(&analysis.margins),
                _ => None,
            },
            response: match (frequency_points, verdict) {
                (0, _) | (_, LoopVerdict::NoLoop) => None,
                (n, _) => Some(loop_response(lp, gains, options, &analysis, n)?),
            },
        })
    }
}

/// The steer loop closed about the steady motion: T_δ = K (φ, δ, φ̇, δ̇).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteerReport {
    /// The law's gains and torque limit.
    pub law: SteerSettings,
    /// The lean-and-steer states the gains act on, in the gains' order.
    pub modes: Vec<String>,
    /// The lean-and-steer loop's poles (eigenvalues of A + b K on the modes), their abscissa and
    /// whether every one has Re < 0.
    pub loop_poles: SteerClosedLoop,
    /// The margins at the steer torque (gain, phase, delay, disk), only for a stable loop.
    pub margins: Option<StableMargins>,
    /// Every state's modes with the law closed (the loop's poles and the steady motion's
    /// drift: position, heading, wheel angle, the speed nothing restores).
    pub closed_loop: Vec<Mode>,
}

/// Everything `twv linear` finds.
#[derive(Debug, Clone, Serialize)]
pub struct LinearReport {
    /// Model name.
    pub model: String,
    /// Where the parameters came from.
    pub params: String,
    /// The state linearised about.
    pub at: Vec<f64>,
    /// The steady motion's speed [m/s] when linearised about one (`None`: an equilibrium).
    pub speed: Option<f64>,
    /// max |f| there (0 at an equilibrium); at a steady motion over the states it holds (its
    /// modes and its speed: position and heading advance steadily).
    pub residual: f64,
    /// Whether the point is an equilibrium, or a steady motion (residual within
    /// [`equilibrium_tolerance`]).
    pub equilibrium: bool,
    /// Open-loop modes.
    pub open_loop: Vec<Mode>,
    /// The pitch gains.
    pub gains: PidGains,
    /// Lag and delay.
    pub loop_options: LoopOptions,
    /// The pitch loop; `None` for a model without a pitch (states phi and w_y).
    pub pitch: Option<PitchReport>,
    /// The steer loop, when a steer law was given.
    pub steer: Option<SteerReport>,
    /// States of the LQR design.
    pub lqr_states: Vec<String>,
    /// The LQR design, when the cart–pendulum part can be cut out.
    pub lqr: Option<Lqr>,
    /// Why there is no LQR design, if there is none.
    pub lqr_note: Option<String>,
    /// The state names, in order (the rows of A and B).
    pub states: Vec<String>,
    /// The input names, in order (the columns of B).
    pub inputs: Vec<String>,
    /// ∂f/∂x at the operating point, one list per row.
    #[serde(serialize_with = "crate::linear::rows")]
    pub a: DMatrix<f64>,
    /// ∂f/∂u at the operating point, one list per row (the model's own inputs).
    #[serde(serialize_with = "crate::linear::rows")]
    pub b: DMatrix<f64>,
}

/// The largest max |f(x0)| that counts as an equilibrium: 1e-9 relative to the size of the
/// terms (1 + max|A| · max|x0|).
pub fn equilibrium_tolerance(a: &DMatrix<f64>, x0: &[f64]) -> f64 {
    let x = x0.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    1e-9 * (1.0 + a.amax() * x)
}

/// The pitch loop of `lin`: the force acts along the input direction the controller uses
/// (F1, or equal wheel torques for segway7).
pub fn pitch_loop<const NX: usize, const NU: usize>(
    lin: &Linearization<NX, NU>,
    info: &ModelInfo,
    model: &ResolvedModel,
) -> Result<PitchLoop> {
    let plant = Plant::<NU>::from_info(info, &|n| model.param(n))?;
    Ok(PitchLoop::from_linearization(lin, &plant.inputs.force)?)
}

struct Linear<'a>(&'a LinearSettings);

impl ModelTask for Linear<'_> {
    type Output = LinearReport;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<LinearReport> {
        let s = self.0;
        let info = model.info();
        let at = match (&s.at, s.speed) {
            (_, Some(v)) => OperatingPoint::State(state_vector(
                "speed",
                &super::steady_state(resolved, v)?,
                info.states,
            )?),
            (At::Upright, None) => OperatingPoint::Upright,
            (At::Hanging, None) => OperatingPoint::Hanging,
            (At::State(x), None) => OperatingPoint::State(state_vector("at", x, info.states)?),
        };
        let lin = linearize(model, &at, &[0.0; NU])?;
        let (a, b_full) = lin.dynamic();
        let b = b_full.columns(0, info.inputs.len()).into_owned();
        let residual = match s.speed {
            Some(_) => steady_residual(&lin.f, &lin.states, &held_states(resolved)),
            None => lin.residual,
        };
        let equilibrium = residual <= equilibrium_tolerance(&a, &lin.x0);
        if !equilibrium && !s.allow_non_equilibrium {
            return Err(Error::input(
                if s.speed.is_some() { "speed" } else { "at" },
                format!(
                    "not an equilibrium: max |f| = {residual:.3e} there (allow it explicitly to \
                     linearise along a trajectory)",
                ),
            ));
        }
        let open_loop = modes(&a, &lin.states)?;
        let pitch = if PITCH_STATES.iter().all(|n| info.states.contains(n)) {
            Some(PitchReport::of(
                &pitch_loop(&lin, &info, resolved)?,
                &s.gains,
                &s.loop_options,
                s.frequency_points,
            )?)
        } else {
            None
        };
        let steer = match (&s.steer, s.speed) {
            (Some(law), Some(v)) => Some(steer_report(resolved, &a, &b, &lin.states, law, v)?),
            _ => None,
        };
        let (lqr, lqr_note) = match lin.subsystem(&LQR_STATES) {
            Ok((a_sub, b_sub)) => {
                // Only the model's own inputs (an interpreted model may carry padding ones).
                let nu = info.inputs.len();
                let b_sub = b_sub.columns(0, nu).into_owned();
                let q = DMatrix::identity(LQR_STATES.len(), LQR_STATES.len()) * s.lqr_q;
                let r = DMatrix::identity(nu, nu) * s.lqr_r;
                let design = lqr(&a_sub, &b_sub, &q, &r)?;
                match design.status {
                    CareStatus::Solved => (Some(design), None),
                    status => (
                        None,
                        Some(format!(
                            "the Riccati equation has no usable solution ({status:?}): the \
                             cart–pendulum part is not stabilisable by the inputs"
                        )),
                    ),
                }
            }
            Err(e) => (None, Some(e.to_string())),
        };
        Ok(LinearReport {
            model: resolved.name().to_string(),
            params: resolved.params_origin.clone(),
            at: lin.x0.to_vec(),
            speed: s.speed,
            residual,
            equilibrium,
            open_loop,
            gains: s.gains,
            loop_options: s.loop_options,
            pitch,
            steer,
            lqr_states: LQR_STATES.iter().map(|s| s.to_string()).collect(),
            lqr,
            lqr_note,
            states: info.states.iter().map(|s| s.to_string()).collect(),
            inputs: info.inputs.iter().map(|s| s.to_string()).collect(),
            a,
            b,
        })
    }
}

/// The states a steady motion holds constant: the modes its IR studies and its speed (the
/// coordinates it advances, position and heading, are the others).
fn held_states(model: &ResolvedModel) -> Vec<String> {
    model.steady_motion().map_or_else(Vec::new, |m| {
        let mut held = m.modes.clone();
        held.push(m.speed_state.clone());
        held
    })
}

/// max |f| over the `held` states: zero at a steady motion, where those are at rest while the
/// position and heading advance at a constant rate.
fn steady_residual(f: &[f64], states: &[String], held: &[String]) -> f64 {
    f.iter()
        .zip(states)
        .filter(|(_, n)| held.contains(n))
        .fold(0.0_f64, |m, (v, _)| m.max(v.abs()))
}

/// The steer loop closed about the steady motion at `speed`: its poles and margins on the
/// lean-and-steer plant ([`super::steer_loop`], the IR's steady-motion Jacobian) and every
/// state's modes of A + b K (the model's own Jacobian `a`, `b`).
fn steer_report(
    resolved: &ResolvedModel,
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    states: &[String],
    law: &SteerSettings,
    speed: f64,
) -> Result<SteerReport> {
    let lp = super::steer_loop(resolved, speed)?.with_rate_filter(law.rate_filter)?;
    let analysis = lp.analyse(&law.gains)?;
    let input = super::steer_input(resolved)?;
    let mut at = [0; 4];
    for (slot, mode) in at.iter_mut().zip(lp.modes()) {
        *slot = resolved
            .state_index(mode)
            .ok_or_else(|| Error::Unsupported {
                model: resolved.name().to_string(),
                reason: format!("steady-motion mode `{mode}` is not a state"),
            })?;
    }
    let b_steer: Vec<f64> = b.column(input).iter().copied().collect();
    let closed = steer_closed_loop(a, &b_steer, at, &law.gains, law.rate_filter);
    // The filter's states are named after the rates they filter.
    let mut names = states.to_vec();
    if law.rate_filter.is_some() {
        names.extend(lp.modes()[2..].iter().map(|m| filter_state(m)));
    }
    Ok(SteerReport {
        law: *law,
        modes: lp.modes().to_vec(),
        margins: StableMargins::of(&analysis.margins),
        loop_poles: analysis.closed_loop,
        closed_loop: modes(&closed, &names)?,
    })
}

/// The linear analysis of `model` with `settings`.
pub fn analyse(model: &ResolvedModel, settings: &LinearSettings) -> Result<LinearReport> {
    settings.validate()?;
    dispatch(model, Linear(settings))
}

/// A complex number for people: `-1.428571` or `-0.5 + 1.2i`.
pub fn complex(c: &Complex<f64>) -> String {
    if c.im.abs() < 1e-12 * c.re.abs().max(1.0) {
        format!("{:+.6}", c.re)
    } else {
        format!(
            "{:+.6} {} {:.6}i",
            c.re,
            if c.im < 0.0 { '-' } else { '+' },
            c.im.abs()
        )
    }
}

fn list(values: &[Complex<f64>]) -> String {
    values.iter().map(complex).collect::<Vec<_>>().join(", ")
}

/// One line per mode; a repeated eigenvalue (or a conjugate pair) shares one eigenspace, so
/// each group is printed once with its multiplicity.
fn mode_lines(modes: &[Mode]) -> String {
    let mut s = String::new();
    let mut i = 0;
    while i < modes.len() {
        let m = &modes[i];
        let near =
            |e: Complex<f64>| (e - m.eigenvalue).norm() <= 1e-9 * m.eigenvalue.norm().max(1.0);
        let same = modes[i..]
            .iter()
            .take_while(|n| {
                n.kind == m.kind
                    && n.states == m.states
                    && (n.kind == ModeKind::Drift
                        || near(n.eigenvalue)
                        || near(n.eigenvalue.conj()))
            })
            .count();
        let value = if same > 1 {
            format!("{} (×{same})", complex(&m.eigenvalue))
        } else {
            complex(&m.eigenvalue)
        };
        s += &format!("    {value:<28} {:?} ({})\n", m.kind, m.states.join(", "));
        i += same;
    }
    s
}

/// The margins of a stable loop, two lines.
fn margin_lines(m: &StableMargins) -> String {
    let or_any =
        |v: Option<f64>, unit: &str| v.map_or("unbounded".to_string(), |v| format!("{v:.4}{unit}"));
    format!(
        "    gain margin [{:.4}, {}], phase margin {}, delay margin {}\n    disk margin α = \
         {:.4}: gain [{:.4}, {}], phase ±{:.2}°; peak |S| = {:.3}\n",
        m.gain_margin_lower,
        or_any(m.gain_margin_upper, ""),
        m.phase_margin
            .map_or("unbounded (no gain crossover)".to_string(), |p| {
                format!("{:.2}° at {:.3} rad/s", p.deg, p.frequency)
            }),
        or_any(m.delay_margin, " s"),
        m.disk_alpha,
        m.disk_gain_low,
        or_any(m.disk_gain_high, ""),
        m.disk_phase_deg,
        m.peak_sensitivity
    )
}

impl SteerReport {
    /// The law, its verdict, the loop's poles, the margins, and every state's closed-loop modes.
    pub fn summary(&self) -> String {
        let g = &self.law.gains;
        let mut s = format!(
            "  steer loop k_phi = {}, k_delta = {}, k_phi_dot = {}, k_delta_dot = {}: {}\n",
            g.k_phi,
            g.k_delta,
            g.k_phi_dot,
            g.k_delta_dot,
            if self.loop_poles.stable {
                "stable"
            } else {
                "UNSTABLE"
            }
        );
        if let Some(tau) = self.law.rate_filter {
            s += &format!("    rates read through 1/({tau} s · s + 1)\n");
        }
        s += &format!("    loop poles: {}\n", list(&self.loop_poles.eigenvalues));
        match &self.margins {
            Some(m) => s += &margin_lines(m),
            None => s += "    unstable: margins undefined\n",
        }
        s += "  closed-loop modes (every state):\n";
        s += &mode_lines(&self.closed_loop);
        s
    }
}

impl PitchReport {
    /// The verdict, the poles and (for a stable loop) the margins, a few lines.
    pub fn summary(&self) -> String {
        let mut s = String::new();
        match self.verdict {
            LoopVerdict::NoLoop => {
                s += "    no loop: the force does not reach Φ (its transfer function is zero), \
                      so there is nothing to stabilise and no margin to state\n";
            }
            _ => s += &format!("    loop poles: {}\n", list(&self.loop_poles)),
        }
        for h in &self.hidden {
            s += &format!(
                "    uncontrolled ({:?}): {} ({})\n",
                h.kind,
                list(&h.eigenvalues),
                h.states.join(", ")
            );
        }
        match (&self.margins, self.verdict) {
            (Some(m), _) => s += &margin_lines(m),
            (None, LoopVerdict::Unstable) => s += "    unstable: margins undefined\n",
            (None, _) => {}
        }
        s
    }
}

impl LinearReport {
    /// The pitch loop's Bode and Nyquist figures (`bode.svg`, `nyquist.svg`), when the report
    /// has its frequency response.
    pub fn figures(&self) -> Vec<(String, crate::plot::Figure)> {
        let g = &self.gains;
        let title = format!(
            "{} pitch loop, Kp {} Ki {} Kd {}",
            self.model, g.kp, g.ki, g.kd
        );
        let Some(r) = self.pitch.as_ref().and_then(|p| p.response.as_ref()) else {
            return Vec::new();
        };
        [
            ("bode.svg", super::bode(&title, r)),
            ("nyquist.svg", super::nyquist(&title, r)),
        ]
        .into_iter()
        .filter_map(|(name, f)| Some((name.to_string(), f?)))
        .collect()
    }

    /// linear.json and the figures with their PNGs.
    pub fn files(&self) -> Result<Files> {
        let mut f = Files::new();
        f.json("linear.json", self);
        for (name, figure) in self.figures() {
            f.figure(&name, &figure)?;
        }
        Ok(f)
    }

    /// A readable summary.
    pub fn summary(&self) -> String {
        let mut s = format!(
            "linear analysis of {} ({}){}, residual {:.1e}{}\n",
            self.model,
            self.params,
            self.speed
                .map_or(String::new(), |v| format!(" at its steady motion, {v} m/s")),
            self.residual,
            if self.equilibrium {
                ""
            } else {
                " (NOT an equilibrium: frozen-time linearisation)"
            }
        );
        s += "  open-loop modes:\n";
        s += &mode_lines(&self.open_loop);
        let g = &self.gains;
        match &self.pitch {
            Some(pitch) => {
                s += &format!(
                    "  pitch loop Kp = {}, Ki = {}, Kd = {}: {}\n",
                    g.kp,
                    g.ki,
                    g.kd,
                    match pitch.verdict {
                        LoopVerdict::Stable => "stable",
                        LoopVerdict::Unstable => "UNSTABLE",
                        LoopVerdict::NoLoop => "NO LOOP",
                    }
                );
                s += &pitch.summary();
            }
            None => s += "  pitch loop: none (the model has no pitch states phi, w_y)\n",
        }
        if let Some(st) = &self.steer {
            s += &st.summary();
        }
        match (&self.lqr, &self.lqr_note) {
            (Some(l), _) => {
                s += &format!(
                    "  LQR on ({}): {:?}, residual {:.1e}, K = {:.4}",
                    self.lqr_states.join(", "),
                    l.status,
                    l.residual,
                    l.k
                );
                s += &format!(
                    "    closed-loop poles: {}\n",
                    list(&l.closed_loop_eigenvalues)
                );
            }
            (None, Some(note)) => s += &format!("  LQR: not designed ({note})\n"),
            (None, None) => {}
        }
        s
    }
}
