//! `twv phase`: phase portraits (Φ, Φ̇) — closed loop for several PID gain sets side by side (the
//! study's Fig. 4 a–d), or open loop under constant external forces (how the study related
//! external force to stability).

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::Args;
use serde::Serialize;
use twv_model::Model;

use super::control_args::{
    dispatch_control, parse_gains, plant, split_sets, ControlTask, ControllerArgs, RunArgs,
};
use super::model::{parse_vector, to_array, LoadedModel, ModelArgs};
use crate::control::{
    scenario, simulate, ControllerSettings, PidLoop, RunEnd, RunSettings, Trajectory,
};
use crate::integrate::{OpenLoop, VectorField};
use crate::linear::{eigenvalues, PidGains};
use crate::output::OutputDir;
use crate::plot::{line_chart, Chart, Series};

/// Phase portraits (Φ, Φ̇) for several gain sets, or for constant external forces.
#[derive(Args, Debug)]
pub struct PhaseArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Gain sets "Kp,Ki,Kd;Kp,Ki,Kd;…" [N/rad, N/(rad s), N s/rad] [default: four sets retracing
    /// the study's Fig. 4: (a) 3860,1.2e5,1980 (Ki above the Routh–Hurwitz limit: growing
    /// oscillation), (b) 3860,3e4,1980 (stable, slow oscillation), (c) 1000,0,300 (Kp < M_x g:
    /// a saddle, leaving along a line), (d) 3860,0,1980 (the study's PD)]
    #[arg(long, value_name = "SETS", conflicts_with = "force")]
    pub gains: Option<String>,
    /// Open loop instead: constant inputs "U1,U2;U1,U2;…" in the model's input order (F1 [N],
    /// T2 [N m] for vehicle8/vehicle7; τ_L, τ_R [N m] for segway7), one portrait per set
    #[arg(long, value_name = "SETS", allow_hyphen_values = true)]
    pub force: Option<String>,
    /// Initial states "x0;x0;…", each comma-separated in the model's state order [default: at
    /// rest with Φ = 0.1, −0.1, 0.2, −0.2 rad]
    #[arg(long, value_name = "STATES", allow_hyphen_values = true)]
    pub x0: Option<String>,
    #[command(flatten)]
    pub controller: ControllerArgs,
    #[command(flatten)]
    pub run: RunArgs,
    /// Write phase_1.svg … (one per set), phase.svg (all side by side), phase.csv, phase.json
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the result as JSON on stdout
    #[arg(long)]
    pub json: bool,
}

/// One portrait: a gain set (or constant input) and its trajectories.
#[derive(Serialize)]
pub struct Portrait {
    pub label: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub controller: Option<ControllerSettings>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub input: Option<Vec<f64>>,
    /// Largest real part of the non-zero eigenvalues of the closed loop at the upright (the
    /// zero ones are the drift modes no pitch loop moves) [1/s]
    pub loop_abscissa: f64,
    pub runs: Vec<PhaseRun>,
}

/// One trajectory of a portrait.
#[derive(Serialize)]
pub struct PhaseRun {
    pub x0: Vec<f64>,
    /// Initial pitch [rad].
    pub phi0: f64,
    pub end: RunEnd,
    /// (Φ, Φ̇) at the end [rad, rad/s].
    pub final_phi: f64,
    pub final_phi_dot: f64,
    #[serde(skip)]
    pub t: Vec<f64>,
    #[serde(skip)]
    pub points: Vec<(f64, f64)>,
}

/// What `--json` prints and phase.json holds.
#[derive(Serialize)]
pub struct PhaseOutput {
    pub model: String,
    pub params: String,
    pub run: RunSettings,
    pub portraits: Vec<Portrait>,
}

/// What drives one portrait.
enum Drive {
    Closed(ControllerSettings),
    Open(String),
}

struct PhaseTask<'a> {
    drive: &'a Drive,
    x0: &'a [Option<String>],
    run: &'a RunSettings,
}

