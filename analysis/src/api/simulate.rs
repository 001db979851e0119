//! One closed-loop run of the PID pitch controller — a tilt recovery or a maneuver — with its
//! time series, metrics and whether it recovered: `twv sim` and `twv disturb`.

use serde::{Deserialize, Serialize};
use twv_model::Model;

use crate::control::{
    run_closed_loop, ClosedLoopRun, ControllerSettings, LoopMetrics, PidLoop, Plant, Profile,
    RunEnd, RunSettings, VelocityLoop,
};
use crate::error::Result;
use crate::model::{dispatch_control, state_vector, ControlTask, ResolvedModel};
use crate::output::Files;
use crate::plot::{Curve, Figure, LineChart};
use crate::progress::Progress;

/// Velocity-loop gains of the maneuver when none are given [rad per m/s, rad per m]: with the
/// study's PD inside, the outer poles are then −0.45 ± 1.08i and −0.51 (linearised, paper
/// vehicle): the fastest well-damped choice, since the inner loop's slow pole sits at −1.36.
pub const MANEUVER_V_LOOP: (f64, f64) = (0.08, 0.03);

/// The largest |Φ| at the end of a run, in rad, that still counts as recovered (with Φ inside
/// its 2 % band from the settling time on): 0.002 rad = 0.11°.
pub const RECOVERED_PHI: f64 = 0.002;

/// The maneuver of `twv simulate --scenario maneuver`: from rest, accelerate to `v_cruise` over
/// `ramp`, cruise for `cruise`, decelerate over `ramp`, stop, through the velocity loop.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Maneuver {
    /// Cruise speed [m/s]. Default 2.
    pub v_cruise: f64,
    /// Acceleration and deceleration time [s]. Default 3.
    pub ramp: f64,
    /// Cruise time [s]. Default 5.
    pub cruise: f64,
}

impl Default for Maneuver {
    fn default() -> Self {
        Self {
            v_cruise: 2.0,
            ramp: 3.0,
            cruise: 5.0,
        }
    }
}

impl Maneuver {
    /// The velocity reference.
    pub fn profile(&self) -> Result<Profile> {
        Ok(crate::control::scenario::maneuver(
            self.v_cruise,
            self.ramp,
            self.cruise,
        )?)
    }

    /// The run's default length: the maneuver and 10 s more [s].
    pub fn default_t_end(&self) -> Result<f64> {
        Ok(self.profile()?.t_last() + 10.0)
    }
}

/// A closed-loop run to simulate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SimSettings {
    /// A title for tables and figures; empty (default): from the scenario and the gains.
    pub title: String,
    /// What the run is (`tilt`, `maneuver`, `forward tilt`, …). Default `tilt`.
    pub scenario: String,
    /// The controller. Default the study's PD.
    pub controller: ControllerSettings,
    /// The start/accelerate/cruise/decelerate/stop maneuver through the velocity loop (its
    /// gains, or [`MANEUVER_V_LOOP`] without one); `None` (default): no maneuver.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub maneuver: Option<Maneuver>,
    /// Length, sampling, integrator, fall angle. Default 10 s, RK4 at 1 ms.
    pub run: RunSettings,
    /// Initial model state; `None`: at rest with Φ = `phi0`.
    pub x0: Option<Vec<f64>>,
    /// Initial pitch when `x0` is `None` [rad]. Default 0.1.
    pub phi0: f64,
    /// Initial pitch rate when `x0` is `None` [rad/s] (a push instead of, or beside, a tilt).
    /// Default 0.
    pub phi_dot0: f64,
}

impl Default for SimSettings {
    fn default() -> Self {
        Self {
            title: String::new(),
            scenario: "tilt".into(),
            controller: ControllerSettings::default(),
            maneuver: None,
            run: RunSettings::default(),
            x0: None,
            phi0: 0.1,
            phi_dot0: 0.0,
        }
    }
}

impl SimSettings {
    /// Checks the settings.
    pub fn validate(&self) -> Result<()> {
        self.controller.validate()?;
        self.run.validate()?;
        crate::control::check_tilt("phi0", self.phi0)?;
        if !self.phi_dot0.is_finite() {
            return Err(crate::Error::input(
                "phi_dot0",
                format!("{} rad/s must be finite", self.phi_dot0),
            ));
        }
        if let Some(m) = &self.maneuver {
            m.profile()?;
        }
        Ok(())
    }

