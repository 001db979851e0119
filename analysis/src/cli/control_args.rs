//! What the control commands (`sim`, `phase`, `disturb`, `lyap --gains`) share: the controller
//! and run options, gain parsing, and the dispatch that picks the augmented size NA = NX + NZ.
//!
//! A closed loop with NZ controller states is a `VectorField<NA>` with NA = NX + NZ, which stable
//! Rust cannot spell for a generic NX. So these commands resolve the model themselves, with NX
//! as a literal, and match NZ ∈ 0..=3 to `{NX + NZ}`: four instantiations per supported model
//! size (shipped vehicle8, vehicle7, segway7; IR files with 4, 7 or 8 states and 1 or 2 inputs),
//! rather than the 30 sizes × every NA the generic `dispatch` would instantiate.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use twv_generated::{Segway7, Vehicle7, Vehicle8};
use twv_ir::{Interpreted, MAX_NU};
use twv_model::Model;

use super::model::{parse_vector, LoadedModel, Source};
use crate::control::{
    AntiWindup, ControllerSettings, PitchPid, Plant, Profile, RunSettings, Setpoint, VelocityLoop,
    YawLoop,
};
use crate::integrate::DopriOptions;
use crate::linear::PidGains;
use crate::lyapunov::IntegratorChoice;

