//! What the commands share: the context (embedded vehicles, --quiet, the interrupt flag), model
//! and controller options, vector parsing, printing, writing files, and error messages.

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context as _, Result};
use clap::{Args, ValueEnum};
use serde::Serialize;
use twv_analysis::api::CancelFlag;
use twv_analysis::control::{
    AntiWindup, ControllerSettings, PitchPid, Profile, RunSettings, Setpoint, VelocityLoop, YawLoop,
};
use twv_analysis::integrate::DopriOptions;
use twv_analysis::linear::PidGains;
use twv_analysis::lyapunov::IntegratorChoice;
use twv_analysis::model::{
    Compiler, IrRuntime, ModelSource, ModelSpec, ParamSource, ResolvedModel,
};
use twv_analysis::output::Files;

use crate::progress::Bar;

/// How a command ended (errors are the `Err` of its `Result`).
#[derive(Debug)]
pub enum Outcome {
    /// Done, with a positive (or no) verdict.
    Done,
    /// Done, but the verdict is negative: the message says which; exit code 3.
    Negative(String),
    /// Interrupted; the message says what was kept; exit code 130.
    Interrupted(String),
}

/// Raised by Ctrl-C (SIGINT) or SIGTERM; jobs check it between chunks of work.
pub static CANCEL: CancelFlag = CancelFlag::new();

/// The first interrupt asks the running job to stop cleanly (a sweep then writes its
/// checkpoint); a second one exits at once.
pub fn install_interrupt_handler() {
    let _ = ctrlc::set_handler(|| {
        if CANCEL.is_raised() {
            std::process::exit(130);
        }
        CANCEL.raise();
    });
}

/// What every command may need besides its arguments.
pub struct Context {
    paper: &'static str,
    segway: &'static str,
    /// `--quiet`.
    pub quiet: bool,
}

impl Context {
    /// The context of this run.
    pub fn new(paper: &'static str, segway: &'static str, quiet: bool) -> Self {
        Self {
            paper,
            segway,
            quiet,
        }
    }

    /// The embedded default parameter file of a shipped vehicle, if it has one.
    pub fn vehicle_defaults(&self, model: &str) -> Option<ParamSource> {
        twv_analysis::model::vehicle_defaults(model, self.paper, self.segway)
    }

    /// The embedded vehicles/paper.toml.
    pub fn paper_toml(&self) -> &'static str {
        self.paper
    }

    /// A progress bar for a job (shown on a terminal after 2 s unless `--quiet`).
    pub fn bar(&self) -> Bar {
        Bar::new(!self.quiet && std::io::stderr().is_terminal(), &CANCEL)
    }

    /// An informational line on stderr, unless `--quiet`.
    pub fn say(&self, line: impl std::fmt::Display) {
        if !self.quiet {
            eprintln!("{line}");
        }
    }
}

/// The one-line message for an error: a bad setting names the command-line option.
pub fn describe(err: &anyhow::Error) -> String {
    if let Some(twv_analysis::Error::Input { field, reason }) = err.downcast_ref() {
        return format!("--{}: {reason}", field.replace('_', "-"));
    }
    format!("{err:#}")
}

/// Which model to run and with which parameters.
#[derive(Args, Debug, Clone, Default)]
pub struct ModelArgs {
    /// Shipped model: vehicle8, vehicle7, segway7, lorenz or henon_heiles [default: vehicle8]
    #[arg(long, value_name = "NAME", conflicts_with = "ir")]
    pub model: Option<String>,
    /// A model IR file (twv-ir/1) to run without recompiling twv (see --runtime)
    #[arg(long, value_name = "FILE")]
    pub ir: Option<PathBuf>,
    /// Parameter file (TOML, SI units) [default: for the vehicles vehicles/paper.toml
    /// (segway7: vehicles/segway.toml), embedded in the binary; otherwise the IR's defaults]
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// How a model without generated code (--ir, whipple) runs: `jit` compiles it to native
    /// code when it is loaded (Cranelift; the interpreter's bits), `interpreter` interprets it
    /// (the reference) [default: jit in a build with the `jit` feature, else interpreter]
    #[arg(long, value_name = "RUNTIME", value_parser = ["jit", "interpreter"])]
    pub runtime: Option<String>,
}