    /// The maneuver of `twv simulate --scenario maneuver` (see [`Maneuver`]) under the
    /// controller `base`. The run lasts `t_end`, or the maneuver and 10 s more.
    pub fn maneuver(
        base: ControllerSettings,
        (v_cruise, ramp, cruise): (f64, f64, f64),
        run: RunSettings,
        t_end: Option<f64>,
    ) -> Result<Self> {
        let maneuver = Maneuver {
            v_cruise,
            ramp,
            cruise,
        };
        let t_end = match t_end {
            Some(t) => t,
            None => maneuver.default_t_end()?,
        };
        Ok(Self {
            scenario: "maneuver".into(),
            controller: base,
            maneuver: Some(maneuver),
            run: RunSettings { t_end, ..run },
            phi0: 0.0,
            ..Self::default()
        })
    }

    /// The settings as they run: the maneuver's velocity reference in the controller, the
    /// title filled in.
    pub fn resolved(&self) -> Result<Self> {
        let mut s = self.clone();
        if let Some(m) = &self.maneuver {
            let (kp, ki, lean_max) = s
                .controller
                .velocity
                .as_ref()
                .map_or((MANEUVER_V_LOOP.0, MANEUVER_V_LOOP.1, None), |v| {
                    (v.kp, v.ki, v.lean_max)
                });
            s.controller.velocity = Some(VelocityLoop {
                kp,
                ki,
                reference: m.profile()?,
                lean_max,
            });
        }
        if s.title.is_empty() {
            let g = s.controller.pitch.gains;
            s.title = format!("{}, Kp {} Ki {} Kd {}", s.scenario, g.kp, g.ki, g.kd);
        }
        Ok(s)
    }
}

/// Whether a run recovered, and by which test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Recovery {
    /// Φ settled into its 2 % band and ends within [`RECOVERED_PHI`] of its rest value.
    Recovered,
    /// The run completed but Φ did not settle, or ends farther than [`RECOVERED_PHI`] away.
    NotSettled,
    /// |Φ| passed the fall angle.
    Fell,
}

/// The input directions of the controller, the model's own inputs only.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InputDirections {
    /// ∂u/∂F.
    pub force: Vec<f64>,
    /// ∂u/∂T, if the model has a yaw input.
    pub yaw: Option<Vec<f64>>,
}

/// One closed-loop run.
#[derive(Debug, Clone, Serialize)]
pub struct SimResult {
    /// Title.
    pub title: String,
    /// Model name.
    pub model: String,
    /// Where the parameters came from.
    pub params: String,
    /// The scenario.
    pub scenario: String,
    /// The controller.
    pub controller: ControllerSettings,
    /// How F and T act on the inputs.
    pub input_map: InputDirections,
    /// The run settings.
    pub run: RunSettings,
    /// Initial model state.
    pub x0: Vec<f64>,
    /// How the run ended.
    pub end: RunEnd,
    /// Response metrics.
    pub metrics: LoopMetrics,
    /// The verdict on the pitch.
    pub recovery: Recovery,
    /// CSV column names.
    #[serde(skip)]
    pub columns: Vec<String>,
    /// Each column's unit, in the order of the CSV's columns (SI).
    pub units: Vec<String>,
    /// CSV rows.
    #[serde(skip)]
    pub rows: Vec<Vec<f64>>,
}

/// The recovery verdict of a run from its end and metrics.
pub fn recovery_of(end: &RunEnd, metrics: &LoopMetrics, rest: f64) -> Recovery {
    match end {
        RunEnd::Fell { .. } => Recovery::Fell,
        RunEnd::Completed
            if metrics.phi.settling_time.is_some()
                && (metrics.final_phi - rest).abs() <= RECOVERED_PHI =>
        {
            Recovery::Recovered
        }
        RunEnd::Completed => Recovery::NotSettled,
    }
}

struct Sim<'a>(&'a SimSettings, &'a dyn Progress);

