//! `twv sim`: one closed-loop run of the PID pitch controller — a tilt recovery or the
//! start/accelerate/cruise/decelerate/stop maneuver — as CSV, figures and metrics.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use serde::Serialize;
use twv_model::Model;

use super::control_args::{
    dispatch_control, parse_gains, plant, ControlTask, ControllerArgs, RunArgs,
};
use super::model::{parse_vector, to_array, LoadedModel, ModelArgs};
use crate::control::{
    run_closed_loop, scenario, ClosedLoopRun, ControllerSettings, LoopMetrics, PidLoop, Plant,
    RunEnd, RunSettings,
};
use crate::output::OutputDir;
use crate::plot::{line_chart, Chart, Series};

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ScenarioKind {
    /// Recovery from an initial state (by default a forward tilt of --phi0)
    Tilt,
    /// From rest: accelerate to --v-cruise, cruise, decelerate, stop, through the velocity loop
    Maneuver,
}

/// Velocity-loop gains of the maneuver when `--v-loop` is not given [rad per m/s, rad per m]:
/// with the study's PD inside, the outer poles are then −0.45 ± 1.08i and −0.51 (linearised,
/// paper vehicle): the fastest well-damped choice, since the inner loop's slow pole sits at
/// −1.36.
pub const MANEUVER_V_LOOP: (f64, f64) = (0.08, 0.03);

/// Simulate the closed loop: PID on the pitch Φ driving the base force (or wheel torques).
#[derive(Args, Debug)]
pub struct SimArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Scenario [default: tilt]
    #[arg(long, value_enum)]
    pub scenario: Option<ScenarioKind>,
    /// Initial state, comma-separated in the model's state order (SI units, rad) [default: at
    /// rest with Φ = --phi0 for tilt, at rest upright for maneuver]
    #[arg(long, value_name = "V1,V2,...", allow_hyphen_values = true)]
    pub x0: Option<String>,
    /// Initial pitch of the tilt scenario when --x0 is not given [rad] [default: 0.1]
    #[arg(
        long,
        value_name = "RAD",
        allow_hyphen_values = true,
        conflicts_with = "x0"
    )]
    pub phi0: Option<f64>,
    /// PID gains Kp,Ki,Kd of F = Kp e + Ki ∫e + Kd Φ̇ [N/rad, N/(rad s), N s/rad]
    /// [default: 3860,0,1980, the study's PD]
    #[arg(long, value_name = "KP,KI,KD")]
    pub gains: Option<String>,
    /// Maneuver cruise speed [m/s] [default: 2]
    #[arg(long, value_name = "M/S", allow_hyphen_values = true)]
    pub v_cruise: Option<f64>,
    /// Maneuver acceleration and deceleration time [s] [default: 3]
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub ramp: Option<f64>,
    /// Maneuver cruise time [s] [default: 5]
    #[arg(long, value_name = "S", allow_hyphen_values = true)]
    pub cruise: Option<f64>,
    #[command(flatten)]
    pub controller: ControllerArgs,
    #[command(flatten)]
    pub run: RunArgs,
    /// Write sim.csv, metrics.json and the figures (phi, phi_dot, v_x, x, force; v_y, theta
    /// when they move) into this folder
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the result as JSON on stdout
    #[arg(long)]
    pub json: bool,
}

/// A validated closed-loop experiment: what `sim` and `disturb` run.
pub struct Experiment {
    pub title: String,
    pub scenario: &'static str,
    pub controller: ControllerSettings,
    pub run: RunSettings,
    /// The initial state text (`--x0`) or, if absent, a tilt of this angle.
    pub x0: Option<String>,
    pub phi0: f64,
}

/// What `--json` prints and metrics.json holds.
#[derive(Serialize)]
pub struct SimOutput {
    pub title: String,
    pub model: String,
    pub params: String,
    pub scenario: &'static str,
    pub controller: ControllerSettings,
    pub input_map: serde_json::Value,
    pub run: RunSettings,
    pub x0: Vec<f64>,
    pub end: RunEnd,
    pub metrics: LoopMetrics,
    /// Column names of the CSV.
    #[serde(skip)]
    pub columns: Vec<String>,
    /// The CSV rows.
    #[serde(skip)]
    pub rows: Vec<Vec<f64>>,
}