/// The JIT of a build with the `jit` feature.
#[cfg(feature = "jit")]
const JIT: Option<IrRuntime> = Some(IrRuntime::Compiled(Compiler {
    name: "cranelift",
    compile: |ir| twv_jit::compile(ir).map_err(|e| e.to_string()),
}));

#[cfg(not(feature = "jit"))]
const JIT: Option<IrRuntime> = None;

/// `--runtime`'s value (see [`ModelArgs::runtime`]).
fn runtime(given: Option<&str>) -> IrRuntime {
    match (given, JIT) {
        (Some("interpreter"), _) | (None, None) => IrRuntime::Interpreter,
        (_, Some(jit)) => jit,
        (Some(_), None) => IrRuntime::Compiled(Compiler {
            name: "none",
            compile: |_| {
                Err(
                    "this twv was built without the JIT: rebuild it with `--features jit` or \
                     run `--runtime interpreter`"
                        .to_string(),
                )
            },
        }),
    }
}

impl ModelArgs {
    /// The spec these arguments name.
    pub fn spec(&self, ctx: &Context) -> ModelSpec {
        let (model, shipped) = match (&self.ir, &self.model) {
            (Some(path), _) => (ModelSource::IrFile(path.clone()), None),
            (None, name) => {
                let name = name.clone().unwrap_or_else(|| "vehicle8".into());
                (ModelSource::Shipped(name.clone()), Some(name))
            }
        };
        let params = match (&self.params, shipped) {
            (Some(p), _) => ParamSource::File(p.clone()),
            (None, Some(name)) => ctx.vehicle_defaults(&name).unwrap_or_default(),
            (None, None) => ParamSource::Defaults,
        };
        ModelSpec {
            model,
            params,
            runtime: runtime(self.runtime.as_deref()),
        }
    }

    /// The resolved model.
    pub fn resolve(&self, ctx: &Context) -> Result<ResolvedModel> {
        Ok(self.spec(ctx).resolve()?)
    }
}

/// A comma-separated list of numbers for option `--{option}` (its length and finiteness are
/// checked against the model by the library, which names the component).
pub fn parse_vector(option: &str, text: &str) -> Result<Vec<f64>> {
    if text.trim().is_empty() {
        return Ok(Vec::new());
    }
    text.split(',')
        .map(|s| {
            let s = s.trim();
            s.parse::<f64>()
                .map_err(|_| anyhow!("--{option}: `{s}` is not a number"))
        })
        .collect()
}

/// `Kp,Ki,Kd` → gains.
pub fn parse_gains(option: &str, text: &str) -> Result<PidGains> {
    let v = parse_vector(option, text)?;
    let [kp, ki, kd] = v[..] else {
        bail!("--{option} wants three numbers Kp,Ki,Kd, got `{text}`");
    };
    Ok(PidGains { kp, ki, kd })
}

/// `A;B;C` → the non-empty parts, trimmed.
pub fn split_sets(text: &str) -> Vec<&str> {
    text.split(';')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .collect()
}

/// Writes `files` into `dir` (atomically, all or nothing) and names them on stderr.
pub fn write_files(ctx: &Context, dir: &Path, files: &Files) -> Result<()> {
    for path in files.write(dir)? {
        ctx.say(format!("wrote {}", path.display()));
    }
    Ok(())
}

/// Text on stdout; a failed write (a full disk, /dev/full) is an error, not a panic.
pub fn print(text: &str) -> Result<()> {
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .context("cannot write to stdout")
}

/// The result as pretty JSON, or its summary.
pub fn print_result<T: Serialize>(
    value: &T,
    json: bool,
    summary: impl FnOnce() -> String,
) -> Result<()> {
    if json {
        print(&(serde_json::to_string_pretty(value)? + "\n"))
    } else {
        print(&summary())
    }
}

/// Integrator choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Integrator {
    /// Fixed-step classical Runge–Kutta (the study's)
    Rk4,
    /// Adaptive Dormand–Prince 5(4) with dense output
    Dopri,
}