impl ControlTask for Sim<'_> {
    type Output = SimResult;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<SimResult> {
        let s = self.0;
        let info = model.info();
        let x0: [f64; NX] = match &s.x0 {
            Some(x) => state_vector("x0", x, info.states)?,
            None => {
                let mut x = resolved.rest_with("phi", s.phi0)?;
                if s.phi_dot0 != 0.0 {
                    let rate = resolved.state_index("w_y").ok_or_else(|| {
                        crate::Error::input("phi_dot0", "the model has no pitch rate w_y")
                    })?;
                    x[rate] = s.phi_dot0;
                }
                state_vector("x0", &x, info.states)?
            }
        };
        let plant: Plant<NU> = Plant::from_info(&info, &|n| resolved.param(n))?;
        let field = PidLoop::<_, NX, NU, NA>::new(model, &s.controller, plant)?;
        let run = run_closed_loop(&field, &x0, &s.run, self.1)?;
        let (columns, rows) = table(&field, &run);
        let mut extra: Vec<(&str, &str)> = vec![
            ("phi_ref", "rad"),
            ("F_cmd", "N"),
            ("F", "N"),
            ("T", "N m"),
            ("v_ref", "m/s"),
        ];
        extra.extend(field.layout().states().iter().map(|(_, n, u)| (*n, *u)));
        let units = resolved.column_units(&columns, &extra);
        let nu = info.inputs.len();
        let rest = s.controller.pitch.setpoint.rest_value();
        Ok(SimResult {
            title: s.title.clone(),
            model: resolved.name().to_string(),
            params: resolved.params_origin.clone(),
            scenario: s.scenario.clone(),
            controller: s.controller.clone(),
            input_map: InputDirections {
                force: plant.inputs.force[..nu].to_vec(),
                yaw: plant.inputs.yaw.map(|y| y[..nu].to_vec()),
            },
            run: s.run,
            x0: x0.to_vec(),
            end: run.trajectory.end,
            recovery: recovery_of(&run.trajectory.end, &run.metrics, rest),
            metrics: run.metrics,
            columns,
            units,
            rows,
        })
    }
}

/// CSV columns: t, the model states, the controller states, the inputs, Φ_ref, F_cmd, F, T,
/// and v_ref with a velocity loop.
fn table<M: Model<NX, NU>, const NX: usize, const NU: usize, const NA: usize>(
    field: &PidLoop<'_, M, NX, NU, NA>,
    run: &ClosedLoopRun<NA, NU>,
) -> (Vec<String>, Vec<Vec<f64>>) {
    let info = field.model().info();
    let nu = info.inputs.len();
    let mut columns = vec!["t".to_string()];
    columns.extend(info.states.iter().map(|s| s.to_string()));
    columns.extend(
        field
            .layout()
            .states()
            .iter()
            .map(|(_, n, _)| n.to_string()),
    );
    columns.extend(info.inputs.iter().map(|s| s.to_string()));
    columns.extend(["phi_ref", "F_cmd", "F", "T"].map(String::from));
    let v_ref: Option<&Profile> = field.settings().velocity.as_ref().map(|v| &v.reference);
    if v_ref.is_some() {
        columns.push("v_ref".into());
    }
    let rows = run
        .trajectory
        .t
        .iter()
        .zip(&run.trajectory.x)
        .zip(&run.commands)
        .map(|((t, x), c)| {
            let mut row = Vec::with_capacity(columns.len());
            row.push(*t);
            row.extend_from_slice(x);
            row.extend_from_slice(&c.u[..nu]);
            row.extend([c.phi_ref, c.force_cmd, c.force, c.yaw]);
            row.extend(v_ref.map(|r| r.value(*t)));
            row
        })
        .collect();
    (columns, rows)
}

/// Runs the closed loop of `settings` on `model`.
pub fn simulate(
    model: &ResolvedModel,
    settings: &SimSettings,
    progress: &dyn Progress,
) -> Result<SimResult> {
    settings.validate()?;
    let settings = &settings.resolved()?;
    dispatch_control(
        model,
        settings.controller.n_states(),
        Sim(settings, progress),
    )
}

/// A figure of a run: file, what it shows, y label, and the (column, legend) curves.
type FigureSpec = (
    &'static str,
    &'static str,
    &'static str,
    Vec<(&'static str, &'static str)>,
);

