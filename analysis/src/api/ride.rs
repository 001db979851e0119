//! A run under constant inputs from a state, or from its steady motion at a speed with some
//! states pushed — `twv ride`. What the bicycle does when nobody steers: inside its self-stable
//! speed range a small push in lean dies out, outside it grows into a fall; and what it does
//! when a steer controller ([`SteerSettings`]) steers it. The verdict is computed from the run
//! with the thresholds below.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};
use twv_model::{Model, ModelInfo};

use crate::control::steer::{filtered_rate, FilteredSteer, SteerLaw, SteerSettings};
use crate::control::{simulate as integrate, RunEnd, RunSettings, Trajectory};
use crate::error::{Error, Result};
use crate::integrate::{ClosedLoop, OpenLoop};
use crate::model::{
    dispatch, dispatch_steer_filtered, dispatch_steered, input_vector, state_vector, ControlTask,
    ModelTask, ResolvedModel,
};
use crate::output::Files;
use crate::plot::{Curve, Figure, LineChart};
use crate::progress::Progress;

/// The last part of a run whose largest |watched state| is compared with the whole run's.
pub const RIDE_TAIL: f64 = 0.1;

/// A run recovered when the largest |watched state| over its last [`RIDE_TAIL`] is at most
/// this fraction of the largest over the whole run: the disturbance has died out to a tenth.
pub const RIDE_DECAY: f64 = 0.1;

/// A run under constant inputs, steered or not. Defaults beside each field.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RideSettings {
    /// Initial state in the model's order; `None`: the steady motion at `speed` (or rest).
    pub x0: Option<Vec<f64>>,
    /// Start from the model's steady motion at this speed [m/s] (a model whose IR describes
    /// one, e.g. the bicycle's straight running). Default none: at rest.
    pub speed: Option<f64>,
    /// Values added to named states of the initial state (a push: `w_phi = 0.05`).
    pub perturb: BTreeMap<String, f64>,
    /// Constant inputs in the model's order. Default all zero.
    pub u: Option<Vec<f64>>,
    /// A steer-torque law on the model's steer input (two-wheelers with one: the bicycle).
    /// Default none: not steered.
    pub steer: Option<SteerSettings>,
    /// The state whose decay is judged and whose size stops the run (`run.fall_angle`).
    /// Default `phi` (the bicycle's lean, the vehicles' pitch).
    pub watch: String,
    /// Length, sampling, integrator; `fall_angle` applies to `watch`. Default 10 s, RK4 at
    /// 1 ms, fall at π/2.
    pub run: RunSettings,
}

impl Default for RideSettings {
    fn default() -> Self {
        Self {
            x0: None,
            speed: None,
            perturb: BTreeMap::new(),
            u: None,
            steer: None,
            watch: "phi".into(),
            run: RunSettings::default(),
        }
    }
}

impl RideSettings {
    /// Checks the settings (the state and input sizes are checked against the model).
    pub fn validate(&self) -> Result<()> {
        self.run.validate()?;
        if let Some(v) = self.speed {
            if !v.is_finite() {
                return Err(Error::input("speed", format!("{v} must be finite")));
            }
            if self.x0.is_some() {
                return Err(Error::input(
                    "speed",
                    "give either an initial state (x0) or a speed, not both",
                ));
            }
        }
        if let Some(law) = &self.steer {
            law.validate()?;
        }
        for (name, v) in &self.perturb {
            if !v.is_finite() {
                return Err(Error::input(
                    "perturb",
                    format!("{name} = {v} must be finite"),
                ));
            }
        }
        Ok(())
    }
}

/// How the run is judged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RideVerdict {
    /// Completed, and the largest |watch| over the last [`RIDE_TAIL`] of the run is at most
    /// [`RIDE_DECAY`] times the largest over the run.
    Recovered,
    /// Completed without dying out that far.
    NotRecovered,
    /// |watch| passed the fall angle.
    Fell,
    /// The watched state stayed exactly at zero: nothing to recover from.
    Undisturbed,
}

/// One run.
#[derive(Debug, Clone, Serialize)]
pub struct RideResult {
    pub model: String,
    /// Where the parameters came from.
    pub params: String,
    pub x0: Vec<f64>,
    pub u: Vec<f64>,
    pub speed: Option<f64>,
    /// The steer-torque law, when steered.
    pub steer: Option<SteerSettings>,
    pub watch: String,
    pub run: RunSettings,
    pub end: RunEnd,
    /// Largest |watch| over the run.
    pub peak: f64,
    /// Largest |watch| over the last [`RIDE_TAIL`] of the run.
    pub tail_peak: f64,
    /// |watch| at the end.
    pub final_value: f64,
    pub verdict: RideVerdict,
    /// CSV column names: t, then the states.
    #[serde(skip)]
    pub columns: Vec<String>,
    /// Each column's unit, in the order of the CSV's columns (SI).
    pub units: Vec<String>,
    /// CSV rows.
    #[serde(skip)]
    pub rows: Vec<Vec<f64>>,
}

