//! Phase portraits (Φ, Φ̇): closed loop for several gain sets side by side (the study's
//! Fig. 4 a–d), or open loop under constant inputs; for a two-wheeler with a steer input the
//! lean (φ, φ̇) under several steer laws from its steady motion: `twv phase`.

use serde::Serialize;
use twv_model::{Model, ModelInfo};

use crate::control::steer::{FilteredSteer, SteerLaw, SteerSettings};
use crate::control::{
    scenario, simulate, ControllerSettings, PidLoop, Plant, RunEnd, RunSettings, Trajectory,
};
use crate::error::{Error, Result};
use crate::integrate::{ClosedLoop, OpenLoop, VectorField};
use crate::linear::eigenvalues;
use crate::model::{
    dispatch_control, dispatch_steer_filtered, dispatch_steered, input_vector, state_vector,
    ControlTask, ModelTask, ResolvedModel,
};
use crate::output::Files;
use crate::plot::{Curve, Figure, Grid, LineChart};
use crate::progress::Progress;

/// What drives one portrait.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Drive {
    /// The PID controller.
    Closed(ControllerSettings),
    /// Constant inputs, in the model's input order.
    Open(Vec<f64>),
    /// A steer-torque law on lean, steer and their rates (a two-wheeler with a steer input,
    /// from its steady motion at [`PhaseSettings::speed`]).
    Steer(SteerSettings),
}

/// The portraits to draw.
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhaseSettings {
    /// (label, drive) per portrait. Default the study's four gain sets.
    pub portraits: Vec<(String, Drive)>,
    /// Initial model states; `None`: at rest with Φ = each of `tilts`.
    pub x0: Option<Vec<Vec<f64>>>,
    /// Initial pitch angles from rest when `x0` is `None` [rad]. Default 0.1, −0.1, 0.2, −0.2.
    /// With a `speed`: initial leans from the steady motion.
    pub tilts: Vec<f64>,
    /// Start from the model's steady motion at this speed [m/s], leaning by each of `tilts`
    /// (models whose IR describes one: the bicycle); the portraits are then of the lean
    /// (φ, φ̇). Needed by steer laws.
    pub speed: Option<f64>,
    /// τ [s] of a rate filter for every steer law (1/(τs + 1) on the lean and steer rates);
    /// `None` (default): each law's own (none unless set).
    pub steer_filter: Option<f64>,
    /// Length, sampling and integrator of each run. Default 10 s.
    pub run: RunSettings,
}

impl Default for PhaseSettings {
    fn default() -> Self {
        Self {
            portraits: scenario::STUDY_GAIN_SETS
                .iter()
                .map(|s| {
                    (
                        s.label.to_string(),
                        Drive::Closed(ControllerSettings::pid(s.gains)),
                    )
                })
                .collect(),
            x0: None,
            tilts: DEFAULT_TILTS.to_vec(),
            speed: None,
            steer_filter: None,
            run: RunSettings::default(),
        }
    }
}

/// The default initial tilts [rad].
pub const DEFAULT_TILTS: [f64; 4] = [0.1, -0.1, 0.2, -0.2];

/// One portrait: a gain set (or constant input) and its trajectories.
#[derive(Debug, Clone, Serialize)]
pub struct Portrait {
    /// Label.
    pub label: String,
    /// The controller of a closed-loop portrait.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub controller: Option<ControllerSettings>,
    /// The constant input of an open-loop portrait.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub input: Option<Vec<f64>>,
    /// The steer law of a steered portrait.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steer: Option<SteerSettings>,
    /// Largest real part of the non-zero eigenvalues at the upright, or at the steady motion
    /// (the zero ones are the drift modes no loop moves) [1/s]; `None` when every eigenvalue is
    /// zero.
    pub loop_abscissa: Option<f64>,
    /// Whether the linearised loop there is stable (`loop_abscissa` < 0).
    pub stable: bool,
    /// The trajectories.
    pub runs: Vec<PhaseRun>,
}

/// One trajectory of a portrait.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseRun {
    /// Initial state.
    pub x0: Vec<f64>,
    /// Initial pitch [rad].
    pub phi0: f64,
    /// How the run ended.
    pub end: RunEnd,
    /// Φ at the end [rad].
    pub final_phi: f64,
    /// Φ̇ at the end [rad/s].
    pub final_phi_dot: f64,
    /// Sample times.
    #[serde(skip)]
    pub t: Vec<f64>,
    /// (Φ, Φ̇) at the samples.
    #[serde(skip)]
    pub points: Vec<(f64, f64)>,
}

