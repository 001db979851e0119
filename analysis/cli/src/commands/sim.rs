//! `twv sim`: one closed-loop run of the PID pitch controller — a tilt recovery or the
//! start/accelerate/cruise/decelerate/stop maneuver — as CSV, figures and metrics.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use twv_analysis::api::{simulate, SimSettings, MANEUVER_V_LOOP};
use twv_analysis::control::STUDY_PD;

use super::interrupted_or;
use crate::common::{
    parse_gains, parse_vector, print_result, write_files, Context, ControllerArgs, ModelArgs,
    Outcome, RunArgs,
};

/// What to simulate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ScenarioKind {
    /// Recovery from an initial state (by default a forward tilt of --tilt)
    Tilt,
    /// From rest: accelerate to --v-cruise, cruise, decelerate, stop, through the velocity loop
    Maneuver,
}

/// Simulate the closed loop: PID on the pitch Φ driving the base force (or wheel torques).
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct SimArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Scenario [default: tilt]
    #[arg(long, value_enum)]
    pub scenario: Option<ScenarioKind>,
    /// Initial state, comma-separated in the model's state order (SI units, rad) [default: at
    /// rest with Φ = --tilt for tilt, at rest upright for maneuver]
    #[arg(long, value_name = "V1,V2,...", allow_hyphen_values = true)]
    pub x0: Option<String>,
    /// Initial pitch when --x0 is not given [rad] [default: 0.1 for tilt, 0 for maneuver]
    #[arg(long, value_name = "RAD", alias = "phi0", conflicts_with = "x0")]
    pub tilt: Option<f64>,
    /// PID gains Kp,Ki,Kd of F = Kp e + Ki ∫e + Kd Φ̇ [N/rad, N/(rad s), N s/rad]
    /// [default: 3860,0,1980, the study's PD]
    #[arg(long, value_name = "KP,KI,KD", allow_hyphen_values = true)]
    pub gains: Option<String>,
    /// Maneuver cruise speed [m/s] [default: 2]
    #[arg(long, value_name = "M/S")]
    pub v_cruise: Option<f64>,
    /// Maneuver acceleration and deceleration time [s] [default: 3]
    #[arg(long, value_name = "S")]
    pub ramp: Option<f64>,
    /// Maneuver cruise time [s] [default: 5]
    #[arg(long, value_name = "S")]
    pub cruise: Option<f64>,
    #[command(flatten)]
    pub controller: ControllerArgs,
    #[command(flatten)]
    pub run: RunArgs,
    /// Write sim.csv, metrics.json and the figures (phi, phi_dot, v_x, x, force; v_y, theta
    /// when they move; SVG and PNG) into this folder
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the result as JSON on stdout
    #[arg(long)]
    pub json: bool,
}

/// Runs `settings` on the model, writes and prints the result.
pub fn execute(
    ctx: &Context,
    model: &ModelArgs,
    settings: &SimSettings,
    out: Option<&std::path::Path>,
    json: bool,
) -> Result<Outcome> {
    let model = model.resolve(ctx)?;
    let bar = ctx.bar();
    let result = match interrupted_or(simulate(&model, settings, &bar), "the simulation")? {
        Ok(r) => r,
        Err(outcome) => return Ok(outcome),
    };
    if let Some(dir) = out {
        write_files(ctx, dir, &result.files()?)?;
    }
    print_result(&result, json, || result.summary())?;
    Ok(Outcome::Done)
}

pub fn run(args: &SimArgs, ctx: &Context) -> Result<Outcome> {
    let gains = match &args.gains {
        Some(text) => parse_gains("gains", text)?,
        None => STUDY_PD,
    };
    let x0 = args
        .x0
        .as_deref()
        .map(|x| parse_vector("x0", x))
        .transpose()?;
    let settings = match args.scenario.unwrap_or(ScenarioKind::Tilt) {
        ScenarioKind::Tilt => {
            if args.v_cruise.is_some() || args.ramp.is_some() || args.cruise.is_some() {
                bail!("--v-cruise, --ramp and --cruise belong to --scenario maneuver");
            }
            SimSettings {
                title: format!("tilt, Kp {} Ki {} Kd {}", gains.kp, gains.ki, gains.kd),
                scenario: "tilt".into(),
                controller: args.controller.settings(gains, None)?,
                run: args.run.settings(10.0),
                x0,
                phi0: args.tilt.unwrap_or(0.1),
            }
        }
        ScenarioKind::Maneuver => {
            if args.controller.v_ref.is_some() {
                bail!("--scenario maneuver sets the velocity reference itself; drop --v-ref");
            }
            let base = args.controller.settings(gains, Some(MANEUVER_V_LOOP))?;
            let mut s = SimSettings::maneuver(
                base,
                (
                    args.v_cruise.unwrap_or(2.0),
                    args.ramp.unwrap_or(3.0),
                    args.cruise.unwrap_or(5.0),
                ),
                args.run.settings(10.0),
                args.run.t_end,
            )?;
            s.x0 = x0;
            s.phi0 = args.tilt.unwrap_or(0.0);
            s
        }
    };
    execute(ctx, &args.model, &settings, args.out.as_deref(), args.json)
}