fn runs<F: VectorField<N>, const N: usize>(
    field: F,
    starts: &[[f64; N]],
    phi: usize,
    w_y: usize,
    run: &RunSettings,
) -> Result<Vec<PhaseRun>> {
    starts
        .iter()
        .map(|x0| {
            let traj: Trajectory<N> = simulate(&field, x0, phi, run)?;
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

/// Largest real part of the eigenvalues of J at `x` that are not zero (drift modes).
fn loop_abscissa<F: VectorField<N>, const N: usize>(field: &F, x: &[f64; N]) -> Result<f64> {
    let mut j = [[0.0; N]; N];
    field.jacobian(0.0, x, &mut j);
    let m = nalgebra::DMatrix::from_fn(N, N, |r, c| j[r][c]);
    let scale = m.amax().max(1.0);
    Ok(eigenvalues(&m)?
        .iter()
        .filter(|e| e.norm() > 1e-9 * scale)
        .fold(f64::NEG_INFINITY, |a, e| a.max(e.re)))
}

impl ControlTask for PhaseTask<'_> {
    type Output = (
        Option<ControllerSettings>,
        Option<Vec<f64>>,
        f64,
        Vec<PhaseRun>,
    );
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<Self::Output> {
        let info = model.info();
        let starts: Vec<[f64; NX]> = self
            .x0
            .iter()
            .map(|s| match s {
                Some(text) => Ok(to_array(&parse_vector("x0", text, info.states)?)),
                None => bail!("internal: missing initial state"),
            })
            .collect::<Result<_>>()?;
        let p = plant(model, loaded)?;
        let (phi, w_y) = (p.measured.phi, p.measured.w_y);
        match self.drive {
            Drive::Closed(settings) => {
                let field = PidLoop::<_, NX, NU, NA>::new(model, settings, p)?;
                let aug: Vec<[f64; NA]> = starts.iter().map(|x| field.initial_state(x)).collect();
                let abscissa = loop_abscissa(&field, &[0.0; NA])?;
                let runs = runs(field, &aug, phi, w_y, self.run)?;
                Ok((Some(settings.clone()), None, abscissa, runs))
            }
            Drive::Open(text) => {
                let u: [f64; NU] = to_array(&parse_vector("force", text, info.inputs)?);
                let field = OpenLoop::new(model, u);
                let abscissa = loop_abscissa(&field, &[0.0; NX])?;
                let runs = runs(field, &starts, phi, w_y, self.run)?;
                Ok((None, Some(u.to_vec()), abscissa, runs))
            }
        }
    }
}

/// The portraits' figure: one curve per initial state.
fn portrait_svg(p: &Portrait, size: (u32, u32)) -> Result<String> {
    let series: Vec<Series> = p
        .runs
        .iter()
        .map(|r| Series {
            name: format!("Φ0 = {:.3}", r.phi0),
            points: &r.points,
        })
        .collect();
    Ok(line_chart(
        &Chart {
            title: &p.label,
            x_label: "Φ [rad]",
            y_label: "Φ̇ [rad/s]",
            size,
        },
        &series,
    )?)
}

/// Several SVG documents in one, on a grid of `cols` columns: each is nested as an `<svg>`
/// element at its offset (browsers and the HTML report render nested SVG natively).
fn side_by_side(docs: &[String], size: (u32, u32), cols: usize) -> String {
    let cols = cols.max(1).min(docs.len().max(1));
    let rows = docs.len().div_ceil(cols);
    let (w, h) = (size.0 as usize, size.1 as usize);
    let mut s = format!(
        "<svg width=\"{}\" height=\"{}\" viewBox=\"0 0 {} {}\" xmlns=\"http://www.w3.org/2000/svg\">\n",
        w * cols,
        h * rows,
        w * cols,
        h * rows
    );
    for (i, doc) in docs.iter().enumerate() {
        let (x, y) = ((i % cols) * w, (i / cols) * h);
        s += &doc.replacen("<svg ", &format!("<svg x=\"{x}\" y=\"{y}\" "), 1);
        s.push('\n');
    }
    s += "</svg>\n";
    s
}

/// Write the figures, phase.csv and phase.json (all or nothing).
/// One SVG per portrait (560 × 480 px each).
pub fn portrait_figures(out: &PhaseOutput) -> Result<Vec<String>> {
    out.portraits
        .iter()
        .map(|p| portrait_svg(p, PORTRAIT_SIZE))
        .collect()
}

/// The portraits side by side in one SVG (four to a row).
pub fn combined_figure(docs: &[String]) -> String {
    side_by_side(docs, PORTRAIT_SIZE, 4)
}

const PORTRAIT_SIZE: (u32, u32) = (560, 480);

pub fn write_files(dir: &Path, out: &PhaseOutput) -> Result<Vec<PathBuf>> {
    let docs = portrait_figures(out)?;
    let mut csv = String::from("set,run,t,phi,phi_dot\n");
    for (i, p) in out.portraits.iter().enumerate() {
        for (j, r) in p.runs.iter().enumerate() {
            for (t, (phi, rate)) in r.t.iter().zip(&r.points) {
                csv += &format!("{},{},{t:e},{phi:e},{rate:e}\n", i + 1, j + 1);
            }
        }
    }
    let mut files = OutputDir::create(dir)?;
    for (i, doc) in docs.iter().enumerate() {
        files.write(&format!("phase_{}.svg", i + 1), doc.as_bytes())?;
    }
    files.write("phase.svg", combined_figure(&docs).as_bytes())?;
    files.write("phase.csv", csv.as_bytes())?;
    files.write("phase.json", serde_json::to_string_pretty(out)?.as_bytes())?;
    Ok(files.commit())
}

/// Compute the portraits (also used by the report).
pub fn compute(args: &PhaseArgs) -> Result<PhaseOutput> {
    let run = args.run.settings(10.0)?;
    let loaded = args.model.clone().with_default("vehicle8").load()?;
    let drives: Vec<(String, Drive)> = match (&args.force, &args.gains) {
        (Some(_), _) if args.controller.any() => {
            bail!("--force runs the open loop: controller options do not apply")
        }
        (Some(text), _) => {
            let sets = split_sets(text);
            if sets.is_empty() {
                bail!("--force: no input sets in `{text}` (use \"F1,T2;F1,T2\")");
            }
            sets.into_iter()
                .map(|s| (format!("open loop, u = ({s})"), Drive::Open(s.to_string())))
                .collect()
        }
        (None, gains) => {
            let sets: Vec<(String, PidGains)> = match gains {
                Some(text) => {
                    let sets = split_sets(text);
                    if sets.is_empty() {
                        bail!("--gains: no gain sets in `{text}` (use \"Kp,Ki,Kd;Kp,Ki,Kd\")");
                    }
                    sets.into_iter()
                        .map(|s| {
                            let g = parse_gains("gains", s)?;
                            Ok((format!("Kp {} Ki {} Kd {}", g.kp, g.ki, g.kd), g))
                        })
                        .collect::<Result<_>>()?
                }
                None => scenario::STUDY_GAIN_SETS
                    .iter()
                    .map(|s| (s.label.to_string(), s.gains))
                    .collect(),
            };
            sets.into_iter()
                .map(|(label, g)| {
                    Ok((
                        label,
                        Drive::Closed(args.controller.settings(g, None, None)?),
                    ))
                })
                .collect::<Result<_>>()?
        }
    };
    let x0: Vec<Option<String>> = match &args.x0 {
        Some(text) => {
            let sets = split_sets(text);
            if sets.is_empty() {
                bail!("--x0: no initial states in `{text}`");
            }
            sets.into_iter().map(|s| Some(s.to_string())).collect()
        }
        None => {
            let nx = loaded.ir.nx();
            let phi = loaded.ir.states().iter().position(|s| s.name == "phi");
            let Some(phi) = phi else {
                bail!("model `{}` has no state phi", loaded.name());
            };
            [0.1, -0.1, 0.2, -0.2]
                .iter()
                .map(|p| {
                    let v: Vec<String> = (0..nx)
                        .map(|i| if i == phi { p.to_string() } else { "0".into() })
                        .collect();
                    Some(v.join(","))
                })
                .collect()
        }
    };
    let mut portraits = Vec::new();
    for (label, drive) in &drives {
        let nz = match drive {
            Drive::Closed(s) => s.n_states(),
            Drive::Open(_) => 0,
        };
        let task = PhaseTask {
            drive,
            x0: &x0,
            run: &run,
        };
        let (controller, input, loop_abscissa, runs) = dispatch_control(&loaded, nz, task)?;
        portraits.push(Portrait {
            label: label.clone(),
            controller,
            input,
            loop_abscissa,
            runs,
        });
    }
    Ok(PhaseOutput {
        model: loaded.name().to_string(),
        params: loaded.params_origin.clone(),
        run,
        portraits,
    })
}

pub fn run(args: &PhaseArgs) -> Result<()> {
    let out = compute(args)?;
    let files = args.out.as_deref().map(|dir| (dir, write_files as _));
    super::finish(&out, files, args.json, summary)
}

/// One line per portrait and per run.
pub fn summary(out: &PhaseOutput) -> String {
    let mut s = format!(
        "Phase portraits (Φ, Φ̇) of {} ({}), {} s\n",
        out.model, out.params, out.run.t_end
    );
    for p in &out.portraits {
        s += &format!(
            "{}: loop spectral abscissa {:+.4} 1/s ({})\n",
            p.label,
            p.loop_abscissa,
            if p.loop_abscissa < 0.0 {
                "stable"
            } else {
                "unstable"
            }
        );
        for r in &p.runs {
            let end = match r.end {
                RunEnd::Completed => format!(
                    "ends at (Φ, Φ̇) = ({:+.3e}, {:+.3e})",
                    r.final_phi, r.final_phi_dot
                ),
                RunEnd::Fell { t, .. } => format!("falls over at t = {t:.3} s"),
            };
            s += &format!("  Φ0 = {:+.3}: {end}\n", r.phi0);
        }
    }
    s
}