/// Every portrait.
#[derive(Debug, Clone, Serialize)]
pub struct PhaseResult {
    /// Model name.
    pub model: String,
    /// Where the parameters came from.
    pub params: String,
    /// The steady motion's speed the runs started from [m/s] (`None`: from rest).
    pub speed: Option<f64>,
    /// The plotted state and its rate (`phi` and `w_y`, the pitch; the lean `phi` and `w_phi`
    /// from a steady motion).
    pub plane: [String; 2],
    /// The run settings.
    pub run: RunSettings,
    /// The portraits.
    pub portraits: Vec<Portrait>,
}

struct PhaseTask<'a> {
    progress: &'a dyn Progress,
    drive: &'a Drive,
    starts: &'a [Vec<f64>],
    run: &'a RunSettings,
}

fn runs<F: VectorField<N>, const N: usize>(
    field: F,
    starts: &[[f64; N]],
    (phi, w_y): (usize, usize),
    run: &RunSettings,
    progress: &dyn Progress,
) -> Result<Vec<PhaseRun>> {
    starts
        .iter()
        .map(|x0| {
            let traj: Trajectory<N> = simulate(&field, x0, phi, run, progress)?;
            let points: Vec<(f64, f64)> = traj.x.iter().map(|x| (x[phi], x[w_y])).collect();
            let last = traj.last();
            Ok(PhaseRun {
                x0: x0[..].to_vec(),
                phi0: x0[phi],
                end: traj.end,
                final_phi: last[phi],
                final_phi_dot: last[w_y],
                t: traj.t,
                points,
            })
        })
        .collect()
}

/// The initial states as the model's state arrays (the error names `x0`).
fn start_states<const NX: usize>(starts: &[Vec<f64>], states: &[&str]) -> Result<Vec<[f64; NX]>> {
    starts
        .iter()
        .map(|x| state_vector("x0", x, states))
        .collect()
}

/// Largest real part of the eigenvalues of J at `x` that are not zero (drift modes); `None`
/// when all are zero.
fn loop_abscissa<F: VectorField<N>, const N: usize>(
    field: &F,
    x: &[f64; N],
) -> Result<Option<f64>> {
    let mut j = [[0.0; N]; N];
    field.jacobian(0.0, x, &mut j);
    let m = nalgebra::DMatrix::from_fn(N, N, |r, c| j[r][c]);
    let scale = m.amax().max(1.0);
    Ok(eigenvalues(&m)?
        .iter()
        .filter(|e| e.norm() > 1e-9 * scale)
        .map(|e| e.re)
        .reduce(f64::max))
}

type Drawn = (
    Option<ControllerSettings>,
    Option<Vec<f64>>,
    Option<f64>,
    Vec<PhaseRun>,
);

/// A steered portrait: the steer law closing the model, runs from `starts`, the loop's
/// abscissa at the steady motion `steady`, the lean plane `plane` (state indices).
struct SteerPhase<'a> {
    progress: &'a dyn Progress,
    law: &'a SteerSettings,
    starts: &'a [Vec<f64>],
    steady: &'a [f64],
    plane: (usize, usize),
    run: &'a RunSettings,
}

impl SteerPhase<'_> {
    /// The runs' starts, the steady motion and the law on a model.
    fn parts<const NX: usize, const NU: usize>(
        &self,
        info: &ModelInfo,
        resolved: &ResolvedModel,
    ) -> Result<(Vec<[f64; NX]>, [f64; NX], SteerLaw<NX, NU>)> {
        let starts = start_states::<NX>(self.starts, info.states)?;
        let steady = state_vector("speed", self.steady, info.states)?;
        let law =
            SteerLaw::<NX, NU>::for_model(resolved, info.states, info.inputs, self.law, [0.0; NU])?;
        Ok((starts, steady, law))
    }
}

impl ModelTask for SteerPhase<'_> {
    type Output = (Option<f64>, Vec<PhaseRun>);
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<Self::Output> {
        let (starts, steady, law) = self.parts::<NX, NU>(&model.info(), resolved)?;
        let field = ClosedLoop::new(model, law);
        let abscissa = loop_abscissa(&field, &steady)?;
        Ok((
            abscissa,
            runs(field, &starts, self.plane, self.run, self.progress)?,
        ))
    }
}

/// The same portrait with the law's rates filtered: on NA = NX + 2 states, each run (and the
/// steady motion the abscissa is taken at) with the filter at its rates.
impl ControlTask for SteerPhase<'_> {
    type Output = (Option<f64>, Vec<PhaseRun>);
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<Self::Output> {
        let (starts, steady, law) = self.parts::<NX, NU>(&model.info(), resolved)?;
        let field = FilteredSteer::<_, NX, NU, NA>::new(model, law)?;
        let starts: Vec<[f64; NA]> = starts.iter().map(|x| field.initial_state(x)).collect();
        let abscissa = loop_abscissa(&field, &field.initial_state(&steady))?;
        Ok((
            abscissa,
            runs(field, &starts, self.plane, self.run, self.progress)?,
        ))
    }
}

