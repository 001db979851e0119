//! `twv lyap`: the Lyapunov spectrum of a model, with the diagnostics that say how far to trust
//! it, as JSON and as files (running estimates CSV + figure, result JSON).

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use serde::Serialize;
use twv_model::Model;

use super::control_args::{dispatch_control, parse_gains, plant, ControlTask, ControllerArgs};
use super::model::{dispatch, parse_vector, to_array, LoadedModel, ModelArgs, ModelTask};
use crate::control::{ControllerSettings, PidLoop};
use crate::integrate::{DopriOptions, OpenLoop, VectorField};
use crate::lyapunov::{
    lyapunov_spectrum, InitialBasis, IntegratorChoice, LyapunovResult, LyapunovSettings,
};
use crate::output::OutputDir;
use crate::plot::{line_chart, Chart, Series};

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Integrator {
    /// Fixed-step classical Runge–Kutta (the study's)
    Rk4,
    /// Adaptive Dormand–Prince 5(4) with dense output
    Dopri,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Preset {
    /// The study's setting: T = 0.1 s, K = 100 iterations, RK4 with h = 1e-3 s
    Paper,
}

/// Compute a Lyapunov spectrum (Benettin–QR) with running estimates and error bars.
#[derive(Args, Debug)]
pub struct LyapArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Initial state, comma-separated, in the model's state order (SI units, rad)
    #[arg(long, value_name = "V1,V2,...", allow_hyphen_values = true)]
    pub x0: String,
    /// Constant input, comma-separated (N, N m) [default: zeros]
    #[arg(
        long,
        value_name = "U1,...",
        allow_hyphen_values = true,
        conflicts_with = "gains"
    )]
    pub u: Option<String>,
    /// Closed loop: PID pitch gains Kp,Ki,Kd [N/rad, N/(rad s), N s/rad]; the spectrum is then
    /// that of the augmented system (model states, then controller states, which start at 0)
    /// [default: open loop]
    #[arg(long, value_name = "KP,KI,KD")]
    pub gains: Option<String>,
    /// Controller options (with --gains)
    #[command(flatten)]
    pub controller: ControllerArgs,
    /// Start from a preset; the options below override it
    #[arg(long, value_enum)]
    pub preset: Option<Preset>,
    /// Re-orthonormalisation interval T [s] [default: 0.1]
    #[arg(long, value_name = "S")]
    pub t_sample: Option<f64>,
    /// Number of intervals K averaged over [default: 100]
    #[arg(long, value_name = "K")]
    pub iterations: Option<usize>,
    /// RK4 step, or the DOPRI initial step [s] [default: 1e-3]
    #[arg(long, value_name = "S")]
    pub h: Option<f64>,
    /// Integrator [default: rk4]
    #[arg(long, value_enum)]
    pub integrator: Option<Integrator>,
    /// DOPRI relative tolerance [default: 1e-9]
    #[arg(long, value_name = "TOL")]
    pub rtol: Option<f64>,
    /// DOPRI absolute tolerance [default: 1e-12]
    #[arg(long, value_name = "TOL")]
    pub atol: Option<f64>,
    /// Include the tangent vectors in DOPRI's error control
    #[arg(long)]
    pub tangent_error_control: bool,
    /// Time discarded before averaging [s] [default: 0]
    #[arg(long, value_name = "S")]
    pub transient: Option<f64>,
    /// Number of exponents: 1, 2, 3 or the full spectrum [default: all]
    #[arg(long, value_name = "K")]
    pub k: Option<usize>,
    /// Random orthonormal initial tangent basis from this seed [default: identity basis]
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// Write lyapunov.json, running.csv and running.svg into this folder
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the result as JSON on stdout
    #[arg(long)]
    pub json: bool,
    /// Repeat the computation N times and report the wall time per run (benchmarking)
    #[arg(long, value_name = "N")]
    pub timing: Option<usize>,
}

