//! `twv tune`: PD/PID gains fitted to a margin specification with Clarabel, and the independent
//! certificate (closed-loop eigenvalues, margins on a dense grid, a nonlinear tilt recovery).

use anyhow::Result;
use clap::{Args, ValueEnum};
use twv_analysis::api::{tune_model, TuneSettings, TuneVerdict};
use twv_analysis::linear::PidGains;
use twv_analysis::tune::{Objective, Spec, TuneOptions};

use super::linear::LoopArgs;
use crate::common::{parse_gains, parse_vector, print_result, Context, ModelArgs, Outcome};

/// What the tuner optimises.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ObjectiveArg {
    /// Smallest gains that meet the spec (default for PD)
    MinGain,
    /// Largest integral gain (default for PID)
    MaxIntegral,
    /// Largest proportional gain
    MaxProportional,
}

/// Fit pitch-loop gains to a margin specification (Hast, Åström, Bernhardsson & Boyd 2013).
/// Exit status 3 when the specification is not met (infeasible, unverified, or the nonlinear
/// check fails).
#[derive(Args, Debug, Clone)]
#[command(allow_negative_numbers = true)]
pub struct TuneArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Specification, comma-separated: dpm>=DEG (disk phase margin), dgm>=DB dB or
    /// dgm>=FACTOR (disk gain margin), ms<=PEAK (peak sensitivity), force<=N (peak force of
    /// the certificate's tilt recovery)
    #[arg(long, value_name = "SPEC", default_value = "dpm>=45")]
    pub spec: String,
    /// Stay as close as possible to these gains Kp,Kd (or Kp,Ki,Kd with --pid) [N/rad, N s/rad]
    #[arg(long, value_name = "KP,KD", allow_hyphen_values = true)]
    pub target: Option<String>,
    /// Tune a PID (Ki free) instead of a PD
    #[arg(long)]
    pub pid: bool,
    /// What to optimise once the spec holds [default: min-gain for PD, max-integral for PID]
    #[arg(long, value_enum)]
    pub objective: Option<ObjectiveArg>,
    #[command(flatten)]
    pub loop_options: LoopArgs,
    /// Tilt of the certificate's nonlinear recovery (and of a force<= bound) [rad]
    #[arg(long, value_name = "RAD", default_value_t = 0.1)]
    pub tilt: f64,
    /// Print JSON instead of the summary
    #[arg(long)]
    pub json: bool,
}

impl TuneArgs {
    fn target(&self) -> Result<Option<PidGains>> {
        let Some(text) = &self.target else {
            return Ok(None);
        };
        if self.pid {
            return Ok(Some(parse_gains("target", text)?));
        }
        let v = parse_vector("target", text)?;
        let [kp, kd] = v[..] else {
            anyhow::bail!("--target wants Kp, Kd (Kp, Ki, Kd with --pid), got `{text}`");
        };
        Ok(Some(PidGains::pd(kp, kd)))
    }
}

pub fn run(args: &TuneArgs, ctx: &Context) -> Result<Outcome> {
    let model = args.model.resolve(ctx)?;
    let spec: Spec = args.spec.parse()?;
    let target = args.target()?;
    let objective = match (args.objective, target) {
        (_, Some(t)) => Some(Objective::Target(t)),
        (Some(ObjectiveArg::MinGain), None) => Some(Objective::MinGain),
        (Some(ObjectiveArg::MaxIntegral), None) => Some(Objective::MaxIntegral),
        (Some(ObjectiveArg::MaxProportional), None) => Some(Objective::MaxProportional),
        (None, None) => None,
    };
    let settings = TuneSettings {
        spec,
        options: TuneOptions {
            pid: args.pid,
            objective,
            target,
            loop_options: args.loop_options.options(),
            ..TuneOptions::default()
        },
        tilt: args.tilt,
    };
    let report = tune_model(&model, &settings)?;
    print_result(&report, args.json, || report.summary())?;
    Ok(match report.verdict {
        TuneVerdict::Met => Outcome::Done,
        TuneVerdict::Infeasible => Outcome::Negative(format!(
            "specification `{}` is infeasible for {}: the best gains found reach {:.1} % of it",
            args.spec,
            report.model,
            100.0 * report.result.best_fraction
        )),
        TuneVerdict::NonlinearCheckFailed => Outcome::Negative(format!(
            "the gains meet `{}` linearly but fail the nonlinear tilt check",
            args.spec
        )),
        TuneVerdict::NotVerified => Outcome::Negative(format!(
            "tuning ended with status {:?}: no gains verified for `{}`",
            report.result.status, args.spec
        )),
    })
}
