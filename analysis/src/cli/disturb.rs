//! `twv disturb`: the study's Figs. 5 and 6 — recovery from a forward or backward tilt under
//! the study's PD: Φ, Φ̇, v_x and x against time, with the metrics.

use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, ValueEnum};

use super::control_args::{parse_gains, ControllerArgs, RunArgs};
use super::model::ModelArgs;
use super::sim::{execute, Experiment};
use crate::control::scenario::Tilt;
use crate::control::STUDY_PD;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum TiltArg {
    /// Φ0 > 0, the study's Fig. 5 (the vehicle accelerates)
    Forward,
    /// Φ0 < 0, the study's Fig. 6 (the vehicle decelerates)
    Backward,
}

/// Tilt-disturbance recovery (the study's Figs. 5 and 6).
#[derive(Args, Debug)]
pub struct DisturbArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Direction of the tilt
    #[arg(long, value_enum)]
    pub tilt: TiltArg,
    /// Size of the tilt [rad] [default: 0.1]
    #[arg(long, value_name = "RAD", allow_hyphen_values = true)]
    pub magnitude: Option<f64>,
    /// PID gains Kp,Ki,Kd [N/rad, N/(rad s), N s/rad] [default: 3860,0,1980, the study's PD]
    #[arg(long, value_name = "KP,KI,KD")]
    pub gains: Option<String>,
    #[command(flatten)]
    pub controller: ControllerArgs,
    #[command(flatten)]
    pub run: RunArgs,
    /// Write sim.csv, metrics.json and the figures (phi, phi_dot, v_x, x, force) into this folder
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the result as JSON on stdout
    #[arg(long)]
    pub json: bool,
}

/// The experiment these arguments describe (also used by the report).
pub fn experiment(args: &DisturbArgs) -> Result<Experiment> {
    let gains = match &args.gains {
        Some(text) => parse_gains("gains", text)?,
        None => STUDY_PD,
    };
    let (tilt, figure) = match args.tilt {
        TiltArg::Forward => (Tilt::Forward, "Fig. 5: forward tilt"),
        TiltArg::Backward => (Tilt::Backward, "Fig. 6: backward tilt"),
    };
    let magnitude = args.magnitude.unwrap_or(0.1);
    if !(magnitude.is_finite() && magnitude > 0.0) {
        anyhow::bail!("--magnitude {magnitude}: must be a finite angle > 0 rad");
    }
    let experiment = Experiment {
        title: format!("{figure} of {magnitude} rad"),
        scenario: match tilt {
            Tilt::Forward => "forward tilt",
            Tilt::Backward => "backward tilt",
        },
        controller: args.controller.settings(gains, None, None)?,
        run: args.run.settings(10.0)?,
        x0: None,
        phi0: tilt.phi0(magnitude),
    };
    Ok(experiment)
}

pub fn run(args: &DisturbArgs) -> Result<()> {
    execute(
        &experiment(args)?,
        &args.model,
        args.out.as_deref(),
        args.json,
    )
}
