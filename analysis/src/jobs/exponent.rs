//! `exponent`: the largest Lyapunov exponent of the closed pitch loop after a tilt, over a short
//! horizon, with its verdict: the map's `max-lyapunov` metric at the one point of the current
//! gains (the page shows it beside the response as the gains move).

use serde::{Deserialize, Serialize};

use super::groups::{controller, one};
use super::options::{field, integer, number, sub, Opt};
use super::{Budget, Job, JobOutput, Verdict};
use crate::api::{sweep, SweepSettings};
use crate::control::ControllerSettings;
use crate::error::{Error, Result};
use crate::model::ResolvedModel;
use crate::progress::Progress;
use crate::sweep::{Axis, Grid, Metric, MetricSettings, PointResult, Status};

/// The one-point exponent.
pub struct Exponent;

/// The controller (its gains are the point), the tilt and the metric's sampling.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExponentSettings {
    /// The controller. Default the study's PD.
    pub controller: ControllerSettings,
    /// Initial pitch from rest [rad]. Default 0.1.
    pub tilt: f64,
    /// The metric's sampling. Default RK4 at 1 ms, 30 intervals of 0.1 s after 0.5 s (a short
    /// horizon: an answer while the gains move).
    pub metric_settings: MetricSettings,
}

impl Default for ExponentSettings {
    fn default() -> Self {
        Self {
            controller: ControllerSettings::default(),
            tilt: 0.1,
            metric_settings: MetricSettings {
                iterations: 30,
                transient: 0.5,
                ..MetricSettings::default()
            },
        }
    }
}

/// What the short-horizon exponent says.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ExponentVerdict {
    /// λ1 < −resolution: nearby trajectories converge.
    Stable,
    /// λ1 > +resolution: they diverge.
    Unstable,
    /// |λ1| ≤ resolution: the horizon is too short to tell.
    Undecided,
    /// |Φ| passed the fall angle.
    Fell,
    /// No value (the integration blew up or failed).
    Failed,
}

/// The exponent with its verdict: `resolution` is one e-fold over the averaging time
/// (1 / (t_sample × iterations)), the smallest rate such a run can tell from zero.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoopExponent {
    pub point: PointResult,
    /// The smallest |λ1| the run can tell from zero [1/s].
    pub resolution: f64,
    pub verdict: ExponentVerdict,
}

/// The verdict of `point` at `resolution`.
pub fn exponent_verdict(point: &PointResult, resolution: f64) -> ExponentVerdict {
    match (point.status, point.value) {
        (Status::Fell, _) => ExponentVerdict::Fell,
        (Status::Ok, Some(v)) if v < -resolution => ExponentVerdict::Stable,
        (Status::Ok, Some(v)) if v > resolution => ExponentVerdict::Unstable,
        (Status::Ok, Some(_)) => ExponentVerdict::Undecided,
        _ => ExponentVerdict::Failed,
    }
}

impl ExponentSettings {
    /// The one-point map these settings are.
    fn map(&self) -> SweepSettings {
        let g = self.controller.pitch.gains;
        SweepSettings {
            grid: Grid {
                kp: Axis::point(g.kp),
                kd: Axis::point(g.kd),
                ki: (g.ki != 0.0).then(|| Axis::point(g.ki)),
                params: Vec::new(),
            },
            metric: Metric::MaxLyapunov,
            x0: None,
            tilt: self.tilt,
            controller: self.controller.clone(),
            metric_settings: self.metric_settings,
        }
    }
}

impl Job for Exponent {
    const NAME: &'static str = "exponent";
    const SUMMARY: &'static str =
        "Largest Lyapunov exponent of the closed pitch loop after a tilt, over a short horizon, \
         with its verdict (stable, unstable or undecided at the horizon's resolution)";
    type Settings = ExponentSettings;
    type Output = LoopExponent;

    fn options() -> Vec<Opt<ExponentSettings>> {
        let mut opts = controller(one(|s: &mut ExponentSettings| &mut s.controller), true);
        opts.push(number(
            "tilt",
            "rad",
            "Initial pitch, from rest",
            field(|s: &mut ExponentSettings| &mut s.tilt),
        ));
        let m = field(|s: &mut ExponentSettings| &mut s.metric_settings);
        opts.push(number("h", "s", "RK4 step", sub(m.clone(), |m| &mut m.h)));
        opts.push(
            number(
                "qr_interval",
                "s",
                "Re-orthonormalisation interval T",
                sub(m.clone(), |m| &mut m.t_sample),
            )
            .aliases(&["t_sample"]),
        );
        opts.push(integer(
            "iterations",
            "",
            "Intervals K averaged over",
            sub(m.clone(), |m| &mut m.iterations),
        ));
        opts.push(number(
            "transient",
            "s",
            "Time discarded before averaging",
            sub(m, |m| &mut m.transient),
        ));
        opts
    }

    fn validate(s: &ExponentSettings) -> Result<()> {
        s.controller.validate()?;
        s.metric_settings.validate()?;
        crate::control::check_tilt("tilt", s.tilt)?;
        Ok(())
    }

    fn budget(model: &ResolvedModel, s: &ExponentSettings) -> Result<Budget> {
        super::Sweep::budget(model, &s.map())
    }

    fn run(
        model: &ResolvedModel,
        s: &ExponentSettings,
        progress: &dyn Progress,
    ) -> Result<LoopExponent> {
        Self::validate(s)?;
        let point = sweep(model, &s.map(), progress)?
            .first()
            .copied()
            .ok_or_else(|| Error::input("settings", "the one-point map has no point"))?;
        let m = &s.metric_settings;
        let resolution = 1.0 / (m.t_sample * m.iterations as f64);
        Ok(LoopExponent {
            point,
            resolution,
            verdict: exponent_verdict(&point, resolution),
        })
    }
}

impl JobOutput for LoopExponent {
    fn summary(&self) -> String {
        let p = &self.point;
        let value = p
            .value
            .map_or("no value".to_string(), |v| format!("λ1 = {v:+.4} 1/s"));
        format!(
            "closed loop Kp {} Ki {} Kd {}: {value} ({:?}); resolution ±{:.4} 1/s: {}\n",
            p.kp,
            p.ki,
            p.kd,
            p.status,
            self.resolution,
            match self.verdict {
                ExponentVerdict::Stable => "stable (nearby trajectories converge)",
                ExponentVerdict::Unstable => "UNSTABLE (nearby trajectories diverge)",
                ExponentVerdict::Undecided => "undecided (|λ1| within the resolution)",
                ExponentVerdict::Fell => "FELL",
                ExponentVerdict::Failed => "FAILED (no value)",
            }
        )
    }
    fn verdict(&self) -> Verdict {
        match self.verdict {
            ExponentVerdict::Stable | ExponentVerdict::Undecided => Verdict::Done,
            other => Verdict::Negative(format!(
                "the closed loop's exponent says {}",
                serde_json::to_value(other)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_string))
                    .unwrap_or_default()
            )),
        }
    }
}