/// Controller options besides the gains.
#[derive(Args, Debug, Clone)]
pub struct ControllerArgs {
    /// Pitch setpoint Φ_ref: `study` (0.03·sin Φ, the study's), `zero`, `sine:A` (A·sin Φ) or a
    /// constant angle in rad [default: study]
    #[arg(long, value_name = "SETPOINT", allow_hyphen_values = true)]
    pub setpoint: Option<String>,
    /// First-order filter on the measured pitch rate, time constant [s] [default: none]
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub rate_filter: Option<f64>,
    /// Force limit |F| ≤ F_MAX [N] (for segway7 the total wheel torque is F·R) [default: none]
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    pub f_max: Option<f64>,
    /// Anti-windup when saturated: none, conditional (clamping) or back-calc [default: conditional]
    #[arg(long, value_enum, value_name = "KIND")]
    pub anti_windup: Option<AntiWindupKind>,
    /// Back-calculation tracking time [s] [default: 0.3]
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub tracking_time: Option<f64>,
    /// Forward-velocity outer loop gains KP,KI [rad per m/s, rad per m]: leans the pitch
    /// setpoint by KP·(v_ref − v_x) + KI·∫(v_ref − v_x) dt [default: no velocity loop; the
    /// maneuver scenario uses 0.08,0.03]
    #[arg(long, value_name = "KP,KI")]
    pub v_loop: Option<String>,
    /// Constant forward-velocity reference for the velocity loop [m/s] [default: 0]
    #[arg(long, value_name = "M/S", allow_hyphen_values = true)]
    pub v_ref: Option<f64>,
    /// Largest lean the velocity loop may ask for [rad] (its integral holds while limited)
    /// [default: no limit]
    #[arg(long, value_name = "RAD", allow_hyphen_values = true)]
    pub lean_max: Option<f64>,
    /// Yaw-rate loop gain [N m per rad/s]: T = KP·(r_ref − w_z) on T2 (differential wheel torque
    /// for segway7) [default: no yaw loop]
    #[arg(long, value_name = "KP")]
    pub yaw_kp: Option<f64>,
    /// Constant yaw-rate reference for the yaw loop [rad/s] [default: 0]
    #[arg(long, value_name = "RAD/S", allow_hyphen_values = true)]
    pub yaw_ref: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AntiWindupKind {
    /// The integral runs on while saturated
    None,
    /// Stop integrating while saturated and the error pushes further into saturation
    Conditional,
    /// Pull the integral back by (F − F_cmd)/(Ki·T_t)
    BackCalc,
}

/// Length, sampling and integrator of a run.
#[derive(Args, Debug, Clone)]
pub struct RunArgs {
    /// Simulated time [s] [default: 10; for the maneuver its length + 10]
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub t_end: Option<f64>,
    /// Output interval of the CSV and figures [s] [default: 0.01]
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub sample: Option<f64>,
    /// Integrator [default: rk4]
    #[arg(long, value_enum)]
    pub integrator: Option<super::lyap::Integrator>,
    /// RK4 step, or the DOPRI initial step [s] [default: 1e-3]
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub h: Option<f64>,
    /// DOPRI relative tolerance [default: 1e-9]
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    pub rtol: Option<f64>,
    /// DOPRI absolute tolerance [default: 1e-12]
    #[arg(long, value_name = "TOL", allow_hyphen_values = true)]
    pub atol: Option<f64>,
    /// Stop the run when |Φ| exceeds this angle: the vehicle fell over [rad]; `inf` runs on
    /// [default: 1.5708 (π/2)]
    #[arg(long, value_name = "RAD", allow_hyphen_values = true)]
    pub fall_angle: Option<f64>,
}

impl RunArgs {
    /// The validated run settings; `t_end` defaults to `default_t_end`.
    pub fn settings(&self, default_t_end: f64) -> Result<RunSettings> {
        let h = self.h.unwrap_or(1e-3);
        let integrator = match self.integrator.unwrap_or(super::lyap::Integrator::Rk4) {
            super::lyap::Integrator::Rk4 => IntegratorChoice::Rk4 { h },
            super::lyap::Integrator::Dopri => IntegratorChoice::Dopri(DopriOptions {
                rtol: self.rtol.unwrap_or(1e-9),
                atol: self.atol.unwrap_or(1e-12),
                h_init: self.h,
                ..DopriOptions::default()
            }),
        };
        let run = RunSettings {
            t_end: self.t_end.unwrap_or(default_t_end),
            sample: self.sample.unwrap_or(0.01),
            integrator,
            fall_angle: match self.fall_angle {
                Some(a) if a == f64::INFINITY => None,
                Some(a) => Some(a),
                None => RunSettings::default().fall_angle,
            },
        };
        run.validate()?;
        Ok(run)
    }
}

/// `Kp,Ki,Kd` → gains (three finite numbers).
pub fn parse_gains(option: &str, text: &str) -> Result<PidGains> {
    let v = parse_vector(option, text, &["Kp", "Ki", "Kd"])
        .with_context(|| format!("--{option} wants three numbers Kp,Ki,Kd, got `{text}`"))?;
    Ok(PidGains {
        kp: v[0],
        ki: v[1],
        kd: v[2],
    })
}

/// `A;B;C` → the non-empty parts, trimmed.
pub fn split_sets(text: &str) -> Vec<&str> {
    text.split(';')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect()
}

fn parse_setpoint(text: &str) -> Result<Setpoint> {
    let t = text.trim();
    Ok(match t {
        "study" => Setpoint::STUDY,
        "zero" | "0" => Setpoint::Zero,
        _ => match t.strip_prefix("sine:") {
            Some(a) => Setpoint::Sine {
                amplitude: a
                    .trim()
                    .parse()
                    .with_context(|| format!("--setpoint sine:A: `{a}` is not a number"))?,
            },
            None => Setpoint::Constant {
                value: t.parse().with_context(|| {
                    format!("--setpoint `{t}`: use study, zero, sine:A or an angle in rad")
                })?,
            },
        },
    })
}

impl ControllerArgs {
    /// Whether any controller option was given (an open-loop command must not ignore them).
    pub fn any(&self) -> bool {
        self.setpoint.is_some()
            || self.rate_filter.is_some()
            || self.f_max.is_some()
            || self.anti_windup.is_some()
            || self.tracking_time.is_some()
            || self.v_loop.is_some()
            || self.v_ref.is_some()
            || self.lean_max.is_some()
            || self.yaw_kp.is_some()
            || self.yaw_ref.is_some()
    }