impl LyapArgs {
    /// The validated settings these arguments describe.
    pub fn settings(&self) -> Result<LyapunovSettings> {
        let mut s = match self.preset {
            Some(Preset::Paper) => LyapunovSettings::preset_paper(),
            None => LyapunovSettings::default(),
        };
        if let Some(t) = self.t_sample {
            s.t_sample = t;
        }
        if let Some(k) = self.iterations {
            s.iterations = k;
        }
        if let Some(t) = self.transient {
            s.transient = t;
        }
        let h = self.h.unwrap_or(1e-3);
        s.integrator = match self.integrator.unwrap_or(Integrator::Rk4) {
            Integrator::Rk4 => IntegratorChoice::Rk4 { h },
            Integrator::Dopri => IntegratorChoice::Dopri(DopriOptions {
                rtol: self.rtol.unwrap_or(1e-9),
                atol: self.atol.unwrap_or(1e-12),
                tangent_error_control: self.tangent_error_control,
                h_init: self.h,
                ..DopriOptions::default()
            }),
        };
        if let Some(seed) = self.seed {
            s.basis = InitialBasis::Random { seed };
        }
        // Batch means need at least two intervals per batch count; short runs use fewer batches.
        s.batches = s.batches.min(s.iterations).max(2);
        s.validate()?;
        Ok(s)
    }
}

/// What `--json` prints.
#[derive(Serialize)]
pub struct LyapOutput {
    pub model: String,
    pub params: String,
    pub x0: Vec<f64>,
    pub u: Vec<f64>,
    pub settings: LyapunovSettings,
    /// The controller of a closed-loop spectrum (`x0` then includes its states).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub controller: Option<ControllerSettings>,
    #[serde(flatten)]
    pub result: LyapunovResult,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub timing: Option<Timing>,
}

#[derive(Serialize)]
pub struct Timing {
    pub runs: usize,
    pub seconds_per_run: f64,
}

struct Lyap<'a> {
    args: &'a LyapArgs,
    settings: LyapunovSettings,
}

/// The spectrum with `k` exponents: one tangent vector for k = 1 (the cheap largest exponent),
/// otherwise the full spectrum, cut to the `k` largest (the same values: the first k columns of
/// a QR do not depend on the others), so each model needs only two instantiations.
fn spectrum<F: VectorField<N>, const N: usize>(
    field: &F,
    x0: &[f64; N],
    k: usize,
    settings: &LyapunovSettings,
) -> Result<LyapunovResult> {
    let result = match k {
        1 => lyapunov_spectrum::<_, N, 1>(field, x0, settings)?,
        k if (2..=N).contains(&k) => lyapunov_spectrum::<_, N, N>(field, x0, settings)?.largest(k),
        k => bail!("--k {k}: choose 1 to {N} (the full spectrum)"),
    };
    Ok(result)
}

/// The spectrum, repeated `--timing` times for the wall time per run.
fn timed_spectrum<F: VectorField<N>, const N: usize>(
    args: &LyapArgs,
    field: &F,
    x0: &[f64; N],
    settings: &LyapunovSettings,
) -> Result<(LyapunovResult, Option<Timing>)> {
    let k = args.k.unwrap_or(N);
    let mut result = spectrum(field, x0, k, settings)?;
    let timing = match args.timing {
        Some(0) => bail!("--timing needs at least one run"),
        Some(runs) => {
            let start = Instant::now();
            for _ in 0..runs {
                result = spectrum(field, x0, k, settings)?;
            }
            Some(Timing {
                runs,
                seconds_per_run: start.elapsed().as_secs_f64() / runs as f64,
            })
        }
        None => None,
    };
    Ok((result, timing))
}

impl ModelTask for Lyap<'_> {
    type Output = LyapOutput;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<LyapOutput> {
        let info = model.info();
        let x0: [f64; NX] = to_array(&parse_vector("x0", &self.args.x0, info.states)?);
        let u: [f64; NU] = match &self.args.u {
            Some(text) => to_array(&parse_vector("u", text, info.inputs)?),
            None => [0.0; NU],
        };
        let field = OpenLoop::new(model, u);
        let (result, timing) = timed_spectrum(self.args, &field, &x0, &self.settings)?;
        Ok(LyapOutput {
            model: loaded.name().to_string(),
            params: loaded.params_origin.clone(),
            x0: x0.to_vec(),
            u: u.to_vec(),
            settings: self.settings,
            controller: None,
            result,
            timing,
        })
    }
}

/// The closed-loop branch: the same spectrum of the model under the PID controller, an
/// augmented field on NA = NX + (controller states).
struct ClosedLyap<'a> {
    args: &'a LyapArgs,
    settings: LyapunovSettings,
    controller: ControllerSettings,
}