/// The integrator these options describe (`h` the RK4 step, or DOPRI's initial step).
pub fn integrator(
    kind: Option<Integrator>,
    h: Option<f64>,
    rtol: Option<f64>,
    atol: Option<f64>,
    tangent_error_control: bool,
) -> IntegratorChoice {
    match kind.unwrap_or(Integrator::Rk4) {
        Integrator::Rk4 => IntegratorChoice::Rk4 {
            h: h.unwrap_or(1e-3),
        },
        Integrator::Dopri => IntegratorChoice::Dopri(DopriOptions {
            rtol: rtol.unwrap_or(1e-9),
            atol: atol.unwrap_or(1e-12),
            tangent_error_control,
            h_init: h,
            ..DopriOptions::default()
        }),
    }
}

/// Controller options besides the gains.
#[derive(Args, Debug, Clone, Default)]
pub struct ControllerArgs {
    /// Pitch setpoint Φ_ref: `study` (0.03·sin Φ, the study's), `zero`, `sine:A` (A·sin Φ) or a
    /// constant angle in rad [default: study]
    #[arg(long, value_name = "SETPOINT", allow_hyphen_values = true)]
    pub setpoint: Option<String>,
    /// First-order filter on the measured pitch rate, time constant [s] [default: none]
    #[arg(long, value_name = "S")]
    pub rate_filter: Option<f64>,
    /// Force limit |F| ≤ F_MAX [N] (for segway7 the total wheel torque is F·R) [default: none]
    #[arg(long, value_name = "N")]
    pub f_max: Option<f64>,
    /// Anti-windup when saturated: none, conditional (clamping) or back-calc [default: conditional]
    #[arg(long, value_enum, value_name = "KIND")]
    pub anti_windup: Option<AntiWindupKind>,
    /// Back-calculation tracking time [s] [default: 0.3]
    #[arg(long, value_name = "S")]
    pub tracking_time: Option<f64>,
    /// Forward-velocity outer loop gains KP,KI [rad per m/s, rad per m]: leans the pitch
    /// setpoint by KP·(v_ref − v_x) + KI·∫(v_ref − v_x) dt [default: no velocity loop; the
    /// maneuver scenario uses 0.08,0.03]
    #[arg(long, value_name = "KP,KI", allow_hyphen_values = true)]
    pub v_loop: Option<String>,
    /// Constant forward-velocity reference for the velocity loop [m/s] [default: 0]
    #[arg(long, value_name = "M/S")]
    pub v_ref: Option<f64>,
    /// Largest lean the velocity loop may ask for [rad] (its integral holds while limited)
    /// [default: no limit]
    #[arg(long, value_name = "RAD")]
    pub lean_max: Option<f64>,
    /// Yaw-rate loop gain [N m per rad/s]: T = KP·(r_ref − w_z) on T2 (differential wheel torque
    /// for segway7) [default: no yaw loop]
    #[arg(long, value_name = "KP")]
    pub yaw_kp: Option<f64>,
    /// Constant yaw-rate reference for the yaw loop [rad/s] [default: 0]
    #[arg(long, value_name = "RAD/S")]
    pub yaw_ref: Option<f64>,
}

/// Anti-windup choice.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum AntiWindupKind {
    /// The integral runs on while saturated
    None,
    /// Stop integrating while saturated and the error pushes further into saturation
    Conditional,
    /// Pull the integral back by (F − F_cmd)/(Ki·T_t)
    BackCalc,
}

fn parse_setpoint(text: &str) -> Result<Setpoint> {
    let t = text.trim();
    Ok(match t {
        "study" => Setpoint::STUDY,
        "zero" | "0" => Setpoint::Zero,
        _ => match t.strip_prefix("sine:") {
            Some(a) => Setpoint::Sine {
                amplitude: a
                    .trim()
                    .parse()
                    .with_context(|| format!("--setpoint sine:A: `{a}` is not a number"))?,
            },
            None => Setpoint::Constant {
                value: t.parse().with_context(|| {
                    format!("--setpoint `{t}`: use study, zero, sine:A or an angle in rad")
                })?,
            },
        },
    })
}

impl ControllerArgs {
    /// Whether any controller option was given (an open-loop command must not ignore them).
    pub fn any(&self) -> bool {
        self.setpoint.is_some()
            || self.rate_filter.is_some()
            || self.f_max.is_some()
            || self.anti_windup.is_some()
            || self.tracking_time.is_some()
            || self.v_loop.is_some()
            || self.v_ref.is_some()
            || self.lean_max.is_some()
            || self.yaw_kp.is_some()
            || self.yaw_ref.is_some()
    }

