//! `tune`: PD/PID gains fitted to a margin specification with Clarabel, with the independent
//! certificate (closed-loop eigenvalues, margins on a dense grid, a nonlinear tilt recovery).

use serde_json::{json, Value};

use super::groups::{gains_json, gains_value};
use super::options::{
    as_choice, as_number, as_vector, field, flag, is_none, number, sub, Kind, Opt,
};
use super::{Budget, Job, JobOutput, Verdict};
use crate::api::{tune_model_with, TuneReport, TuneSettings, TuneVerdict};
use crate::error::{Error, Result};
use crate::linear::PidGains;
use crate::model::ResolvedModel;
use crate::progress::Progress;
use crate::tune::{Objective, Spec};

/// Most requirements of one specification.
pub const MAX_REQUIREMENTS: usize = 16;

/// The gain tuner.
pub struct Tune;

const OBJECTIVES: &[&str] = &["min_gain", "max_integral", "max_proportional"];

impl Job for Tune {
    const NAME: &'static str = "tune";
    const SUMMARY: &'static str =
        "Fit PD/PID gains to a margin specification with Clarabel, with an independent certificate";
    type Settings = TuneSettings;
    type Output = TuneReport;

    fn options() -> Vec<Opt<TuneSettings>> {
        let options = field(|s: &mut TuneSettings| &mut s.options);
        vec![
            Opt::new(
                "spec",
                Kind::Text,
                "",
                "Specification, comma-separated: dpm>=DEG (disk phase margin), dgm>=DB dB or \
                 dgm>=FACTOR (disk gain margin), ms<=PEAK (peak sensitivity), force<=N (peak \
                 force of the certificate's tilt recovery)",
                |s: &mut TuneSettings, v| {
                    s.spec = spec_value(v)?;
                    Ok(())
                },
                |s| json!(s.spec.to_string()),
            ),
            flag(
                "pid",
                "Tune a PID (Ki free) instead of a PD",
                sub(options.clone(), |o| &mut o.pid),
            ),
            Opt::new(
                "objective",
                Kind::Choice,
                "",
                "What to optimise once the spec holds (none: min_gain for a PD, max_integral \
                 for a PID)",
                |s: &mut TuneSettings, v| {
                    s.options.objective = if is_none(v) {
                        None
                    } else {
                        Some(match as_choice("objective", v, OBJECTIVES)? {
                            "min_gain" => Objective::MinGain,
                            "max_integral" => Objective::MaxIntegral,
                            _ => Objective::MaxProportional,
                        })
                    };
                    Ok(())
                },
                |s| match s.options.objective {
                    Some(Objective::MinGain) => json!("min_gain"),
                    Some(Objective::MaxIntegral) => json!("max_integral"),
                    Some(Objective::MaxProportional) => json!("max_proportional"),
                    Some(Objective::Target(_)) | None => Value::Null,
                },
            )
            .choices(OBJECTIVES),
            Opt::new(
                "target",
                Kind::Text,
                "N/rad, N s/rad",
                "Stay as close as possible to these gains: named, kp=…,kd=… (or {kp, kd[, ki]}), or \
                 Kp,Kd in that order (Kp,Ki,Kd with pid)",
                |s: &mut TuneSettings, v| {
                    if is_none(v) {
                        s.options.target = None;
                        return Ok(());
                    }
                    let g = match v {
                        Value::String(text) if !s.options.pid && !text.contains('=') => {
                            let x = as_vector("target", v)?;
                            let [kp, kd] = x[..] else {
                                return Err(Error::input(
                                    "target",
                                    format!("wants Kp,Kd (Kp,Ki,Kd with pid), got `{text}`"),
                                ));
                            };
                            PidGains::pd(kp, kd)
                        }
                        _ => gains_value("target", v, PidGains::default())?,
                    };
                    s.options.target = Some(g);
                    s.options.objective = Some(Objective::Target(g));
                    Ok(())
                },
                |s| s.options.target.as_ref().map_or(Value::Null, gains_json),
            ),
            number(
                "lag",
                "s",
                "First-order actuator lag in the loop",
                sub(sub(options.clone(), |o| &mut o.loop_options), |l| &mut l.lag),
            )
            .aliases(&["actuator_lag"]),
            number(
                "delay",
                "s",
                "Pure delay in the loop",
                sub(sub(options, |o| &mut o.loop_options), |l| &mut l.delay),
            ),
            Opt::new(
                "tilt",
                Kind::Number,
                "rad",
                "Tilt of the certificate's nonlinear recovery (and of a force<= bound)",
                |s: &mut TuneSettings, v| {
                    let t = as_number("tilt", v)?;
                    s.tilt = t;
                    s.options.effort_tilt = t;
                    Ok(())
                },
                |s| json!(s.tilt),
            ),
        ]
    }

    fn validate(s: &TuneSettings) -> Result<()> {
        if !(s.tilt.is_finite() && s.tilt > 0.0) {
            return Err(Error::input(
                "tilt",
                format!("{} must be a finite angle > 0 rad", s.tilt),
            ));
        }
        crate::control::check_tilt("tilt", s.tilt)?;
        if s.spec.requirements.len() > MAX_REQUIREMENTS {
            return Err(Error::input(
                "spec",
                format!(
                    "{} requirements; at most {MAX_REQUIREMENTS}",
                    s.spec.requirements.len()
                ),
            ));
        }
        crate::tune::validate(&s.options).map_err(|e| match e {
            crate::tune::TuneError::Option { what, why } => Error::input(what, why),
            other => other.into(),
        })
    }

    fn budget(_model: &ResolvedModel, s: &TuneSettings) -> Result<Budget> {
        Ok(Budget {
            iterations: s.options.max_iterations as f64,
            frequency_points: s.options.points_per_decade as f64,
            ..Budget::default()
        })
    }

    fn run(model: &ResolvedModel, s: &TuneSettings, p: &dyn Progress) -> Result<TuneReport> {
        tune_model_with(model, s, p)
    }
}

/// A spec from its text (`dpm>=45,ms<=1.6`) or its structured JSON.
pub(super) fn spec_value(v: &Value) -> Result<Spec> {
    Ok(match v {
        Value::String(t) => t.parse()?,
        other => serde_json::from_value(other.clone())
            .map_err(|e| Error::input("spec", e.to_string()))?,
    })
}

impl JobOutput for TuneReport {
    fn summary(&self) -> String {
        TuneReport::summary(self)
    }
    fn verdict(&self) -> Verdict {
        let spec = self.result.spec.to_string();
        match self.verdict {
            TuneVerdict::Met => Verdict::Done,
            TuneVerdict::Infeasible => Verdict::Negative(format!(
                "specification `{spec}` is infeasible for {}: the best gains found reach {:.1} % \
                 of it",
                self.model,
                100.0 * self.result.best_fraction
            )),
            TuneVerdict::NonlinearCheckFailed => Verdict::Negative(format!(
                "the gains meet `{spec}` linearly but fail the nonlinear tilt check"
            )),
            TuneVerdict::NotVerified => Verdict::Negative(format!(
                "tuning ended with status {:?}: no gains verified for `{spec}`",
                self.result.status
            )),
        }
    }
}
