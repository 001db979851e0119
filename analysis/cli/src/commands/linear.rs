//! `twv linear`: A, B from the generated Jacobians, the modes, the pitch loop's closed-loop
//! poles and — only for a stable loop — its margins, and an LQR design for comparison.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use twv_analysis::api::{
    analyse, steady_motion, At, LinearSettings, LoopVerdict, SteadySettings, SteadyVerdict,
};
use twv_analysis::linear::LoopOptions;

use crate::common::{
    parse_gains, parse_vector, print_result, write_files, Context, ModelArgs, Outcome,
};

/// What sits between the controller and the vehicle (shared by `linear` and `tune`).
#[derive(Args, Debug, Clone)]
pub struct LoopArgs {
    /// First-order actuator lag in the loop [s]
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    pub actuator_lag: f64,
    /// Pure delay in the loop [s]
    #[arg(long, value_name = "S", default_value_t = 0.0)]
    pub delay: f64,
}

impl LoopArgs {
    /// The loop options.
    pub fn options(&self) -> LoopOptions {
        LoopOptions {
            lag: self.actuator_lag,
            delay: self.delay,
        }
    }
}

/// Linear analysis at an equilibrium: modes, pitch-loop margins, LQR. Exit status 3 when the
/// pitch loop is unstable (its margins are then undefined) or there is no loop.
#[derive(Args, Debug, Clone)]
#[command(allow_negative_numbers = true)]
pub struct LinearArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Operating point: upright, hanging, or a state V1,V2,... (SI units, rad)
    #[arg(
        long,
        value_name = "POINT",
        default_value = "upright",
        allow_hyphen_values = true
    )]
    pub at: String,
    /// Linearise at a point that is not an equilibrium (a frozen-time linearisation)
    #[arg(long)]
    pub allow_non_equilibrium: bool,
    /// Pitch PID gains Kp,Ki,Kd [N/rad, N/(rad s), N s/rad]
    #[arg(
        long,
        value_name = "KP,KI,KD",
        default_value = "3860,0,1980",
        allow_hyphen_values = true
    )]
    pub gains: String,
    #[command(flatten)]
    pub loop_options: LoopArgs,
    /// LQR state weight (the same for phi, x, w_y, v_x)
    #[arg(long, value_name = "Q", default_value_t = 1.0)]
    pub lqr_q: f64,
    /// LQR input weight [1/N²]
    #[arg(long, value_name = "R", default_value_t = 1e-4)]
    pub lqr_r: f64,
    /// Instead: the eigenvalues of the steady motion's modes against speed, LO:HI:STEP [m/s]
    /// (models whose IR describes straight running, e.g. whipple); exit status 3 when it is
    /// nowhere self-stable
    #[arg(long, value_name = "LO:HI:STEP")]
    pub speed: Option<String>,
    /// Write the results here: linear.json with the pitch loop's frequency response and its
    /// Bode and Nyquist figures (bode.svg/.png, nyquist.svg/.png); with --speed
    /// eigenvalues.csv, eigenvalues.svg/.png and steady.json
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Points of the frequency response written with --out (log-spaced, two decades either
    /// side of the loop's own frequencies)
    #[arg(long, value_name = "N", default_value_t = 400)]
    pub frequency_points: usize,
    /// Print JSON instead of the summary
    #[arg(long)]
    pub json: bool,
}

/// `LO:HI:STEP` into the sweep's settings.
fn speed_grid(text: &str) -> Result<SteadySettings> {
    let parts: Vec<&str> = text.split(':').collect();
    let [lo, hi, step] = parts[..] else {
        bail!("--speed {text}: expected LO:HI:STEP, e.g. 0:10:0.01");
    };
    let number = |what: &str, s: &str| -> Result<f64> {
        s.trim()
            .parse::<f64>()
            .map_err(|_| anyhow::anyhow!("--speed {text}: {what} `{s}` is not a number"))
    };
    Ok(SteadySettings {
        lo: number("LO", lo)?,
        hi: number("HI", hi)?,
        step: number("STEP", step)?,
        ..SteadySettings::default()
    })
}

fn run_speed(args: &LinearArgs, grid: &str, ctx: &Context) -> Result<Outcome> {
    let model = args.model.resolve(ctx)?;
    let result = steady_motion(&model, &speed_grid(grid)?)?;
    if let Some(dir) = &args.out {
        write_files(ctx, dir, &result.files()?)?;
    }
    print_result(&result, args.json, || result.summary())?;
    Ok(match result.verdict {
        SteadyVerdict::SelfStable => Outcome::Done,
        SteadyVerdict::NowhereStable => Outcome::Negative(format!(
            "{} is nowhere self-stable on the grid",
            result.model
        )),
    })
}

pub fn run(args: &LinearArgs, ctx: &Context) -> Result<Outcome> {
    if let Some(grid) = &args.speed {
        return run_speed(args, grid, ctx);
    }
    let model = args.model.resolve(ctx)?;
    let at = match args.at.as_str() {
        "upright" => At::Upright,
        "hanging" => At::Hanging,
        other => At::State(parse_vector("at", other)?),
    };
    let settings = LinearSettings {
        at,
        gains: parse_gains("gains", &args.gains)?,
        loop_options: args.loop_options.options(),
        lqr_q: args.lqr_q,
        lqr_r: args.lqr_r,
        allow_non_equilibrium: args.allow_non_equilibrium,
        frequency_points: if args.out.is_some() {
            args.frequency_points
        } else {
            0
        },
    };
    let report = analyse(&model, &settings)?;
    if let Some(dir) = &args.out {
        write_files(ctx, dir, &report.files()?)?;
    }
    print_result(&report, args.json, || report.summary())?;
    Ok(match report.pitch.verdict {
        LoopVerdict::Stable => Outcome::Done,
        LoopVerdict::Unstable => Outcome::Negative("the pitch loop is unstable".into()),
        LoopVerdict::NoLoop => {
            Outcome::Negative("the force does not reach Φ: no pitch loop".into())
        }
    })
}