    /// The validated controller with `gains`; `velocity` overrides the velocity loop's
    /// reference (the maneuver scenario), `default_v_loop` its gains when `--v-loop` is absent.
    pub fn settings(
        &self,
        gains: PidGains,
        velocity: Option<Profile>,
        default_v_loop: Option<(f64, f64)>,
    ) -> Result<ControllerSettings> {
        let anti_windup = match self.anti_windup.unwrap_or(AntiWindupKind::Conditional) {
            AntiWindupKind::None => AntiWindup::None,
            AntiWindupKind::Conditional => AntiWindup::Conditional,
            AntiWindupKind::BackCalc => AntiWindup::BackCalculation {
                tracking_time: self.tracking_time.unwrap_or(0.3),
            },
        };
        if self.tracking_time.is_some() && self.anti_windup != Some(AntiWindupKind::BackCalc) {
            bail!("--tracking-time needs --anti-windup back-calc");
        }
        let v_gains = match &self.v_loop {
            Some(text) => {
                let v = parse_vector("v-loop", text, &["KP", "KI"])
                    .context("--v-loop wants two numbers KP,KI")?;
                Some((v[0], v[1]))
            }
            None => default_v_loop,
        };
        if self.v_ref.is_some() && v_gains.is_none() {
            bail!("--v-ref needs the velocity loop: give --v-loop KP,KI");
        }
        if self.lean_max.is_some() && v_gains.is_none() {
            bail!("--lean-max needs the velocity loop: give --v-loop KP,KI");
        }
        let velocity = v_gains.map(|(kp, ki)| VelocityLoop {
            kp,
            ki,
            reference: velocity.unwrap_or_else(|| Profile::constant(self.v_ref.unwrap_or(0.0))),
            lean_max: self.lean_max,
        });
        if self.yaw_ref.is_some() && self.yaw_kp.is_none() {
            bail!("--yaw-ref needs the yaw loop: give --yaw-kp KP");
        }
        let yaw = self.yaw_kp.map(|kp| YawLoop {
            kp,
            reference: Profile::constant(self.yaw_ref.unwrap_or(0.0)),
        });
        let settings = ControllerSettings {
            pitch: PitchPid {
                gains,
                setpoint: match &self.setpoint {
                    Some(text) => parse_setpoint(text)?,
                    None => Setpoint::STUDY,
                },
                derivative_filter: self.rate_filter,
                saturation: self.f_max,
                anti_windup,
            },
            velocity,
            yaw,
        };
        settings.validate()?;
        Ok(settings)
    }
}

/// The controller's view of a resolved model (names and the parameters `R`, `c`).
pub fn plant<const NX: usize, const NU: usize, M: Model<NX, NU>>(
    model: &M,
    loaded: &LoadedModel,
) -> Result<Plant<NU>> {
    Ok(Plant::from_info(&model.info(), |name| loaded.param(name))?)
}

/// Work on a closed loop whose augmented size NA is known only once the controller is.
pub trait ControlTask {
    type Output;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<Self::Output>;
}

/// Runs `task` on the resolved model with NA = NX + `nz` (see the module documentation).
pub fn dispatch_control<T: ControlTask>(
    loaded: &LoadedModel,
    nz: usize,
    task: T,
) -> Result<T::Output> {
    macro_rules! with_na {
        ($model:expr, $nx:literal, $nu:literal) => {{
            let model = $model;
            match nz {
                0 => task.run::<$nx, $nu, $nx, _>(&model, loaded),
                1 => task.run::<$nx, $nu, { $nx + 1 }, _>(&model, loaded),
                2 => task.run::<$nx, $nu, { $nx + 2 }, _>(&model, loaded),
                3 => task.run::<$nx, $nu, { $nx + 3 }, _>(&model, loaded),
                _ => bail!("{nz} controller states: at most 3 are supported"),
            }
        }};
    }
    let values = |n: usize| -> Result<Vec<f64>> {
        if loaded.params.len() != n {
            bail!(
                "{} parameter values for a model with {n}",
                loaded.params.len()
            );
        }
        Ok(loaded.params.clone())
    };
    match &loaded.source {
        Source::Shipped(name) => match name.as_str() {
            "vehicle8" => with_na!(Vehicle8::new(fixed(values(Vehicle8::NP)?)), 8, 2),
            "vehicle7" => with_na!(Vehicle7::new(fixed(values(Vehicle7::NP)?)), 7, 2),
            "segway7" => with_na!(Segway7::new(fixed(values(Segway7::NP)?)), 7, 2),
            other => bail!(
                "model `{other}` has no pitch to control: the control commands run vehicle8, \
                 vehicle7, segway7, or an --ir model with states phi, w_y and inputs F1[, T2] \
                 or tau_L, tau_R"
            ),
        },
        Source::File(path) => {
            let ir = &loaded.ir;
            let p = &loaded.params;
            // Interpreted models take 4 inputs, the real ones first (see `twv_ir::Interpreted`).
            match (ir.nx(), ir.nu()) {
                (8, 1 | 2) => with_na!(Interpreted::<8, MAX_NU>::new(ir, p)?, 8, 4),
                (7, 1 | 2) => with_na!(Interpreted::<7, MAX_NU>::new(ir, p)?, 7, 4),
                (4, 1 | 2) => with_na!(Interpreted::<4, MAX_NU>::new(ir, p)?, 4, 4),
                (nx, nu) => bail!(
                    "{}: {nx} states and {nu} inputs; the control commands support IR models \
                     with 8, 7 or 4 states and 1 or 2 inputs",
                    path.display()
                ),
            }
        }
    }
}

/// A parameter vector of checked length as an array.
fn fixed<const N: usize>(v: Vec<f64>) -> [f64; N] {
    super::model::to_array(&v)
}
