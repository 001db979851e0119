//! `steer`: balancing a two-wheeler by steering — at each speed of a range, a steer-torque law
//! tuned to a margin spec (a gain schedule) or given, its certificate at the steer torque, and
//! the nonlinear model steered by it from a push.

use serde_json::{json, Value};

use super::groups::{rate_filter, steer_gains_json, steer_gains_value};
use super::options::{field, integer, is_none, number, optional_number, sub, Kind, Opt};
use super::steady::speeds;
use super::tune::spec_value;
use super::{Budget, Job, JobOutput, Verdict};
use crate::api::{steer, SteerLoopSettings, SteerResult, SteerVerdict};
use crate::error::Result;
use crate::linear::SteerGains;
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;

/// The steer loop over speed.
pub struct Steer;

impl Job for Steer {
    const NAME: &'static str = "steer";
    const FILES: &'static str =
        "steer.csv, steer.json, gains.svg, abscissa.svg and margins.svg (and PNGs)";
    const SUMMARY: &'static str = "Balance a two-wheeler with a steer input (whipple) by \
        steering: a Clarabel-tuned gain schedule over speed (or given gains), its certificate \
        at the steer torque, and the nonlinear recovery from a push at each speed";
    type Settings = SteerLoopSettings;
    type Output = SteerResult;

    fn options() -> Vec<Opt<SteerLoopSettings>> {
        let options = field(|s: &mut SteerLoopSettings| &mut s.options);
        vec![
            Opt::new(
                "speed",
                Kind::Text,
                "m/s",
                "The speeds LO:HI:STEP (or [lo, hi, step]), or one speed",
                |s: &mut SteerLoopSettings, v| {
                    let one = match v {
                        Value::Number(n) => n.as_f64(),
                        Value::String(t) if !t.contains(':') => t.trim().parse().ok(),
                        _ => None,
                    };
                    (s.lo, s.hi, s.step) = match one {
                        Some(v) => (v, v, 1.0),
                        None => speeds(v)?,
                    };
                    Ok(())
                },
                |s| {
                    if s.lo == s.hi {
                        json!(format!("{}", s.lo))
                    } else {
                        json!(format!("{}:{}:{}", s.lo, s.hi, s.step))
                    }
                },
            )
            .aliases(&["speeds"]),
            Opt::new(
                "spec",
                Kind::Text,
                "",
                "The margins every speed must have at the steer torque, comma-separated: \
                 dpm>=DEG (disk phase margin), dgm>=DB dB or dgm>=FACTOR (disk gain margin), \
                 ms<=PEAK (peak sensitivity)",
                |s: &mut SteerLoopSettings, v| {
                    s.spec = spec_value(v)?;
                    Ok(())
                },
                |s| json!(s.spec.to_string()),
            ),
            Opt::new(
                "gains",
                Kind::Text,
                "N m/rad, N m s/rad",
                "Check these gains at every speed instead of tuning a schedule: named \
                 k_phi=…,k_delta=…,k_phi_dot=…,k_delta_dot=… (the others 0)",
                |s: &mut SteerLoopSettings, v| {
                    s.gains = if is_none(v) {
                        None
                    } else {
                        Some(steer_gains_value("gains", v, SteerGains::default())?)
                    };
                    Ok(())
                },
                |s| s.gains.as_ref().map_or(Value::Null, steer_gains_json),
            ),
            optional_number(
                "saturation",
                "N m",
                "Steer-torque limit |T_delta| ≤ T_max in the nonlinear check (none: unlimited)",
                field(|s: &mut SteerLoopSettings| &mut s.saturation),
            ),
            rate_filter(|s: &mut SteerLoopSettings| &mut s.rate_filter),
            number(
                "push",
                "rad/s",
                "The nonlinear check's push: lean rate added to the steady motion",
                field(|s: &mut SteerLoopSettings| &mut s.push),
            ),
            number(
                "check_time",
                "s",
                "Length of the nonlinear check",
                field(|s: &mut SteerLoopSettings| &mut s.check_time),
            ),
            number(
                "max_gain_factor",
                "",
                "Bound on each gain as a multiple of its scale (keeps the subproblems bounded)",
                sub(options.clone(), |o| &mut o.max_gain_factor),
            ),
            integer(
                "points_per_decade",
                "",
                "Design-grid density (doubled up to three times when the check fails)",
                sub(options.clone(), |o| &mut o.points_per_decade),
            ),
            integer(
                "max_iterations",
                "",
                "Convex subproblems per phase",
                sub(options.clone(), |o| &mut o.max_iterations),
            ),
            number(
                "lqr_weight",
                "1/(N m)²",
                "R of the LQR design (Q = I on lean, steer and their rates) the gains stay as \
                 close to as the spec allows: larger, gentler steering",
                sub(options, |o| &mut o.lqr_weight),
            ),
        ]
    }

    fn validate(s: &SteerLoopSettings) -> Result<()> {
        s.validate()
    }

    fn budget(_model: &ResolvedModel, s: &SteerLoopSettings) -> Result<Budget> {
        let n = s.speeds().len() as f64;
        Ok(Budget {
            points: n,
            horizon: s.check_time,
            steps: n * s.check_time / 1e-3,
            iterations: s.options.max_iterations as f64,
            frequency_points: s.options.points_per_decade as f64,
            ..Budget::default()
        })
    }

    fn run(model: &ResolvedModel, s: &SteerLoopSettings, p: &dyn Progress) -> Result<SteerResult> {
        steer(model, s, p)
    }
}

impl JobOutput for SteerResult {
    fn summary(&self) -> String {
        SteerResult::summary(self)
    }
    fn files(&self) -> Result<Files> {
        SteerResult::files(self)
    }
    fn csv(&self) -> Option<String> {
        Some(SteerResult::csv(self))
    }
    fn verdict(&self) -> Verdict {
        match self.verdict {
            SteerVerdict::Met => Verdict::Done,
            SteerVerdict::NotMet => {
                let missed: Vec<String> = self
                    .points
                    .iter()
                    .filter(|p| !p.met)
                    .map(|p| format!("{}", p.speed))
                    .collect();
                Verdict::Negative(format!(
                    "`{}` is not met at {} m/s",
                    self.spec,
                    missed.join(", ")
                ))
            }
        }
    }
}