impl ControlTask for ClosedLyap<'_> {
    type Output = LyapOutput;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<LyapOutput> {
        let x0: [f64; NX] = to_array(&parse_vector("x0", &self.args.x0, model.info().states)?);
        let field = PidLoop::<_, NX, NU, NA>::new(model, &self.controller, plant(model, loaded)?)?;
        let xa = field.initial_state(&x0);
        let (result, timing) = timed_spectrum(self.args, &field, &xa, &self.settings)?;
        Ok(LyapOutput {
            model: format!("{} (closed loop)", loaded.name()),
            params: loaded.params_origin.clone(),
            x0: xa.to_vec(),
            u: Vec::new(),
            settings: self.settings,
            controller: Some(self.controller),
            result,
            timing,
        })
    }
}

/// The running-estimates figure (the study's Fig. 3).
pub fn running_figure(out: &LyapOutput) -> Result<String> {
    let running = &out.result.running;
    let curves: Vec<Vec<(f64, f64)>> = (0..running.k)
        .map(|j| {
            (0..running.len())
                .map(|i| (running.t[i], running.row(i)[j]))
                .collect()
        })
        .collect();
    let series: Vec<Series> = curves
        .iter()
        .enumerate()
        .map(|(j, pts)| Series {
            name: format!("λ{}", j + 1),
            points: pts,
        })
        .collect();
    let title = format!("Lyapunov exponents of {}: running estimates", out.model);
    Ok(line_chart(
        &Chart {
            title: &title,
            x_label: "t [s]",
            y_label: "λ [1/s]",
            size: (900, 520),
        },
        &series,
    )?)
}

/// Write lyapunov.json, running.csv and running.svg (all or nothing).
pub fn write_files(dir: &std::path::Path, out: &LyapOutput) -> Result<Vec<PathBuf>> {
    let mut files = OutputDir::create(dir)?;
    files.write(
        "lyapunov.json",
        serde_json::to_string_pretty(out)?.as_bytes(),
    )?;
    let mut csv = Vec::new();
    out.result
        .running
        .write_csv(&mut csv)
        .context("running estimates CSV")?;
    files.write("running.csv", &csv)?;
    files.write("running.svg", running_figure(out)?.as_bytes())?;
    Ok(files.commit())
}

/// Compute the spectrum these arguments describe (also used by the report).
pub fn compute(args: &LyapArgs) -> Result<LyapOutput> {
    let settings = args.settings()?;
    let loaded = args.model.clone().with_default("vehicle8").load()?;
    Ok(match &args.gains {
        Some(text) => {
            let controller = args
                .controller
                .settings(parse_gains("gains", text)?, None, None)?;
            let nz = controller.n_states();
            let task = ClosedLyap {
                args,
                settings,
                controller,
            };
            dispatch_control(&loaded, nz, task)?
        }
        None if args.controller.any() => {
            bail!("controller options (--setpoint, --f-max, --v-loop, …) need --gains")
        }
        None => dispatch(&loaded, Lyap { args, settings })?,
    })
}

pub fn run(args: &LyapArgs) -> Result<()> {
    let out = compute(args)?;
    let files = args.out.as_deref().map(|dir| (dir, write_files as _));
    super::finish(&out, files, args.json, summary)
}

/// A few readable lines.
pub fn summary(out: &LyapOutput) -> String {
    let r = &out.result;
    let mut s = format!(
        "Lyapunov spectrum of {} over {:.3} s ({})\n",
        out.model, r.t_total, out.params
    );
    for (i, (l, e)) in r.exponents.iter().zip(&r.stderr).enumerate() {
        s += &format!("  λ{:<2} = {:+.6} ± {:.6} 1/s\n", i + 1, l, e);
    }
    s += &format!("  Σλ = {:+.3e}", r.sum);
    if let Some(tr) = r.mean_trace {
        s += &format!("   ⟨tr J⟩ = {tr:+.3e}");
    }
    s += "\n";
    if let Some(ky) = r.kaplan_yorke {
        s += &format!("  Kaplan–Yorke dimension {ky:.4}\n");
    }
    s += &format!("  {}\n", r.classification);
    s
}
