//! `twv linear`: A, B from the generated Jacobians, the modes, the pitch loop's closed-loop
//! spectrum and margins, and an LQR design for comparison.

use anyhow::{bail, Result};
use clap::Args;
use nalgebra::DMatrix;
use serde::Serialize;
use twv_model::Model;

use super::control_args::parse_gains;
use super::model::{dispatch, parse_vector, to_array, LoadedModel, ModelArgs, ModelTask};
use crate::control::Plant;
use crate::linear::{
    analyse_pitch, linearize, lqr, modes, Linearization, LoopOptions, Lqr, Mode, OperatingPoint,
    PidGains, PitchAnalysis, PitchLoop,
};

/// The cart–pendulum part of a vehicle, on which the LQR is designed (y, θ, v_y, w_z are not
/// reachable by the pitch force).
const LQR_STATES: [&str; 4] = ["phi", "x", "w_y", "v_x"];

/// What sits between the controller and the vehicle (shared by `linear` and `tune`).
#[derive(Args, Debug, Clone)]
pub struct LoopArgs {
    /// First-order actuator lag in the loop [s]
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub actuator_lag: f64,
    /// Pure delay in the loop [s]
    #[arg(
        long,
        value_name = "S",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    pub delay: f64,
}

/// Linear analysis at an equilibrium: modes, pitch-loop margins, LQR.
#[derive(Args, Debug, Clone)]
pub struct LinearArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Operating point: upright, hanging, or a state V1,V2,... (SI units, rad)
    #[arg(
        long,
        value_name = "POINT",
        default_value = "upright",
        allow_hyphen_values = true
    )]
    pub at: String,
    /// Pitch PID gains Kp,Ki,Kd [N/rad, N/(rad s), N s/rad]; the study's PD by default
    #[arg(long, value_name = "KP,KI,KD", default_value = "3860,0,1980")]
    pub gains: String,
    #[command(flatten)]
    pub loop_options: LoopArgs,
    /// LQR state weight (the same for phi, x, w_y, v_x)
    #[arg(
        long,
        value_name = "Q",
        default_value_t = 1.0,
        allow_hyphen_values = true
    )]
    pub lqr_q: f64,
    /// LQR input weight [1/N²]
    #[arg(
        long,
        value_name = "R",
        default_value_t = 1e-4,
        allow_hyphen_values = true
    )]
    pub lqr_r: f64,
    /// Print JSON instead of the summary
    #[arg(long)]
    pub json: bool,
}

/// Everything `twv linear` finds.
#[derive(Debug, Clone, Serialize)]
pub struct LinearReport {
    pub model: String,
    pub params: String,
    pub at: Vec<f64>,
    /// max |f| at the operating point (0 at an equilibrium).
    pub residual: f64,
    pub open_loop: Vec<Mode>,
    pub gains: PidGains,
    pub loop_options: LoopOptions,
    pub pitch: PitchAnalysis,
    pub lqr_states: Vec<String>,
    pub lqr: Option<Lqr>,
    /// Why there is no LQR design, if there is none.
    pub lqr_note: Option<String>,
}

struct Linear<'a>(&'a LinearArgs);

fn operating_point<const NX: usize>(text: &str, states: &[&str]) -> Result<OperatingPoint<NX>> {
    Ok(match text {
        "upright" => OperatingPoint::Upright,
        "hanging" => OperatingPoint::Hanging,
        other => OperatingPoint::State(to_array(&parse_vector("at", other, states)?)),
    })
}

/// The pitch loop of `lin`: the force F acts along the input direction the controller uses
/// (F1, or equal wheel torques for segway7).
pub fn pitch_loop<const NX: usize, const NU: usize>(
    lin: &Linearization<NX, NU>,
    info: &twv_model::ModelInfo,
    loaded: &LoadedModel,
) -> Result<PitchLoop> {
    let plant = Plant::<NU>::from_info(info, |n| loaded.param(n))?;
    Ok(PitchLoop::from_linearization(lin, &plant.inputs.force)?)
}

