//! `ride`: a run under constant inputs, from a state or from a steady motion at a speed with
//! some states pushed: the bicycle nobody steers, or steered by a steer-torque law.

use serde_json::{json, Value};

use super::groups::{run, steer};
use super::options::{as_named, as_text, field, optional_number, optional_vector, Kind, Opt};
use super::simulate::by_column;
use super::{run_budget, Budget, Job, JobOutput};
use crate::api::{ride, RideResult, RideSettings};
use crate::error::Result;
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;

/// The run under constant inputs (and an optional steer law).
pub struct Ride;

impl Job for Ride {
    const NAME: &'static str = "ride";
    const FILES: &'static str = "ride.csv, ride.json and a figure per moving state (SVG and PNG)";
    const SUMMARY: &'static str =
        "Run under constant inputs, from a state or a steady motion at a speed (the bicycle \
         nobody steers, or steered with steer_gains): CSV, figures, whether the push died out";
    type Settings = RideSettings;
    type Output = RideResult;

    fn options() -> Vec<Opt<RideSettings>> {
        let mut opts = vec![
            optional_vector(
                "x0",
                "SI, rad",
                "Initial state in the model's state order (none: the steady motion at speed, or \
                 rest)",
                field(|s: &mut RideSettings| &mut s.x0),
            ),
            optional_number(
                "speed",
                "m/s",
                "Start from the model's steady motion at this speed (models whose IR describes \
                 one, e.g. whipple)",
                field(|s: &mut RideSettings| &mut s.speed),
            )
            .conflicts(&["x0"]),
            Opt::new(
                "perturb",
                Kind::Text,
                "SI, rad",
                "Pushes added to the initial state, NAME=VALUE,… (e.g. w_phi=0.5)",
                |s: &mut RideSettings, v| {
                    s.perturb = as_named("perturb", v)?;
                    Ok(())
                },
                |s| json!(s.perturb),
            ),
            optional_vector(
                "u",
                "N, N m",
                "Constant input, in the model's input order (none: zeros)",
                field(|s: &mut RideSettings| &mut s.u),
            ),
            Opt::new(
                "watch",
                Kind::Text,
                "",
                "The state whose decay is judged and whose size past fall_angle ends the run",
                |s: &mut RideSettings, v| {
                    s.watch = as_text("watch", v)?.to_string();
                    Ok(())
                },
                |s| Value::String(s.watch.clone()),
            ),
        ];
        opts.extend(steer(|s: &mut RideSettings| &mut s.steer));
        opts.extend(run(field(|s: &mut RideSettings| &mut s.run)));
        opts
    }

    fn validate(s: &RideSettings) -> Result<()> {
        s.validate()
    }

    fn budget(_model: &ResolvedModel, s: &RideSettings) -> Result<Budget> {
        Ok(run_budget(&s.run, 1.0))
    }

    fn run(model: &ResolvedModel, s: &RideSettings, progress: &dyn Progress) -> Result<RideResult> {
        ride(model, s, progress)
    }
}

impl JobOutput for RideResult {
    fn summary(&self) -> String {
        RideResult::summary(self)
    }
    fn files(&self) -> Result<Files> {
        RideResult::files(self)
    }
    fn csv(&self) -> Option<String> {
        Some(RideResult::csv(self))
    }
    fn series(&self) -> Option<Value> {
        Some(by_column(&self.columns, &self.rows))
    }
}
