//! `disturb`: the study's Figs. 5 and 6 — recovery from a forward or backward tilt under the
//! study's PD: Φ, Φ̇, v_x and x against time, with the metrics.

use serde::{Deserialize, Serialize};
use serde_json::json;

use super::groups::{controller, one, run};
use super::options::{as_choice, field, number, Kind, Opt};
use super::{run_budget, Budget, Job};
use crate::api::{simulate, SimResult, SimSettings};
use crate::control::{ControllerSettings, RunSettings};
use crate::error::{Error, Result};
use crate::model::ResolvedModel;
use crate::progress::Progress;

/// The tilt-disturbance recovery.
pub struct Disturb;

/// Direction of the tilt.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Direction {
    /// Φ0 > 0, the study's Fig. 5 (the vehicle accelerates).
    #[default]
    Forward,
    /// Φ0 < 0, the study's Fig. 6 (the vehicle decelerates).
    Backward,
}

/// A tilt recovery.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct DisturbSettings {
    /// Direction of the tilt. Default forward.
    pub direction: Direction,
    /// Size of the tilt [rad] (> 0; the direction gives the sign). Default 0.1.
    pub tilt: f64,
    /// The controller. Default the study's PD.
    pub controller: ControllerSettings,
    /// Length, sampling, integrator, fall angle. Default 10 s, RK4 at 1 ms.
    pub run: RunSettings,
}

impl Default for DisturbSettings {
    fn default() -> Self {
        Self {
            direction: Direction::Forward,
            tilt: 0.1,
            controller: ControllerSettings::default(),
            run: RunSettings::default(),
        }
    }
}

impl DisturbSettings {
    /// The closed-loop run these settings are.
    pub fn simulation(&self) -> SimSettings {
        let (sign, figure, scenario) = match self.direction {
            Direction::Forward => (1.0, "Fig. 5: forward tilt", "forward tilt"),
            Direction::Backward => (-1.0, "Fig. 6: backward tilt", "backward tilt"),
        };
        SimSettings {
            title: format!("{figure} of {} rad", self.tilt),
            scenario: scenario.into(),
            controller: self.controller.clone(),
            run: self.run,
            phi0: sign * self.tilt,
            ..SimSettings::default()
        }
    }
}

const DIRECTIONS: &[&str] = &["forward", "backward"];

impl Job for Disturb {
    const NAME: &'static str = "disturb";
    const FILES: &'static str = "sim.csv, metrics.json and the figures (SVG and PNG)";
    const SUMMARY: &'static str =
        "Recovery from a forward or backward tilt under the study's PD (its Figs. 5 and 6)";
    type Settings = DisturbSettings;
    type Output = SimResult;

    fn options() -> Vec<Opt<DisturbSettings>> {
        let mut opts = vec![
            Opt::new(
                "direction",
                Kind::Choice,
                "",
                "forward: Φ0 > 0, the study's Fig. 5; backward: Φ0 < 0, its Fig. 6",
                |s: &mut DisturbSettings, v| {
                    s.direction = match as_choice("direction", v, DIRECTIONS)? {
                        "forward" => Direction::Forward,
                        _ => Direction::Backward,
                    };
                    Ok(())
                },
                |s| json!(s.direction),
            )
            .choices(DIRECTIONS),
            number(
                "tilt",
                "rad",
                "Size of the tilt (the direction gives its sign)",
                field(|s: &mut DisturbSettings| &mut s.tilt),
            )
            .aliases(&["magnitude"]),
        ];
        opts.extend(controller(
            one(|s: &mut DisturbSettings| &mut s.controller),
            true,
        ));
        opts.extend(run(field(|s: &mut DisturbSettings| &mut s.run)));
        opts
    }

    fn validate(s: &DisturbSettings) -> Result<()> {
        if !(s.tilt.is_finite() && s.tilt > 0.0) {
            return Err(Error::input(
                "tilt",
                format!(
                    "{}: must be a finite angle > 0 rad (direction gives the sign)",
                    s.tilt
                ),
            ));
        }
        s.simulation().validate()
    }

    fn budget(_model: &ResolvedModel, s: &DisturbSettings) -> Result<Budget> {
        Ok(run_budget(&s.run, 1.0))
    }

    fn run(
        model: &ResolvedModel,
        s: &DisturbSettings,
        progress: &dyn Progress,
    ) -> Result<SimResult> {
        Self::validate(s)?;
        simulate(model, &s.simulation(), progress)
    }
}
