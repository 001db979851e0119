//! Running a vector field over a time span and keeping samples: the closed-loop and open-loop
//! simulations behind `twv sim`, `twv phase` and `twv disturb`.

use serde::{Deserialize, Serialize};

use super::error::ControlError;
use crate::integrate::{Dopri5, Rk4, Stepper, VectorField};
use crate::lyapunov::IntegratorChoice;
use crate::progress::Progress;

/// The most samples one run may record (t_end / sample interval).
pub const MAX_SAMPLES: f64 = 2e6;

/// How long and how finely to run. Defaults are beside each field.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RunSettings {
    /// End time [s]. Default 10.
    pub t_end: f64,
    /// Output interval [s] (samples at 0, Δ, 2Δ, …, t_end). Default 0.01.
    pub sample: f64,
    /// The integrator. Default RK4 with h = 10⁻³ s (the study's).
    pub integrator: IntegratorChoice,
    /// Stop when |Φ| exceeds this [rad] at a sample: the vehicle fell over (the model itself has
    /// no ground). Default π/2; `None` runs on.
    pub fall_angle: Option<f64>,
}

impl Default for RunSettings {
    fn default() -> Self {
        Self {
            t_end: 10.0,
            sample: 0.01,
            integrator: IntegratorChoice::default(),
            fall_angle: Some(std::f64::consts::FRAC_PI_2),
        }
    }
}

impl RunSettings {
    /// Checks the span, sampling and fall angle.
    pub fn validate(&self) -> Result<(), ControlError> {
        use super::error::check;
        check(
            "t_end [s]",
            self.t_end,
            self.t_end > 0.0,
            "must be finite and > 0",
        )?;
        check(
            "sample interval [s]",
            self.sample,
            self.sample > 0.0 && self.sample <= self.t_end,
            "must be finite, > 0 and ≤ t_end",
        )?;
        // Every sample is kept in memory and written out: cap the table at a size a person can
        // still open (and the machine can hold), rather than run out of memory hours later.
        let samples = self.t_end / self.sample;
        check(
            "t_end / sample interval (number of samples)",
            samples,
            samples <= MAX_SAMPLES,
            "must be ≤ 2e6: raise the sample interval or shorten the run",
        )?;
        if let Some(a) = self.fall_angle {
            check("fall angle [rad]", a, a > 0.0, "must be > 0")?;
        }
        // The same rules as the Lyapunov settings: a step within the interval it samples, and
        // no more steps than any run may take.
        match &self.integrator {
            IntegratorChoice::Rk4 { h } => {
                check("h (RK4 step) [s]", *h, *h > 0.0, "must be finite and > 0")?;
                check(
                    "h (RK4 step) [s]",
                    *h,
                    *h <= self.sample,
                    "must be ≤ the sample interval",
                )?;
                let steps = self.t_end / h;
                check(
                    "t_end / h (number of RK4 steps)",
                    steps,
                    steps <= crate::integrate::MAX_STEPS as f64,
                    "must be ≤ 1e9: raise h or shorten the run",
                )?;
            }
            IntegratorChoice::Dopri(o) => o.validate()?,
        }
        Ok(())
    }

    /// The fall angle as a person reads it: `1.5708 rad (90°)`, `none` when not checked.
    pub fn fall_angle_text(&self) -> String {
        self.fall_angle.map_or("none".into(), |a| {
            format!("{a:.4} rad ({:.0}°)", a.to_degrees())
        })
    }
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RunEnd {
    /// Reached t_end.
    Completed,
    /// |Φ| passed the fall angle at the sample time `t` (or the state blew up, from time `t`,
    /// after passing it between two samples).
    Fell {
        /// Time of the first sample past the fall angle [s] (or of the blow-up).
        t: f64,
        /// Φ there [rad] (or at the last finite state before the blow-up).
        phi: f64,
        /// Whether the state blew up after |Φ| passed the fall angle between two samples: then
        /// `phi` is where the integration broke down, not an angle the model reached.
        blew_up: bool,
    },
}

impl RunEnd {
    /// How the run fell, for a summary: `|phi| passed 1.5708 rad (90°) at t = 1.470 s (-0.503
    /// rad)`, or that the integration broke down after the fall; `None` if it did not fall.
    pub fn fall_text(&self, watch: &str, run: &RunSettings) -> Option<String> {
        let RunEnd::Fell { t, phi, blew_up } = *self else {
            return None;
        };
        let passed = format!("|{watch}| passed {}", run.fall_angle_text());
        Some(if blew_up {
            format!("{passed}, and the integration then broke down, by t = {t:.3} s")
        } else {
            format!("{passed} at t = {t:.3} s ({phi:+.3} rad)")
        })
    }
}

/// Samples of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory<const N: usize> {
    /// Sample times [s].
    pub t: Vec<f64>,
    /// States at the sample times.
    pub x: Vec<[f64; N]>,
    /// How the run ended.
    pub end: RunEnd,
}

