//! `twv lyap`: the Lyapunov spectrum of a model, with the diagnostics that say how far to trust
//! it, as JSON and as files (running estimates CSV + figure, result JSON).

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use twv_analysis::api::{spectrum, SpectrumSettings};
use twv_analysis::lyapunov::{InitialBasis, LyapunovSettings};

use super::interrupted_or;
use crate::common::{
    integrator, parse_gains, parse_vector, print_result, write_files, Context, ControllerArgs,
    Integrator, ModelArgs, Outcome,
};

/// A starting point for the settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Preset {
    /// The study's setting: T = 0.1 s, K = 100 iterations, RK4 with h = 1e-3 s
    Paper,
}

/// Compute a Lyapunov spectrum (Benettin–QR) with running estimates and error bars.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
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
    #[arg(long, value_name = "S", alias = "t-sample")]
    pub qr_interval: Option<f64>,
    /// Number of intervals K averaged over [default: 100]
    #[arg(long, value_name = "K")]
    pub iterations: Option<usize>,
    /// RK4 step (≤ the QR interval), or the DOPRI initial step [s] [default: 1e-3]
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
    /// Number of exponents, 1 to the state dimension [default: all]
    #[arg(long, value_name = "K")]
    pub k: Option<usize>,
    /// Random orthonormal initial tangent basis from this seed [default: identity basis]
    #[arg(long, value_name = "S")]
    pub seed: Option<u64>,
    /// Absolute floor of the sign tests [1/s] [default: ln(K²)/T over the horizon T]
    #[arg(long, value_name = "RATE")]
    pub zero_floor: Option<f64>,
    /// Write lyapunov.json, running.csv and running.svg/.png into this folder
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
    /// The Lyapunov settings these arguments describe (validated by the library).
    fn lyapunov(&self) -> LyapunovSettings {
        let mut s = match self.preset {
            Some(Preset::Paper) => LyapunovSettings::preset_paper(),
            None => LyapunovSettings::default(),
        };
        if let Some(t) = self.qr_interval {
            s.t_sample = t;
        }
        if let Some(k) = self.iterations {
            s.iterations = k;
        }
        if let Some(t) = self.transient {
            s.transient = t;
        }
        s.integrator = integrator(
            self.integrator,
            self.h,
            self.rtol,
            self.atol,
            self.tangent_error_control,
        );
        if let Some(seed) = self.seed {
            s.basis = InitialBasis::Random { seed };
        }
        s.zero_floor = self.zero_floor;
        // Running estimates only when they are written.
        s.record_running = self.out.is_some();
        s
    }
}

pub fn run(args: &LyapArgs, ctx: &Context) -> Result<Outcome> {
    let model = args.model.resolve(ctx)?;
    let controller = match &args.gains {
        Some(text) => Some(
            args.controller
                .settings(parse_gains("gains", text)?, None)?,
        ),
        None if args.controller.any() => {
            bail!("controller options (--setpoint, --f-max, --v-loop, …) need --gains")
        }
        None => None,
    };
    let settings = SpectrumSettings {
        x0: parse_vector("x0", &args.x0)?,
        u: args
            .u
            .as_deref()
            .map(|u| parse_vector("u", u))
            .transpose()?,
        controller,
        lyapunov: args.lyapunov(),
        exponents: args.k,
        repeat: args.timing,
    };
    let bar = ctx.bar();
    let out = match interrupted_or(spectrum(&model, &settings, &bar), "the spectrum")? {
        Ok(out) => out,
        Err(outcome) => return Ok(outcome),
    };
    if let Some(dir) = &args.out {
        write_files(ctx, dir, &out.files()?)?;
    }
    print_result(&out, args.json, || out.summary())?;
    Ok(Outcome::Done)
}