impl SimResult {
    /// One column over time, by name.
    pub fn column(&self, name: &str) -> Option<Vec<(f64, f64)>> {
        let i = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| (r[0], r[i])).collect())
    }

    /// The time series as CSV (header = `columns`, full precision).
    pub fn csv(&self) -> String {
        crate::output::csv_table(&self.columns, &self.rows)
    }

    /// (file name, figure) of every figure: Φ (with Φ_ref), Φ̇, v_x, x, the force, and v_y, θ
    /// when they leave zero.
    pub fn figures(&self) -> Vec<(String, Figure)> {
        let moving = |name: &str| {
            self.column(name)
                .is_some_and(|c| c.iter().any(|(_, v)| v.abs() > 1e-12))
        };
        let mut specs: Vec<FigureSpec> = vec![
            (
                "phi.svg",
                "pitch Φ",
                "Φ [rad]",
                vec![("phi", "Φ"), ("phi_ref", "Φ_ref")],
            ),
            (
                "phi_dot.svg",
                "pitch rate dΦ/dt",
                "dΦ/dt [rad/s]",
                vec![("w_y", "dΦ/dt")],
            ),
            (
                "v_x.svg",
                "forward velocity",
                "v_x [m/s]",
                vec![("v_x", "v_x"), ("v_ref", "v_ref")],
            ),
            ("x.svg", "displacement", "x [m]", vec![("x", "x")]),
            (
                "force.svg",
                "force",
                "F [N]",
                vec![("F", "F applied"), ("F_cmd", "F commanded")],
            ),
        ];
        if moving("v_y") {
            specs.push((
                "v_y.svg",
                "lateral velocity",
                "v_y [m/s]",
                vec![("v_y", "v_y")],
            ));
        }
        if moving("theta") {
            specs.push(("theta.svg", "yaw", "θ [rad]", vec![("theta", "θ")]));
        }
        specs
            .into_iter()
            .filter_map(|(file, what, y_label, cols)| {
                let curves: Vec<Curve> = cols
                    .iter()
                    .filter_map(|(c, label)| {
                        self.column(c).map(|points| Curve {
                            name: label.to_string(),
                            points,
                        })
                    })
                    .collect();
                (!curves.is_empty()).then(|| {
                    let title = format!("{} — {what}", self.title);
                    let chart = LineChart::new(&title, "t [s]", y_label, (800, 450), curves);
                    (file.to_string(), Figure::Line(chart))
                })
            })
            .collect()
    }

    /// sim.csv, metrics.json and the figures (SVG and PNG).
    pub fn files(&self) -> Result<Files> {
        let mut f = Files::new();
        f.text("sim.csv", self.csv());
        f.json("metrics.json", self);
        for (name, figure) in self.figures() {
            f.figure(&name, &figure)?;
        }
        Ok(f)
    }

    /// A few readable lines.
    pub fn summary(&self) -> String {
        let m = &self.metrics;
        let opt = |v: Option<f64>, unit: &str| v.map_or("—".into(), |v| format!("{v:.4} {unit}"));
        let mut s = format!(
            "{} on {} ({}), {} s: {}\n",
            self.title,
            self.model,
            self.params,
            self.run.t_end,
            match self.recovery {
                Recovery::Recovered => "recovered".to_string(),
                Recovery::NotSettled => format!(
                    "NOT recovered (Φ not settled, or |Φ| > {RECOVERED_PHI} rad at the end)"
                ),
                Recovery::Fell => "FELL OVER".to_string(),
            }
        );
        if let Some(how) = self.end.fall_text("Φ", &self.run) {
            s += &format!("  fell over: {how}\n");
        }
        s += &format!(
            "  Φ: settling (2 %) {}, overshoot {}, IAE {:.4} rad s, ISE {:.4e} rad² s, final {:+.3e} rad\n",
            m.phi.settling_time.map_or("not settled".into(), |t| format!("{t:.3} s")),
            m.phi.overshoot.map_or("—".into(), |o| format!("{:.2} %", 100.0 * o)),
            m.phi.iae,
            m.phi.ise,
            m.final_phi
        );
        s += &format!(
            "  force: peak {:.1} N (command {:.1} N), saturated {:.1} % of samples\n",
            m.peak_force,
            m.peak_force_command,
            100.0 * m.saturated_fraction
        );
        s += &format!(
            "  drift: final v_x {}, x displacement {}, distance {}",
            opt(m.final_v_x, "m/s"),
            opt(m.x_displacement, "m"),
            opt(m.drift_distance, "m")
        );
        if let Some(v) = m.final_v_y {
            s += &format!(", final v_y {v:.3e} m/s");
        }
        if let Some(w) = m.final_w_z {
            s += &format!(", final w_z {w:.3e} rad/s");
        }
        s += "\n";
        s
    }
}