impl ControlTask for &Experiment {
    type Output = SimOutput;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<SimOutput> {
        let info = model.info();
        let x0: [f64; NX] = match &self.x0 {
            Some(text) => to_array(&parse_vector("x0", text, info.states)?),
            None => scenario::tilted(info.states, self.phi0)?,
        };
        let plant: Plant<NU> = plant(model, loaded)?;
        let field = PidLoop::<_, NX, NU, NA>::new(model, &self.controller, plant)?;
        let run = run_closed_loop(&field, &x0, &self.run)?;
        let (columns, rows) = table(&field, &run);
        Ok(SimOutput {
            title: self.title.clone(),
            model: loaded.name().to_string(),
            params: loaded.params_origin.clone(),
            scenario: self.scenario,
            controller: self.controller.clone(),
            input_map: serde_json::to_value(plant)?,
            run: self.run,
            x0: x0.to_vec(),
            end: run.trajectory.end,
            metrics: run.metrics,
            columns,
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
    let v_ref = field.settings().velocity.as_ref().map(|v| &v.reference);
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
            row.extend_from_slice(&c.u[..info.inputs.len()]);
            row.extend([c.phi_ref, c.force_cmd, c.force, c.yaw]);
            row.extend(v_ref.map(|r| r.value(*t)));
            row
        })
        .collect();
    (columns, rows)
}

impl SimOutput {
    fn column(&self, name: &str) -> Option<Vec<(f64, f64)>> {
        let i = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| (r[0], r[i])).collect())
    }

    /// The time series as CSV (header = `columns`).
    pub fn csv(&self) -> String {
        let mut s = self.columns.join(",");
        s.push('\n');
        for r in &self.rows {
            let cells: Vec<String> = r.iter().map(|v| format!("{v:e}")).collect();
            s += &cells.join(",");
            s.push('\n');
        }
        s
    }

    /// (file name, SVG) of every figure: Φ (with Φ_ref), Φ̇, v_x, x, the force, and v_y, θ
    /// when they leave zero.
    pub fn figures(&self) -> Result<Vec<(String, String)>> {
        let moving = |name: &str| {
            self.column(name)
                .is_some_and(|c| c.iter().any(|(_, v)| v.abs() > 1e-12))
        };
        let mut figs = Vec::new();
        let mut add = |file: &str, what: &str, y_label: &str, cols: &[(&str, &str)]| {
            let data: Vec<(String, Vec<(f64, f64)>)> = cols
                .iter()
                .filter_map(|(c, label)| self.column(c).map(|d| (label.to_string(), d)))
                .collect();
            if data.is_empty() {
                return Ok::<(), anyhow::Error>(());
            }
            let series: Vec<Series> = data
                .iter()
                .map(|(name, points)| Series {
                    name: name.clone(),
                    points,
                })
                .collect();
            let title = format!("{} — {what}", self.title);
            let svg = line_chart(
                &Chart {
                    title: &title,
                    x_label: "t [s]",
                    y_label,
                    size: (800, 450),
                },
                &series,
            )?;
            figs.push((file.to_string(), svg));
            Ok(())
        };
        add(
            "phi.svg",
            "pitch Φ",
            "Φ [rad]",
            &[("phi", "Φ"), ("phi_ref", "Φ_ref")],
        )?;
        add("phi_dot.svg", "pitch rate Φ̇", "Φ̇ [rad/s]", &[("w_y", "Φ̇")])?;
        add(
            "v_x.svg",
            "forward velocity",
            "v_x [m/s]",
            &[("v_x", "v_x"), ("v_ref", "v_ref")],
        )?;
        add("x.svg", "displacement", "x [m]", &[("x", "x")])?;
        add(
            "force.svg",
            "force",
            "F [N]",
            &[("F", "F applied"), ("F_cmd", "F commanded")],
        )?;
        if moving("v_y") {
            add(
                "v_y.svg",
                "lateral velocity",
                "v_y [m/s]",
                &[("v_y", "v_y")],
            )?;
        }
        if moving("theta") {
            add("theta.svg", "yaw", "θ [rad]", &[("theta", "θ")])?;
        }
        Ok(figs)
    }
}