/// The lean and lean-rate states of `model`'s steady motion (its first and third modes).
fn lean_plane(model: &ResolvedModel) -> Result<(usize, usize)> {
    let modes = model
        .steady_motion()
        .map(|m| m.modes.clone())
        .unwrap_or_default();
    let index = |k: usize| {
        modes
            .get(k)
            .and_then(|name| model.state_index(name))
            .ok_or_else(|| Error::Unsupported {
                model: model.name().to_string(),
                reason: "its IR names no lean-and-steer modes of a steady motion".into(),
            })
    };
    Ok((index(0)?, index(2)?))
}

impl ControlTask for PhaseTask<'_> {
    type Output = Drawn;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<Drawn> {
        let info = model.info();
        let starts = start_states::<NX>(self.starts, info.states)?;
        let p: Plant<NU> = Plant::from_info(&info, &|n| resolved.param(n))?;
        let index = (p.measured.phi, p.measured.w_y);
        match self.drive {
            Drive::Closed(settings) => {
                let field = PidLoop::<_, NX, NU, NA>::new(model, settings, p)?;
                let aug: Vec<[f64; NA]> = starts.iter().map(|x| field.initial_state(x)).collect();
                let abscissa = loop_abscissa(&field, &[0.0; NA])?;
                let runs = runs(field, &aug, index, self.run, self.progress)?;
                Ok((Some(settings.clone()), None, abscissa, runs))
            }
            Drive::Steer(_) => Err(Error::input(
                "steer_gains",
                "a steer law runs from a steady motion: give its speed too",
            )),
            Drive::Open(u) => {
                let u: [f64; NU] = input_vector("force", u, info.inputs)?;
                let field = OpenLoop::new(model, u);
                let abscissa = loop_abscissa(&field, &[0.0; NX])?;
                let runs = runs(field, &starts, index, self.run, self.progress)?;
                Ok((None, Some(u[..info.inputs.len()].to_vec()), abscissa, runs))
            }
        }
    }
}

/// Computes the portraits.
pub fn portraits(
    model: &ResolvedModel,
    settings: &PhaseSettings,
    progress: &dyn Progress,
) -> Result<PhaseResult> {
    settings.run.validate()?;
    if settings.portraits.is_empty() {
        return Err(Error::input("portraits", "no gain sets or input sets"));
    }
    let steered = |(_, d): &(String, Drive)| matches!(d, Drive::Steer(_));
    if settings.steer_filter.is_some() && !settings.portraits.iter().any(steered) {
        return Err(Error::input(
            "steer_filter",
            "filters the rates of steer laws: give --steer-gains too",
        ));
    }
    if let Some(v) = settings.speed {
        super::check_speed(v)?;
        if settings.x0.is_some() {
            return Err(Error::input(
                "speed",
                "give either initial states (x0) or a speed, not both",
            ));
        }
    }
    let steady = settings
        .speed
        .map(|v| super::steady_state(model, v))
        .transpose()?;
    let lean = steady.as_ref().map(|_| lean_plane(model)).transpose()?;
    let starts: Vec<Vec<f64>> = match (&settings.x0, &steady, lean) {
        (Some(x), _, _) if x.is_empty() => return Err(Error::input("x0", "no initial states")),
        (Some(x), _, _) => x.clone(),
        (None, _, _) if settings.tilts.is_empty() => {
            return Err(Error::input("tilts", "no initial tilts"))
        }
        (None, Some(x), Some((phi, _))) => settings
            .tilts
            .iter()
            .map(|&p| {
                let mut x = x.clone();
                x[phi] = p;
                x
            })
            .collect(),
        (None, _, _) => settings
            .tilts
            .iter()
            .map(|&p| model.rest_with("phi", p))
            .collect::<Result<_>>()?,
    };
    let mut out = Vec::new();
    for (label, drive) in &settings.portraits {
        let nz = match drive {
            Drive::Closed(s) => {
                s.validate()?;
                s.n_states()
            }
            Drive::Open(_) => 0,
            Drive::Steer(law) => {
                law.validate()?;
                0
            }
        };
        let (controller, input, steer, loop_abscissa, runs) = match (drive, &steady, lean) {
            (Drive::Steer(law), Some(steady), Some(plane)) => {
                let law = SteerSettings {
                    rate_filter: settings.steer_filter.or(law.rate_filter),
                    ..*law
                };
                law.validate()?;
                let task = SteerPhase {
                    progress,
                    law: &law,
                    starts: &starts,
                    steady,
                    plane,
                    run: &settings.run,
                };
                let (abscissa, runs) = match law.rate_filter {
                    Some(_) => dispatch_steer_filtered(model, task)?,
                    None => dispatch_steered(model, task)?,
                };
                (None, None, Some(law), abscissa, runs)
            }
            (Drive::Steer(_), _, _) => {
                return Err(Error::input(
                    "steer_gains",
                    "a steer law runs from a steady motion: give its speed too",
                ))
            }
            _ => {
                let task = PhaseTask {
                    progress,
                    drive,
                    starts: &starts,
                    run: &settings.run,
                };
                let (c, u, a, r) = dispatch_control(model, nz, task)?;
                (c, u, None, a, r)
            }
        };
        out.push(Portrait {
            label: label.clone(),
            controller,
            input,
            steer,
            stable: loop_abscissa.is_some_and(|a| a < 0.0),
            loop_abscissa,
            runs,
        });
    }
    let states = model.states();
    let plane = match lean {
        Some((phi, rate)) => [states[phi].to_string(), states[rate].to_string()],
        None => ["phi".to_string(), "w_y".to_string()],
    };
    Ok(PhaseResult {
        model: model.name().to_string(),
        params: model.params_origin.clone(),
        speed: settings.speed,
        plane,
        run: settings.run,
        portraits: out,
    })
}

