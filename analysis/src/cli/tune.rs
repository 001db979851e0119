//! `twv tune`: PD/PID gains fitted to a margin specification with Clarabel, and the independent
//! certificate (closed-loop eigenvalues, margins on a dense grid, a nonlinear tilt simulation).

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use serde::Serialize;
use twv_model::Model;

use super::control_args::parse_gains;
use super::linear::pitch_loop;
use super::model::{dispatch, LoadedModel, ModelArgs, ModelTask};
use super::{Cli, Command};
use crate::linear::{linearize, LoopOptions, OperatingPoint, PidGains};
use crate::tune::{tune, Objective, Spec, TuneOptions, TuneResult, TuneStatus};
use clap::Parser;

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
#[derive(Args, Debug, Clone)]
pub struct TuneArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Specification, comma-separated: dpm>=DEG (disk phase margin), dgm>=DB dB or dgm>=FACTOR
    /// (disk gain margin), ms<=PEAK (peak sensitivity)
    #[arg(long, value_name = "SPEC", default_value = "dpm>=45")]
    pub spec: String,
    /// Stay as close as possible to these gains Kp,Kd (or Kp,Ki,Kd with --pid) [N/rad, N s/rad]
    #[arg(long, value_name = "KP,KD")]
    pub target: Option<String>,
    /// Tune a PID (Ki free) instead of a PD
    #[arg(long)]
    pub pid: bool,
    /// What to optimise once the spec holds [default: min-gain for PD, max-integral for PID]
    #[arg(long, value_enum)]
    pub objective: Option<ObjectiveArg>,
    #[command(flatten)]
    pub loop_options: super::linear::LoopArgs,
    /// Print JSON instead of the summary
    #[arg(long)]
    pub json: bool,
}

/// The tuner's answer with the model it was computed for.
#[derive(Debug, Clone, Serialize)]
pub struct TuneReport {
    pub model: String,
    pub params: String,
    pub result: TuneResult,
    /// The nonlinear check of the certificate's gains: a 0.1 rad forward tilt, 10 s.
    pub tilt_check: Option<TiltCheck>,
}

/// Part of the certificate: the tuned gains on the nonlinear model after a tilt.
#[derive(Debug, Clone, Serialize)]
pub struct TiltCheck {
    pub tilt: f64,
    pub recovered: bool,
    pub settling_time: Option<f64>,
    pub overshoot: Option<f64>,
    pub peak_force: f64,
    pub final_phi: f64,
}

/// Simulate the nonlinear closed loop with `gains` after a 0.1 rad forward tilt (the same code
/// as `twv disturb`).
fn tilt_check(args: &TuneArgs, gains: &PidGains) -> Result<TiltCheck> {
    let mut words: Vec<String> = ["twv", "disturb", "--tilt", "forward"]
        .map(String::from)
        .to_vec();
    words.push("--gains".into());
    words.push(format!("{},{},{}", gains.kp, gains.ki, gains.kd));
    for (flag, value) in [
        ("--model", args.model.model.clone()),
        (
            "--ir",
            args.model.ir.as_ref().map(|p| p.display().to_string()),
        ),
        (
            "--params",
            args.model.params.as_ref().map(|p| p.display().to_string()),
        ),
    ] {
        if let Some(v) = value {
            words.push(flag.into());
            words.push(v);
        }
    }
    let Command::Disturb(d) = Cli::try_parse_from(&words)?.command else {
        bail!("internal: the tilt check did not parse as `twv disturb`");
    };
    let out = super::sim::compute(&super::disturb::experiment(&d)?, &d.model)?;
    let m = &out.metrics;
    Ok(TiltCheck {
        tilt: 0.1,
        recovered: m.phi.settling_time.is_some() && m.final_phi.abs() < 0.002,
        settling_time: m.phi.settling_time,
        overshoot: m.phi.overshoot,
        peak_force: m.peak_force,
        final_phi: m.final_phi,
    })
}

impl TuneArgs {
    fn target(&self) -> Result<Option<PidGains>> {
        let Some(text) = &self.target else {
            return Ok(None);
        };
        if self.pid {
            return Ok(Some(parse_gains("target", text)?));
        }
        let v = super::model::parse_vector("target", text, &["Kp", "Kd"])?;
        Ok(Some(PidGains::pd(v[0], v[1])))
    }