impl ModelTask for Linear<'_> {
    type Output = LinearReport;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<LinearReport> {
        let args = self.0;
        let info = model.info();
        let at = operating_point::<NX>(&args.at, info.states)?;
        let lin = linearize(model, &at, &[0.0; NU])?;
        let (a, _) = lin.dynamic();
        let open_loop = modes(&a, &lin.states)?;
        let gains = parse_gains("gains", &args.gains)?;
        let loop_options = LoopOptions {
            lag: args.loop_options.actuator_lag,
            delay: args.loop_options.delay,
        };
        let pitch = analyse_pitch(&pitch_loop(&lin, &info, loaded)?, &gains, &loop_options)?;
        if !(args.lqr_q > 0.0 && args.lqr_r > 0.0) {
            bail!("--lqr-q and --lqr-r must be positive");
        }
        let (lqr, lqr_note) = match lin.subsystem(&LQR_STATES) {
            Ok((a_sub, b_sub)) => {
                // Only the model's own inputs (an interpreted model may carry padding ones).
                let nu = info.inputs.len();
                let b_sub = b_sub.columns(0, nu).into_owned();
                let q = DMatrix::identity(LQR_STATES.len(), LQR_STATES.len()) * args.lqr_q;
                let r = DMatrix::identity(nu, nu) * args.lqr_r;
                (Some(lqr(&a_sub, &b_sub, &q, &r)?), None)
            }
            Err(e) => (None, Some(e.to_string())),
        };
        Ok(LinearReport {
            model: loaded.name().to_string(),
            params: loaded.params_origin.clone(),
            at: lin.x0.to_vec(),
            residual: lin.residual,
            open_loop,
            gains,
            loop_options,
            pitch,
            lqr_states: LQR_STATES.iter().map(|s| s.to_string()).collect(),
            lqr,
            lqr_note,
        })
    }
}

/// Run the analysis (also used by the report).
pub fn analyse(args: &LinearArgs) -> Result<LinearReport> {
    let loaded = args.model.clone().with_default("vehicle8").load()?;
    dispatch(&loaded, Linear(args))
}

fn complex(c: &nalgebra::Complex<f64>) -> String {
    if c.im.abs() < 1e-12 * c.re.abs().max(1.0) {
        format!("{:+.6}", c.re)
    } else {
        format!(
            "{:+.6} {} {:.6}i",
            c.re,
            if c.im < 0.0 { '-' } else { '+' },
            c.im.abs()
        )
    }
}

/// A readable summary.
pub fn summary(r: &LinearReport) -> String {
    let mut s = format!(
        "linear analysis of {} ({}), residual {:.1e}\n",
        r.model, r.params, r.residual
    );
    s += "  open-loop modes:\n";
    // Repeated eigenvalues share one eigenspace: print each group once with its multiplicity.
    let mut i = 0;
    while i < r.open_loop.len() {
        let m = &r.open_loop[i];
        let same = r.open_loop[i..]
            .iter()
            .take_while(|n| n.kind == m.kind && n.states == m.states)
            .count();
        let value = if same > 1 {
            format!("{} (×{same})", complex(&m.eigenvalue))
        } else {
            complex(&m.eigenvalue)
        };
        s += &format!("    {value:<28} {:?} ({})\n", m.kind, m.states.join(", "));
        i += same;
    }
    let g = &r.gains;
    let cl = &r.pitch.closed_loop;
    s += &format!(
        "  pitch loop Kp = {}, Ki = {}, Kd = {}: {}\n",
        g.kp,
        g.ki,
        g.kd,
        if cl.stable { "stable" } else { "UNSTABLE" }
    );
    s += &format!(
        "    loop poles: {}\n",
        cl.loop_eigenvalues
            .iter()
            .map(complex)
            .collect::<Vec<_>>()
            .join(", ")
    );
    for h in &cl.hidden {
        s += &format!(
            "    uncontrolled ({:?}): {} ({})\n",
            h.kind,
            h.eigenvalues
                .iter()
                .map(complex)
                .collect::<Vec<_>>()
                .join(", "),
            h.states.join(", ")
        );
    }
    let m = &r.pitch.margins;
    s += &format!(
        "    gain margin [{:.4}, {:.4}], phase margin {:.2}° at {:.3} rad/s, delay margin {:.4} s\n",
        m.gain_margin_lower, m.gain_margin_upper, m.phase_margin_deg, m.phase_margin_frequency, m.delay_margin
    );
    s += &format!(
        "    disk margin α = {:.4}: gain [{:.4}, {:.4}], phase ±{:.2}°; peak |S| = {:.3}\n",
        m.disk.alpha, m.disk.gain_low, m.disk.gain_high, m.disk.phase_deg, m.peak_sensitivity
    );
    match (&r.lqr, &r.lqr_note) {
        (Some(l), _) => {
            s += &format!(
                "  LQR on ({}): {:?}, residual {:.1e}, K = {:.4}",
                r.lqr_states.join(", "),
                l.status,
                l.residual,
                l.k
            );
            s += &format!(
                "    closed-loop poles: {}\n",
                l.closed_loop_eigenvalues
                    .iter()
                    .map(complex)
                    .collect::<Vec<_>>()
                    .join(", ")
            );
        }
        (None, Some(note)) => s += &format!("  LQR: not designed ({note})\n"),
        (None, None) => {}
    }
    s
}

pub fn run(args: &LinearArgs) -> Result<()> {
    super::finish(&analyse(args)?, None, args.json, summary)
}
