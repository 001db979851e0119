//! `steer-map`: where a steer-torque law balances a two-wheeler, over speed × one steer gain,
//! with the open loop's self-stable band marked, or at one speed over one steer gain × another.

use serde_json::{json, Value};

use super::groups::{rate_filter, steer_gains_json, steer_gains_value};
use super::options::{as_choice, is_none, Kind, Opt};
use super::sweep::{axis, axis_text};
use super::{Budget, Job, JobOutput, Verdict};
use crate::api::{steer_map, SteerMapResult, SteerMapSettings, SteerMapVerdict};
use crate::error::Result;
use crate::linear::SteerGains;
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;
use crate::sweep::Axis;

/// The choices of `against`: none (a map over speed) or a second steer gain.
const AGAINST: [&str; 5] = {
    let k = SteerGains::NAMES;
    ["none", k[0], k[1], k[2], k[3]]
};

/// The speeds: an axis A:B:N, or one speed (a number) for a gain × gain map.
fn speeds(v: &Value) -> Result<Axis> {
    let one = match v {
        Value::Number(x) => x.as_f64(),
        Value::String(t) => t.trim().parse::<f64>().ok(),
        _ => None,
    };
    match one {
        Some(x) => Ok(Axis::point(x)),
        None => axis("speed", v),
    }
}

/// The closed steer loop's stability over speed × gain.
pub struct SteerMap;

impl Job for SteerMap {
    const NAME: &'static str = "steer_map";
    const FILES: &'static str = "steer_map.csv, steer_map.json and map.svg (and PNG)";
    const SUMMARY: &'static str = "Map where a steer-torque law balances a two-wheeler with a \
        steer input (whipple): the closed loop's largest eigenvalue real part over speed × one \
        steer gain, the self-stable band nobody steering marked, or at one speed over one steer gain \
        × another";
    type Settings = SteerMapSettings;
    type Output = SteerMapResult;

    fn options() -> Vec<Opt<SteerMapSettings>> {
        vec![
            Opt::new(
                "speed",
                Kind::Text,
                "m/s",
                "The speeds A:B:N (N values from A to B), or one speed V for a gain × gain \
                 map (--against)",
                |s: &mut SteerMapSettings, v| {
                    s.speed = speeds(v)?;
                    Ok(())
                },
                |s| axis_text(&s.speed),
            )
            .aliases(&["speeds"]),
            Opt::new(
                "gain",
                Kind::Choice,
                "",
                "The gain the map varies (the others are --gains)",
                |s: &mut SteerMapSettings, v| {
                    s.gain = as_choice("gain", v, &SteerGains::NAMES)?.to_string();
                    Ok(())
                },
                |s| json!(s.gain),
            )
            .choices(&SteerGains::NAMES),
            Opt::new(
                "values",
                Kind::Text,
                "N m/rad or N m s/rad",
                "The varied gain's values A:B:N",
                |s: &mut SteerMapSettings, v| {
                    s.values = axis("values", v)?;
                    Ok(())
                },
                |s| axis_text(&s.values),
            ),
            Opt::new(
                "against",
                Kind::Choice,
                "",
                "A second gain for the x axis instead of speed: a gain × gain map at one \
                 --speed (none: the x axis is speed)",
                |s: &mut SteerMapSettings, v| {
                    s.against = if is_none(v) {
                        None
                    } else {
                        Some(as_choice("against", v, &AGAINST[1..])?.to_string())
                    };
                    Ok(())
                },
                |s| json!(s.against.as_deref().unwrap_or("none")),
            )
            .choices(&AGAINST),
            Opt::new(
                "against_values",
                Kind::Text,
                "N m/rad or N m s/rad",
                "The second gain's values A:B:N",
                |s: &mut SteerMapSettings, v| {
                    s.against_values = axis("against_values", v)?;
                    Ok(())
                },
                |s| axis_text(&s.against_values),
            ),
            Opt::new(
                "gains",
                Kind::Text,
                "N m/rad, N m s/rad",
                "The other gains, named k_phi=…,k_delta=…,k_phi_dot=…,k_delta_dot=… (the \
                 others 0; the varied gains' values here are ignored)",
                |s: &mut SteerMapSettings, v| {
                    s.gains = steer_gains_value("gains", v, SteerGains::default())?;
                    Ok(())
                },
                |s| steer_gains_json(&s.gains),
            ),
            rate_filter(|s: &mut SteerMapSettings| &mut s.rate_filter),
        ]
    }

    fn validate(s: &SteerMapSettings) -> Result<()> {
        s.validate()
    }

    fn budget(_model: &ResolvedModel, s: &SteerMapSettings) -> Result<Budget> {
        Ok(Budget {
            points: (s.speed.n * s.values.n * s.against.as_ref().map_or(1, |_| s.against_values.n))
                as f64,
            ..Budget::default()
        })
    }

    fn run(
        model: &ResolvedModel,
        s: &SteerMapSettings,
        p: &dyn Progress,
    ) -> Result<SteerMapResult> {
        steer_map(model, s, p)
    }
}

impl JobOutput for SteerMapResult {
    fn summary(&self) -> String {
        SteerMapResult::summary(self)
    }
    fn files(&self) -> Result<Files> {
        SteerMapResult::files(self)
    }
    fn csv(&self) -> Option<String> {
        Some(SteerMapResult::csv(self))
    }
    fn verdict(&self) -> Verdict {
        match self.verdict {
            SteerMapVerdict::StableSomewhere => Verdict::Done,
            SteerMapVerdict::NowhereStable => Verdict::Negative(match &self.against {
                Some(a) => format!(
                    "no pair of {} and {a} on the map balances {} at {} m/s",
                    self.gain, self.model, self.speeds[0]
                ),
                None => format!(
                    "no value of {} on the map balances {} at any speed of the map",
                    self.gain, self.model
                ),
            }),
        }
    }
}