impl<const N: usize> Trajectory<N> {
    /// Component `i` over time.
    pub fn component(&self, i: usize) -> Vec<f64> {
        self.x.iter().map(|x| x[i]).collect()
    }

    /// The last state.
    pub fn last(&self) -> &[f64; N] {
        self.x.last().expect("a trajectory holds its initial state")
    }
}

/// Integrates `field` from `x0` at t = 0 and samples it every `run.sample` seconds; `phi` is the
/// index of Φ for the fall check. A blow-up is an error naming the time and the state, unless
/// Φ had passed the fall angle by its last finite state: a model that has fallen between two
/// samples may blow up (the bicycle's contact geometry degenerates lying flat), and that is
/// the fall the run stops at anyway.
pub fn simulate<F, const N: usize>(
    field: F,
    x0: &[f64; N],
    phi: usize,
    run: &RunSettings,
    progress: &dyn Progress,
) -> Result<Trajectory<N>, ControlError>
where
    F: VectorField<N>,
{
    run.validate()?;
    if phi >= N {
        return Err(ControlError::InvalidRun(format!(
            "pitch index {phi} outside the {N}-state vector"
        )));
    }
    match run.integrator {
        IntegratorChoice::Rk4 { h } => {
            sample(Rk4::new(field, 0.0, *x0, [], h, false)?, phi, run, progress)
        }
        IntegratorChoice::Dopri(opts) => sample(
            Dopri5::new(field, 0.0, *x0, [], opts, false)?,
            phi,
            run,
            progress,
        ),
    }
}

fn sample<S: Stepper<N, 0>, const N: usize>(
    mut stepper: S,
    phi: usize,
    run: &RunSettings,
    progress: &dyn Progress,
) -> Result<Trajectory<N>, ControlError> {
    // Sample i at i·Δ (not an accumulated sum), the last exactly at t_end.
    let n = (run.t_end / run.sample * (1.0 - 1e-12)).ceil() as usize;
    progress.start(n as u64, "samples");
    // Progress in about 200 steps, however many samples.
    let every = (n / 200).max(1);
    let mut traj = Trajectory {
        t: Vec::with_capacity(n + 1),
        x: Vec::with_capacity(n + 1),
        end: RunEnd::Completed,
    };
    traj.t.push(stepper.t());
    traj.x.push(stepper.state().x);
    for i in 1..=n {
        let t = if i == n {
            run.t_end
        } else {
            i as f64 * run.sample
        };
        match stepper.advance_to(t) {
            Ok(()) => {}
            Err(crate::integrate::IntegrateError::BlowUp { t, x, .. })
                if run
                    .fall_angle
                    .zip(x.get(phi))
                    .is_some_and(|(limit, p)| p.abs() > limit) =>
            {
                traj.end = RunEnd::Fell {
                    t,
                    phi: x[phi],
                    blew_up: true,
                };
                break;
            }
            Err(e) => return Err(e.into()),
        }
        if i % every == 0 {
            progress.advance(every as u64);
            if progress.cancelled() {
                return Err(ControlError::Interrupted);
            }
        }
        let x = stepper.state().x;
        traj.t.push(t);
        traj.x.push(x);
        if let Some(limit) = run.fall_angle {
            if x[phi].abs() > limit {
                traj.end = RunEnd::Fell {
                    t,
                    phi: x[phi],
                    blew_up: false,
                };
                break;
            }
        }
    }
    Ok(traj)
}