/// Size of one portrait [px].
pub const PORTRAIT_SIZE: (u32, u32) = (560, 480);

impl PhaseResult {
    /// The plotted angle: the pitch Φ, or the lean φ of a steady motion.
    fn symbol(&self) -> &'static str {
        match self.speed {
            Some(_) => "φ",
            None => "Φ",
        }
    }

    /// The axes' titles.
    fn axes(&self) -> (String, String) {
        let sym = self.symbol();
        match self.speed {
            Some(v) => (
                format!("lean {sym} [rad] at {v} m/s"),
                format!("d{sym}/dt [rad/s]"),
            ),
            None => (format!("{sym} [rad]"), format!("d{sym}/dt [rad/s]")),
        }
    }

    /// One chart per portrait.
    pub fn portrait_figures(&self) -> Vec<LineChart> {
        let (x, y) = self.axes();
        self.portraits
            .iter()
            .map(|p| {
                let curves = p
                    .runs
                    .iter()
                    .map(|r| Curve {
                        name: format!("{}0 = {:.3}", self.symbol(), r.phi0),
                        points: r.points.clone(),
                    })
                    .collect();
                LineChart::new(&p.label, &x, &y, PORTRAIT_SIZE, curves)
            })
            .collect()
    }

    /// The portraits side by side, `columns` to a row.
    pub fn combined_figure(&self, columns: usize) -> Figure {
        Figure::Grid(Grid {
            panels: self.portrait_figures(),
            columns,
        })
    }

    /// phase_1.svg … (one per portrait), phase.svg (two to a row), their PNGs, phase.csv and
    /// phase.json.
    pub fn files(&self) -> Result<Files> {
        let mut f = Files::new();
        for (i, chart) in self.portrait_figures().into_iter().enumerate() {
            f.figure(&format!("phase_{}.svg", i + 1), &Figure::Line(chart))?;
        }
        f.figure("phase.svg", &self.combined_figure(2))?;
        f.text("phase.csv", self.csv());
        f.json("phase.json", self);
        Ok(f)
    }

    /// The trajectories as CSV: set, run, t, Φ, Φ̇.
    pub fn csv(&self) -> String {
        let mut csv = String::from("set,run,t,phi,phi_dot\n");
        for (i, p) in self.portraits.iter().enumerate() {
            for (j, r) in p.runs.iter().enumerate() {
                for (t, (phi, rate)) in r.t.iter().zip(&r.points) {
                    csv += &format!("{},{},{t:e},{phi:e},{rate:e}\n", i + 1, j + 1);
                }
            }
        }
        csv
    }

    /// One line per portrait and per run.
    pub fn summary(&self) -> String {
        let sym = self.symbol();
        let mut s = format!(
            "Phase portraits ({sym}, {sym}̇) of {} ({}){}, {} s\n",
            self.model,
            self.params,
            self.speed.map_or(String::new(), |v| format!(
                " from its steady motion at {v} m/s"
            )),
            self.run.t_end
        );
        for p in &self.portraits {
            s += &match p.loop_abscissa {
                Some(a) => format!(
                    "{}: loop spectral abscissa {a:+.4} 1/s ({})\n",
                    p.label,
                    if p.stable { "stable" } else { "unstable" }
                ),
                None => format!("{}: every eigenvalue there is zero\n", p.label),
            };
            for r in &p.runs {
                let end = match r.end {
                    RunEnd::Completed => format!(
                        "ends at ({sym}, {sym}̇) = ({:+.3e}, {:+.3e})",
                        r.final_phi, r.final_phi_dot
                    ),
                    RunEnd::Fell { t, .. } => format!("falls over at t = {t:.3} s"),
                };
                s += &format!("  {sym}0 = {:+.3}: {end}\n", r.phi0);
            }
        }
        s
    }
}
