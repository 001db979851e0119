//! `linearize`: A, B from the generated Jacobians at an equilibrium or a steady motion, the
//! modes, the pitch loop's closed-loop poles and (for a stable loop) its margins, an LQR for
//! comparison, and a steer law's poles and margins at the steer torque.

use serde_json::{json, Value};

use super::groups::{gains, gains_field, steer};
use super::options::{as_vector, field, flag, integer, number, optional_number, sub, Kind, Opt};
use super::{Budget, Job, JobOutput, Verdict};
use crate::api::{analyse, At, LinearReport, LinearSettings, LoopVerdict};
use crate::error::Result;
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;

/// The linear analysis.
pub struct Linearize;

impl Job for Linearize {
    const NAME: &'static str = "linearize";
    const ALIASES: &'static [&'static str] = &["linear", "margins"];
    const FILES: &'static str =
        "linear.json with the pitch loop's frequency response, bode.svg/.png and nyquist.svg/.png";
    const SUMMARY: &'static str =
        "Linearisation at an equilibrium or a steady motion: modes, pitch-loop or steer-loop \
         poles and margins (gain, phase, delay, disk), LQR";
    type Settings = LinearSettings;
    type Output = LinearReport;

    fn options() -> Vec<Opt<LinearSettings>> {
        let mut opts = vec![
            Opt::new(
                "at",
                Kind::Text,
                "SI, rad",
                "Operating point: upright, hanging, or a state V1,V2,…",
                |s: &mut LinearSettings, v| {
                    s.at = match v {
                        Value::String(t) if t.trim() == "upright" => At::Upright,
                        Value::String(t) if t.trim() == "hanging" => At::Hanging,
                        Value::Object(_) => serde_json::from_value(v.clone())
                            .map_err(|e| crate::Error::input("at", e.to_string()))?,
                        _ => At::State(as_vector("at", v)?),
                    };
                    Ok(())
                },
                |s| match &s.at {
                    At::Upright => json!("upright"),
                    At::Hanging => json!("hanging"),
                    At::State(x) => json!(x),
                },
            ),
            optional_number(
                "speed",
                "m/s",
                "Linearise about the model's steady motion at this speed instead of --at (models \
                 whose IR describes one, e.g. whipple)",
                field(|s: &mut LinearSettings| &mut s.speed),
            )
            .conflicts(&["at"]),
            flag(
                "allow_non_equilibrium",
                "Linearise at a point that is not an equilibrium (a frozen-time linearisation)",
                field(|s: &mut LinearSettings| &mut s.allow_non_equilibrium),
            ),
        ];
        // The steered bicycle: its steer loop's poles and margins at the steer torque.
        opts.extend(steer(|s: &mut LinearSettings| &mut s.steer));
        opts.extend(gains(gains_field(|s: &mut LinearSettings| &mut s.gains)));
        let loop_options = field(|s: &mut LinearSettings| &mut s.loop_options);
        opts.push(
            number(
                "lag",
                "s",
                "First-order actuator lag in the loop",
                sub(loop_options.clone(), |o| &mut o.lag),
            )
            .aliases(&["actuator_lag"]),
        );
        opts.push(number(
            "delay",
            "s",
            "Pure delay in the loop",
            sub(loop_options, |o| &mut o.delay),
        ));
        opts.push(number(
            "lqr_q",
            "",
            "LQR state weight (the same for phi, x, w_y, v_x)",
            field(|s: &mut LinearSettings| &mut s.lqr_q),
        ));
        opts.push(number(
            "lqr_r",
            "1/N²",
            "LQR input weight",
            field(|s: &mut LinearSettings| &mut s.lqr_r),
        ));
        opts.push(integer(
            "frequency_points",
            "",
            "Points of the pitch loop's frequency response L(jω) in the result (Bode, Nyquist; \
             0: none)",
            field(|s: &mut LinearSettings| &mut s.frequency_points),
        ));
        opts
    }

    fn validate(s: &LinearSettings) -> Result<()> {
        s.validate()
    }

    fn budget(_model: &ResolvedModel, s: &LinearSettings) -> Result<Budget> {
        Ok(Budget {
            frequency_points: s.frequency_points as f64,
            ..Budget::default()
        })
    }

    fn run(model: &ResolvedModel, s: &LinearSettings, _p: &dyn Progress) -> Result<LinearReport> {
        analyse(model, s)
    }
}

impl JobOutput for LinearReport {
    fn summary(&self) -> String {
        LinearReport::summary(self)
    }
    fn files(&self) -> Result<Files> {
        LinearReport::files(self)
    }
    /// The steer loop's when one was closed, else the pitch loop's; a model with neither (the
    /// unsteered bicycle, Lorenz) has nothing to judge.
    fn verdict(&self) -> Verdict {
        if let Some(st) = &self.steer {
            return if st.loop_poles.stable {
                Verdict::Done
            } else {
                Verdict::Negative(format!(
                    "the steer loop is unstable (a pole at Re = {:.4} 1/s)",
                    st.loop_poles.spectral_abscissa
                ))
            };
        }
        match self.pitch.as_ref().map(|p| p.verdict) {
            Some(LoopVerdict::Stable) | None => Verdict::Done,
            Some(LoopVerdict::Unstable) => Verdict::Negative("the pitch loop is unstable".into()),
            Some(LoopVerdict::NoLoop) => {
                Verdict::Negative("the force does not reach Φ: no pitch loop".into())
            }
        }
    }
}