    /// The validated controller with `gains`; `default_v_loop` gives the velocity loop's gains
    /// when `--v-loop` is absent (the maneuver's).
    pub fn settings(
        &self,
        gains: PidGains,
        default_v_loop: Option<(f64, f64)>,
    ) -> Result<ControllerSettings> {
        let anti_windup = match self.anti_windup.unwrap_or(AntiWindupKind::Conditional) {
            AntiWindupKind::None => AntiWindup::None,
            AntiWindupKind::Conditional => AntiWindup::Conditional,
            AntiWindupKind::BackCalc => AntiWindup::BackCalculation {
                tracking_time: self.tracking_time.unwrap_or(0.3),
            },
        };
        if self.tracking_time.is_some() && self.anti_windup != Some(AntiWindupKind::BackCalc) {
            bail!("--tracking-time needs --anti-windup back-calc");
        }
        let v_gains = match &self.v_loop {
            Some(text) => {
                let v = parse_vector("v-loop", text)?;
                let [kp, ki] = v[..] else {
                    bail!("--v-loop wants two numbers KP,KI, got `{text}`");
                };
                Some((kp, ki))
            }
            None => default_v_loop,
        };
        if self.v_ref.is_some() && v_gains.is_none() {
            bail!("--v-ref needs the velocity loop: give --v-loop KP,KI");
        }
        if self.lean_max.is_some() && v_gains.is_none() {
            bail!("--lean-max needs the velocity loop: give --v-loop KP,KI");
        }
        let velocity = v_gains.map(|(kp, ki)| VelocityLoop {
            kp,
            ki,
            reference: Profile::constant(self.v_ref.unwrap_or(0.0)),
            lean_max: self.lean_max,
        });
        if self.yaw_ref.is_some() && self.yaw_kp.is_none() {
            bail!("--yaw-ref needs the yaw loop: give --yaw-kp KP");
        }
        let yaw = self.yaw_kp.map(|kp| YawLoop {
            kp,
            reference: Profile::constant(self.yaw_ref.unwrap_or(0.0)),
        });
        let settings = ControllerSettings {
            pitch: PitchPid {
                gains,
                setpoint: match &self.setpoint {
                    Some(text) => parse_setpoint(text)?,
                    None => Setpoint::STUDY,
                },
                derivative_filter: self.rate_filter,
                saturation: self.f_max,
                anti_windup,
            },
            velocity,
            yaw,
        };
        settings.validate()?;
        Ok(settings)
    }
}

/// Length, sampling and integrator of a run.
#[derive(Args, Debug, Clone, Default)]
pub struct RunArgs {
    /// Simulated time [s] [default: 10; for the maneuver its length + 10]
    #[arg(long, value_name = "S")]
    pub t_end: Option<f64>,
    /// Output sample interval of the CSV and figures [s] [default: 0.01]
    #[arg(long, value_name = "S")]
    pub sample: Option<f64>,
    /// Integrator [default: rk4]
    #[arg(long, value_enum)]
    pub integrator: Option<Integrator>,
    /// RK4 step (≤ the sample interval), or the DOPRI initial step [s] [default: 1e-3]
    #[arg(long, value_name = "S")]
    pub h: Option<f64>,
    /// DOPRI relative tolerance [default: 1e-9]
    #[arg(long, value_name = "TOL")]
    pub rtol: Option<f64>,
    /// DOPRI absolute tolerance [default: 1e-12]
    #[arg(long, value_name = "TOL")]
    pub atol: Option<f64>,
    /// Stop the run when |Φ| exceeds this angle: the vehicle fell over [rad]; `inf` runs on
    /// [default: 1.5708 (π/2)]
    #[arg(long, value_name = "RAD")]
    pub fall_angle: Option<f64>,
}

impl RunArgs {
    /// The run settings (validated by the library); `t_end` defaults to `default_t_end`.
    pub fn settings(&self, default_t_end: f64) -> RunSettings {
        RunSettings {
            t_end: self.t_end.unwrap_or(default_t_end),
            sample: self.sample.unwrap_or(0.01),
            integrator: integrator(self.integrator, self.h, self.rtol, self.atol, false),
            fall_angle: match self.fall_angle {
                Some(a) if a == f64::INFINITY => None,
                Some(a) => Some(a),
                None => RunSettings::default().fall_angle,
            },
        }
    }
}