/// The verdict from the watched state's samples and how the run ended.
pub fn ride_verdict(end: &RunEnd, watched: &[f64]) -> (RideVerdict, f64, f64) {
    let peak = watched.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let tail_from = ((watched.len() as f64) * (1.0 - RIDE_TAIL)).floor() as usize;
    let tail_peak = watched[tail_from.min(watched.len() - 1)..]
        .iter()
        .fold(0.0_f64, |m, v| m.max(v.abs()));
    let verdict = match end {
        RunEnd::Fell { .. } => RideVerdict::Fell,
        RunEnd::Completed if peak == 0.0 => RideVerdict::Undisturbed,
        RunEnd::Completed if tail_peak <= RIDE_DECAY * peak => RideVerdict::Recovered,
        RunEnd::Completed => RideVerdict::NotRecovered,
    };
    (verdict, peak, tail_peak)
}

/// The initial state of `settings` on `model`: x0, or the steady motion at `speed`, or rest,
/// plus the pushes.
fn initial_state(model: &ResolvedModel, s: &RideSettings) -> Result<Vec<f64>> {
    let mut x = match (&s.x0, s.speed) {
        (Some(x), _) => x.clone(),
        (None, Some(v)) => super::steady::steady_state(model, v)?,
        (None, None) => vec![0.0; model.states().len()],
    };
    for (name, dv) in &s.perturb {
        let i = model.state_index(name).ok_or_else(|| {
            Error::input(
                "perturb",
                format!(
                    "`{name}` is not a state of {} (states: {})",
                    model.name(),
                    model.states().join(", ")
                ),
            )
        })?;
        if let Some(xi) = x.get_mut(i) {
            *xi += dv;
        }
    }
    Ok(x)
}

struct Ride<'a>(&'a RideSettings, &'a dyn Progress);

/// What a run starts from on a model: the watched state's index, x0 and u.
fn start<const NX: usize, const NU: usize>(
    s: &RideSettings,
    resolved: &ResolvedModel,
    info: &ModelInfo,
) -> Result<(usize, [f64; NX], [f64; NU])> {
    let watch = resolved.state_index(&s.watch).ok_or_else(|| {
        Error::input(
            "watch",
            format!(
                "`{}` is not a state of {} (states: {})",
                s.watch,
                resolved.name(),
                info.states.join(", ")
            ),
        )
    })?;
    let x0: [f64; NX] = state_vector("x0", &initial_state(resolved, s)?, info.states)?;
    let u_given = s.u.clone().unwrap_or_else(|| vec![0.0; info.inputs.len()]);
    let u: [f64; NU] = input_vector("u", &u_given, info.inputs)?;
    Ok((watch, x0, u))
}

/// [`start`] and the steer law of `settings` on the model.
fn steered_start<const NX: usize, const NU: usize>(
    s: &RideSettings,
    resolved: &ResolvedModel,
    info: &ModelInfo,
    settings: &SteerSettings,
) -> Result<(usize, [f64; NX], SteerLaw<NX, NU>)> {
    let (watch, x0, u) = start::<NX, NU>(s, resolved, info)?;
    let law = SteerLaw::<NX, NU>::for_model(resolved, info.states, info.inputs, settings, u)?;
    Ok((watch, x0, law))
}

impl ModelTask for Ride<'_> {
    type Output = RideResult;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<RideResult> {
        let s = self.0;
        let info = model.info();
        let (watch, x0, u) = start::<NX, NU>(s, resolved, &info)?;
        let traj = integrate(OpenLoop::new(model, u), &x0, watch, &s.run, self.1)?;
        Ok(result(s, resolved, &info, &x0, watch, traj, &[]))
    }
}

/// A ride steered by a law without a rate filter.
struct SteeredRide<'a>(&'a RideSettings, &'a dyn Progress, SteerSettings);

impl ModelTask for SteeredRide<'_> {
    type Output = RideResult;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<RideResult> {
        let s = self.0;
        let info = model.info();
        let (watch, x0, law) = steered_start::<NX, NU>(s, resolved, &info, &self.2)?;
        let traj = integrate(ClosedLoop::new(model, law), &x0, watch, &s.run, self.1)?;
        Ok(result(s, resolved, &info, &x0, watch, traj, &[]))
    }
}

/// A ride steered by a law with a rate filter: the closed loop on NA = NX + 2 states, whose
/// filtered rates are two more columns.
struct FilteredRide<'a>(&'a RideSettings, &'a dyn Progress, SteerSettings);

impl ControlTask for FilteredRide<'_> {
    type Output = RideResult;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<RideResult> {
        let s = self.0;
        let info = model.info();
        let (watch, x0, law) = steered_start::<NX, NU>(s, resolved, &info, &self.2)?;
        let field = FilteredSteer::<_, NX, NU, NA>::new(model, law)?;
        let xa = field.initial_state(&x0);
        let traj = integrate(field, &xa, watch, &s.run, self.1)?;
        let filter = FilteredSteer::<M, NX, NU, NA>::filter_states(info.states, &law);
        Ok(result(s, resolved, &info, &x0, watch, traj, &filter))
    }
}

