//! `simulate`: one closed-loop run of the PID pitch controller — a tilt recovery or the
//! start/accelerate/cruise/decelerate/stop maneuver — as CSV, figures and metrics.

use serde_json::{json, Value};

use super::groups::{controller, one, run};
use super::options::{as_choice, as_number, as_text, field, number, optional_vector, Kind, Opt};
use super::{run_budget, Budget, Job, JobOutput};
use crate::api::{simulate, Maneuver, SimResult, SimSettings};
use crate::error::{Error, Result};
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;

/// The closed-loop run.
pub struct Simulate;

const SCENARIOS: &[&str] = &["tilt", "maneuver"];

/// A maneuver option: sets one of its numbers and the run's length to match (a `t_end` given
/// too, applied after it, wins).
fn maneuver_opt(
    name: &'static str,
    unit: &'static str,
    help: &'static str,
    f: fn(&mut Maneuver) -> &mut f64,
) -> Opt<SimSettings> {
    Opt::new(
        name,
        Kind::Number,
        unit,
        help,
        move |s: &mut SimSettings, v| {
            let x = as_number(name, v)?;
            let m = s.maneuver.as_mut().ok_or_else(|| {
                Error::input(name, "belongs to the maneuver: give scenario = maneuver")
            })?;
            *f(m) = x;
            s.run.t_end = m.default_t_end()?;
            Ok(())
        },
        move |s| json!(*f(&mut s.maneuver.unwrap_or_default())),
    )
}

impl Job for Simulate {
    const NAME: &'static str = "simulate";
    const ALIASES: &'static [&'static str] = &["sim"];
    const FILES: &'static str = "sim.csv, metrics.json and the figures (phi, phi_dot, v_x, x, force; v_y, theta when they move; SVG and PNG)";
    const SUMMARY: &'static str =
        "Closed-loop run of the PID pitch controller (tilt recovery or a maneuver): CSV, \
         figures, metrics";
    type Settings = SimSettings;
    type Output = SimResult;

    fn options() -> Vec<Opt<SimSettings>> {
        let mut opts = vec![
            Opt::new(
                "scenario",
                Kind::Choice,
                "",
                "tilt: recovery from an initial state (by default a forward tilt); maneuver: \
                 from rest, accelerate to v_cruise, cruise, decelerate, stop, through the \
                 velocity loop (whose gains default to 0.08,0.03 then)",
                |s: &mut SimSettings, v| {
                    if as_choice("scenario", v, SCENARIOS)? == "maneuver" {
                        let m = Maneuver::default();
                        s.run.t_end = m.default_t_end()?;
                        s.maneuver = Some(m);
                        s.scenario = "maneuver".into();
                        s.phi0 = 0.0;
                    } else {
                        s.maneuver = None;
                        s.scenario = "tilt".into();
                    }
                    Ok(())
                },
                |s| {
                    json!(if s.maneuver.is_some() {
                        "maneuver"
                    } else {
                        "tilt"
                    })
                },
            )
            .choices(SCENARIOS),
            optional_vector(
                "x0",
                "SI, rad",
                "Initial state in the model's state order (none: at rest with Φ = tilt)",
                field(|s: &mut SimSettings| &mut s.x0),
            ),
            number(
                "tilt",
                "rad",
                "Initial pitch when x0 is not given (0 for the maneuver)",
                field(|s: &mut SimSettings| &mut s.phi0),
            )
            .aliases(&["phi0"])
            .conflicts(&["x0"]),
            number(
                "phi_dot0",
                "rad/s",
                "Initial pitch rate when x0 is not given (a push)",
                field(|s: &mut SimSettings| &mut s.phi_dot0),
            )
            .conflicts(&["x0"]),
        ];
        opts.extend(controller(
            one(|s: &mut SimSettings| &mut s.controller),
            true,
        ));
        opts.push(maneuver_opt(
            "v_cruise",
            "m/s",
            "Maneuver cruise speed",
            |m| &mut m.v_cruise,
        ));
        opts.push(maneuver_opt(
            "ramp",
            "s",
            "Maneuver acceleration and deceleration time",
            |m| &mut m.ramp,
        ));
        opts.push(maneuver_opt("cruise", "s", "Maneuver cruise time", |m| {
            &mut m.cruise
        }));
        opts.extend(run(field(|s: &mut SimSettings| &mut s.run)));
        opts.push(Opt::new(
            "title",
            Kind::Text,
            "",
            "Title of the tables and figures (empty: from the scenario and the gains)",
            |s: &mut SimSettings, v| {
                s.title = as_text("title", v)?.to_string();
                Ok(())
            },
            |s| Value::String(s.title.clone()),
        ));
        opts
    }

    fn validate(s: &SimSettings) -> Result<()> {
        if s.maneuver.is_some()
            && s.controller
                .velocity
                .as_ref()
                .is_some_and(|v| v.reference.value(0.0) != 0.0)
        {
            return Err(Error::input(
                "v_ref",
                "the maneuver sets the velocity reference itself; drop v_ref",
            ));
        }
        s.validate()
    }

    fn budget(_model: &ResolvedModel, s: &SimSettings) -> Result<Budget> {
        Ok(run_budget(&s.run, 1.0))
    }

    fn run(model: &ResolvedModel, s: &SimSettings, progress: &dyn Progress) -> Result<SimResult> {
        Self::validate(s)?;
        simulate(model, s, progress)
    }
}

/// The samples of a run by column: `{"t": […], "phi": […], …}`.
pub(super) fn by_column(columns: &[String], rows: &[Vec<f64>]) -> Value {
    let map: serde_json::Map<String, Value> = columns
        .iter()
        .enumerate()
        .map(|(j, name)| {
            (
                name.clone(),
                json!(rows.iter().map(|r| r[j]).collect::<Vec<_>>()),
            )
        })
        .collect();
    Value::Object(map)
}

impl JobOutput for SimResult {
    fn summary(&self) -> String {
        SimResult::summary(self)
    }
    fn files(&self) -> Result<Files> {
        SimResult::files(self)
    }
    fn csv(&self) -> Option<String> {
        Some(SimResult::csv(self))
    }
    fn series(&self) -> Option<Value> {
        Some(by_column(&self.columns, &self.rows))
    }
}