/// Write sim.csv, metrics.json and the figures (all or nothing).
pub fn write_files(dir: &Path, out: &SimOutput) -> Result<Vec<PathBuf>> {
    let figures = out.figures()?;
    let mut files = OutputDir::create(dir)?;
    files.write("sim.csv", out.csv().as_bytes())?;
    files.write(
        "metrics.json",
        serde_json::to_string_pretty(out)?.as_bytes(),
    )?;
    for (name, svg) in &figures {
        files.write(name, svg.as_bytes())?;
    }
    Ok(files.commit())
}

/// Runs an experiment on the resolved model (also used by the report).
pub fn compute(experiment: &Experiment, model: &ModelArgs) -> Result<SimOutput> {
    let loaded = model.clone().with_default("vehicle8").load()?;
    dispatch_control(&loaded, experiment.controller.n_states(), experiment)
}

/// Runs an experiment on the resolved model, writes and prints it.
pub fn execute(
    experiment: &Experiment,
    model: &ModelArgs,
    out: Option<&Path>,
    json: bool,
) -> Result<()> {
    let result = compute(experiment, model)?;
    let files = out.map(|dir| (dir, write_files as _));
    super::finish(&result, files, json, summary)
}

pub fn run(args: &SimArgs) -> Result<()> {
    let gains = match &args.gains {
        Some(text) => parse_gains("gains", text)?,
        None => crate::control::STUDY_PD,
    };
    let kind = args.scenario.unwrap_or(ScenarioKind::Tilt);
    let (profile, default_v_loop, default_t_end, scenario) = match kind {
        ScenarioKind::Tilt => {
            if args.v_cruise.is_some() || args.ramp.is_some() || args.cruise.is_some() {
                bail!("--v-cruise, --ramp and --cruise belong to --scenario maneuver");
            }
            (None, None, 10.0, "tilt")
        }
        ScenarioKind::Maneuver => {
            if args.controller.v_ref.is_some() {
                bail!("--scenario maneuver sets the velocity reference itself; drop --v-ref");
            }
            let profile = scenario::maneuver(
                args.v_cruise.unwrap_or(2.0),
                args.ramp.unwrap_or(3.0),
                args.cruise.unwrap_or(5.0),
            )?;
            let t_end = profile.t_last() + 10.0;
            (Some(profile), Some(MANEUVER_V_LOOP), t_end, "maneuver")
        }
    };
    let controller = args.controller.settings(gains, profile, default_v_loop)?;
    let phi0 = match kind {
        ScenarioKind::Tilt => args.phi0.unwrap_or(0.1),
        ScenarioKind::Maneuver => args.phi0.unwrap_or(0.0),
    };
    let g = &controller.pitch.gains;
    let experiment = Experiment {
        title: format!("{scenario}, Kp {} Ki {} Kd {}", g.kp, g.ki, g.kd),
        scenario,
        controller,
        run: args.run.settings(default_t_end)?,
        x0: args.x0.clone(),
        phi0,
    };
    execute(&experiment, &args.model, args.out.as_deref(), args.json)
}

fn opt(v: Option<f64>, unit: &str) -> String {
    v.map_or("—".into(), |v| format!("{v:.4} {unit}"))
}

/// A few readable lines.
pub fn summary(out: &SimOutput) -> String {
    let m = &out.metrics;
    let mut s = format!(
        "{} on {} ({}), {} s\n",
        out.title, out.model, out.params, out.run.t_end
    );
    if let RunEnd::Fell { t, phi } = out.end {
        s += &format!("  FELL OVER at t = {t:.3} s (Φ = {phi:.3} rad)\n");
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