/// The result of a run whose samples are `traj` over the model's states and then `extra` (a
/// controller's own states).
fn result<const N: usize>(
    s: &RideSettings,
    resolved: &ResolvedModel,
    info: &ModelInfo,
    x0: &[f64],
    watch: usize,
    traj: Trajectory<N>,
    extra: &[String],
) -> RideResult {
    let watched = traj.component(watch);
    let (verdict, peak, tail_peak) = ride_verdict(&traj.end, &watched);
    let mut columns = vec!["t".to_string()];
    columns.extend(info.states.iter().map(|n| n.to_string()));
    columns.extend_from_slice(extra);
    let rows = traj
        .t
        .iter()
        .zip(&traj.x)
        .map(|(t, x)| std::iter::once(*t).chain(x.iter().copied()).collect())
        .collect();
    let rate_unit = |name: &str| {
        filtered_rate(name)
            .and_then(|rate| resolved.unit_of(rate))
            .unwrap_or("")
    };
    let filtered: Vec<(&str, &str)> = columns
        .iter()
        .filter(|c| resolved.state_index(c).is_none())
        .map(|c| (c.as_str(), rate_unit(c)))
        .collect();
    RideResult {
        model: resolved.name().to_string(),
        params: resolved.params_origin.clone(),
        x0: x0.to_vec(),
        u: s.u.clone().unwrap_or_else(|| vec![0.0; info.inputs.len()]),
        speed: s.speed,
        steer: s.steer,
        watch: s.watch.clone(),
        run: s.run,
        end: traj.end,
        peak,
        tail_peak,
        final_value: watched.last().map_or(0.0, |v| v.abs()),
        verdict,
        units: resolved.column_units(&columns, &filtered),
        columns,
        rows,
    }
}

/// Runs the model under `settings`.
pub fn ride(
    model: &ResolvedModel,
    settings: &RideSettings,
    progress: &dyn Progress,
) -> Result<RideResult> {
    settings.validate()?;
    match settings.steer {
        Some(law) if law.rate_filter.is_some() => {
            dispatch_steer_filtered(model, FilteredRide(settings, progress, law))
        }
        Some(law) => dispatch_steered(model, SteeredRide(settings, progress, law)),
        None => dispatch(model, Ride(settings, progress)),
    }
}

impl RideResult {
    /// The time series as CSV (header = `columns`, full precision).
    pub fn csv(&self) -> String {
        crate::output::csv_table(&self.columns, &self.rows)
    }

    /// One figure per state that moves (the watched state first).
    pub fn figures(&self) -> Vec<(String, Figure)> {
        let mut names: Vec<&String> = self.columns[1..].iter().collect();
        names.sort_by_key(|n| **n != self.watch);
        names
            .into_iter()
            .filter_map(|name| {
                let i = self.columns.iter().position(|c| c == name)?;
                let points: Vec<(f64, f64)> = self.rows.iter().map(|r| (r[0], r[i])).collect();
                let first = points[0].1;
                points.iter().any(|p| p.1 != first).then(|| {
                    let title = format!("{} {} — {name}", self.model, self.how());
                    let curve = Curve {
                        name: name.clone(),
                        points,
                    };
                    let chart = LineChart::new(&title, "t [s]", name, (800, 450), vec![curve]);
                    (format!("{name}.svg"), Figure::Line(chart))
                })
            })
            .collect()
    }

    /// ride.csv, ride.json and the figures (SVG and PNG).
    pub fn files(&self) -> Result<Files> {
        let mut f = Files::new();
        f.text("ride.csv", self.csv());
        f.json("ride.json", self);
        for (name, figure) in self.figures() {
            f.figure(&name, &figure)?;
        }
        Ok(f)
    }

    /// "steered" or "uncontrolled".
    fn how(&self) -> &'static str {
        if self.steer.is_some() {
            "steered"
        } else {
            "uncontrolled"
        }
    }

    /// A few readable lines with the verdict and its threshold.
    pub fn summary(&self) -> String {
        let start = match self.speed {
            Some(v) => format!("from its steady motion at {v} m/s"),
            None => "from the given state".to_string(),
        };
        let verdict = match self.verdict {
            RideVerdict::Recovered => format!(
                "recovered: |{}| over the last {:.0} % is {:.3e}, ≤ {} × its peak {:.3e}",
                self.watch,
                100.0 * RIDE_TAIL,
                self.tail_peak,
                RIDE_DECAY,
                self.peak
            ),
            RideVerdict::NotRecovered => format!(
                "NOT recovered: |{}| over the last {:.0} % is {:.3e}, > {} × its peak {:.3e}",
                self.watch,
                100.0 * RIDE_TAIL,
                self.tail_peak,
                RIDE_DECAY,
                self.peak
            ),
            RideVerdict::Fell => match self.end.fall_text(&self.watch, &self.run) {
                Some(how) => format!("FELL: {how}"),
                None => "FELL".to_string(),
            },
            RideVerdict::Undisturbed => format!("{} stayed at zero: undisturbed", self.watch),
        };
        format!(
            "{} {} {start}, {} s ({}): {verdict}\n",
            self.model,
            self.how(),
            self.run.t_end,
            self.params
        )
    }
}
