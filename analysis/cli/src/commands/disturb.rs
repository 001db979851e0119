//! `twv disturb`: the study's Figs. 5 and 6 — recovery from a forward or backward tilt under
//! the study's PD: Φ, Φ̇, v_x and x against time, with the metrics.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use twv_analysis::api::SimSettings;
use twv_analysis::control::scenario::Tilt;
use twv_analysis::control::STUDY_PD;

use super::sim::execute;
use crate::common::{parse_gains, Context, ControllerArgs, ModelArgs, Outcome, RunArgs};

/// Direction of the tilt.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Direction {
    /// Φ0 > 0, the study's Fig. 5 (the vehicle accelerates)
    Forward,
    /// Φ0 < 0, the study's Fig. 6 (the vehicle decelerates)
    Backward,
}

/// Tilt-disturbance recovery (the study's Figs. 5 and 6).
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct DisturbArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Direction of the tilt
    #[arg(long, value_enum)]
    pub direction: Direction,
    /// Size of the tilt [rad] [default: 0.1]
    #[arg(long, value_name = "RAD", alias = "magnitude")]
    pub tilt: Option<f64>,
    /// PID gains Kp,Ki,Kd [N/rad, N/(rad s), N s/rad] [default: 3860,0,1980, the study's PD]
    #[arg(long, value_name = "KP,KI,KD", allow_hyphen_values = true)]
    pub gains: Option<String>,
    #[command(flatten)]
    pub controller: ControllerArgs,
    #[command(flatten)]
    pub run: RunArgs,
    /// Write sim.csv, metrics.json and the figures into this folder
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the result as JSON on stdout
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &DisturbArgs, ctx: &Context) -> Result<Outcome> {
    let gains = match &args.gains {
        Some(text) => parse_gains("gains", text)?,
        None => STUDY_PD,
    };
    let (tilt, figure, scenario) = match args.direction {
        Direction::Forward => (Tilt::Forward, "Fig. 5: forward tilt", "forward tilt"),
        Direction::Backward => (Tilt::Backward, "Fig. 6: backward tilt", "backward tilt"),
    };
    let magnitude = args.tilt.unwrap_or(0.1);
    if !(magnitude.is_finite() && magnitude > 0.0) {
        bail!("--tilt {magnitude}: must be a finite angle > 0 rad (--direction gives the sign)");
    }
    let settings = SimSettings {
        title: format!("{figure} of {magnitude} rad"),
        scenario: scenario.into(),
        controller: args.controller.settings(gains, None)?,
        run: args.run.settings(10.0),
        x0: None,
        phi0: tilt.phi0(magnitude),
    };
    execute(ctx, &args.model, &settings, args.out.as_deref(), args.json)
}