    fn options(&self) -> Result<TuneOptions> {
        let target = self.target()?;
        let objective = match (self.objective, target) {
            (_, Some(t)) => Some(Objective::Target(t)),
            (Some(ObjectiveArg::MinGain), None) => Some(Objective::MinGain),
            (Some(ObjectiveArg::MaxIntegral), None) => Some(Objective::MaxIntegral),
            (Some(ObjectiveArg::MaxProportional), None) => Some(Objective::MaxProportional),
            (None, None) => None,
        };
        Ok(TuneOptions {
            pid: self.pid,
            objective,
            target,
            loop_options: LoopOptions {
                lag: self.loop_options.actuator_lag,
                delay: self.loop_options.delay,
            },
            ..TuneOptions::default()
        })
    }
}

struct Tune<'a>(&'a TuneArgs, Spec);

impl ModelTask for Tune<'_> {
    type Output = TuneReport;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<TuneReport> {
        let lin = linearize(model, &OperatingPoint::Upright, &[0.0; NU])?;
        let lp = pitch_loop(&lin, &model.info(), loaded)?;
        let result = tune(&lp, &self.1, &self.0.options()?)?;
        let tilt_check = match &result.certificate {
            Some(c) if c.analysis.closed_loop.stable => Some(tilt_check(self.0, &c.gains)?),
            _ => None,
        };
        Ok(TuneReport {
            model: loaded.name().to_string(),
            params: loaded.params_origin.clone(),
            result,
            tilt_check,
        })
    }
}

/// Run the tuner (also used by the report).
pub fn fit(args: &TuneArgs) -> Result<TuneReport> {
    let spec: Spec = args.spec.parse()?;
    let loaded = args.model.clone().with_default("vehicle8").load()?;
    dispatch(&loaded, Tune(args, spec))
}

/// A readable summary of the result and its certificate.
pub fn summary(r: &TuneReport) -> String {
    let res = &r.result;
    let mut s = format!(
        "tune {} ({}): {:?} after {} subproblems\n",
        r.model, r.params, res.status, res.iterations
    );
    if let Some(c) = &res.certificate {
        let g = &c.gains;
        let m = &c.analysis.margins;
        s += &format!(
            "  gains Kp = {:.4}, Ki = {:.4}, Kd = {:.4}\n",
            g.kp, g.ki, g.kd
        );
        s += &format!(
            "  certificate (independent check): closed loop {}, disk phase margin {:.2}°, disk gain margin [{:.4}, {:.4}], phase margin {:.2}°, peak |S| {:.3}: spec {}\n",
            if c.analysis.closed_loop.stable { "stable" } else { "UNSTABLE" },
            m.disk.phase_deg,
            m.disk.gain_low,
            m.disk.gain_high,
            m.phase_margin_deg,
            m.peak_sensitivity,
            match (res.status, c.meets_spec) {
                (TuneStatus::Infeasible, _) => "not met (best gains found)",
                (_, true) => "met",
                (_, false) => "NOT met",
            }
        );
    }
    if let Some(t) = &r.tilt_check {
        s += &format!(
            "  nonlinear check: after a {} rad forward tilt Φ {} (2 % settling {}, peak force {:.1} N)\n",
            t.tilt,
            if t.recovered { "recovers" } else { "does NOT recover" },
            t.settling_time.map_or("—".into(), |v| format!("{v:.3} s")),
            t.peak_force
        );
    }
    if res.status == TuneStatus::Infeasible {
        s += &format!(
            "  infeasible: the best gains found reach {:.1} % of the specification (the method is local: no gains found, not a proof that none exist)\n",
            100.0 * res.best_fraction
        );
    }
    s
}

pub fn run(args: &TuneArgs) -> Result<()> {
    let report = fit(args)?;
    super::finish(&report, None, args.json, summary)?;
    if report.tilt_check.as_ref().is_some_and(|t| !t.recovered)
        && report.result.status == TuneStatus::Solved
    {
        bail!("the tuned gains meet the linear specification but do not recover from a 0.1 rad tilt on the nonlinear model");
    }
    match report.result.status {
        TuneStatus::Solved => Ok(()),
        TuneStatus::Infeasible => bail!(
            "specification `{}` is infeasible for {}: best achievable is {:.1} % of it",
            args.spec,
            report.model,
            100.0 * report.result.best_fraction
        ),
        other => bail!(
            "tuning ended with status {other:?}: the certificate does not meet `{}`",
            args.spec
        ),
    }
}
