//! What one request may ask for. The library validates that settings make sense; these bound
//! how much work they may cost, so that no request ties a worker up for more than a few
//! seconds: a request over a limit is refused with the limit named, not started.

use serde::Serialize;
use twv_analysis::api::{LinearSettings, SimSettings, SweepSettings, TuneSettings};
use twv_analysis::control::RunSettings;
use twv_analysis::lyapunov::IntegratorChoice;

/// Largest request body [bytes].
pub const MAX_BODY: usize = 256 * 1024;
/// Largest model time of one run [s].
pub const MAX_HORIZON: f64 = 120.0;
/// Most integration steps of one run (an adaptive run counted at its smallest step).
pub const MAX_STEPS: f64 = 500_000.0;
/// Most samples one run returns.
pub const MAX_SAMPLES: f64 = 50_000.0;
/// Largest initial tilt [rad]: half a turn (beyond it the pendulum hangs below).
pub const MAX_TILT: f64 = std::f64::consts::PI;
/// Most initial tilts of a phase portrait.
pub const MAX_TILTS: usize = 16;
/// Most points of one map request (the page asks row by row).
pub const MAX_MAP_POINTS: usize = 2_500;
/// Most integration steps of one map request, all points together.
pub const MAX_MAP_STEPS: f64 = 2.5e7;
/// Most points of a frequency response.
pub const MAX_FREQUENCY_POINTS: usize = 5_000;
/// Most requirements of a tuning spec.
pub const MAX_REQUIREMENTS: usize = 16;
/// Most iterations and grid points per decade of a tuning.
pub const MAX_TUNE_ITERATIONS: usize = 500;
pub const MAX_TUNE_POINTS_PER_DECADE: usize = 2_000;

/// The limits, for `GET /api/model` (the page and scripts read them).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Limits {
    pub max_body_bytes: usize,
    pub max_horizon: f64,
    pub max_steps: f64,
    pub max_samples: f64,
    pub max_tilt: f64,
    pub max_tilts: usize,
    pub max_map_points: usize,
    pub max_map_steps: f64,
    pub max_requirements: usize,
    pub max_frequency_points: usize,
}

/// The limits in force.
pub const LIMITS: Limits = Limits {
    max_body_bytes: MAX_BODY,
    max_horizon: MAX_HORIZON,
    max_steps: MAX_STEPS,
    max_samples: MAX_SAMPLES,
    max_tilt: MAX_TILT,
    max_tilts: MAX_TILTS,
    max_map_points: MAX_MAP_POINTS,
    max_map_steps: MAX_MAP_STEPS,
    max_requirements: MAX_REQUIREMENTS,
    max_frequency_points: MAX_FREQUENCY_POINTS,
};

/// A request over a limit: the field, what it asks, the limit.
pub type Refusal = String;

fn over(field: &str, asked: f64, limit: f64) -> Refusal {
    format!("{field}: {asked} is over this server's limit of {limit}")
}

/// `asked` ≤ `limit`, or the refusal naming `field`.
fn at_most(field: &str, asked: f64, limit: f64) -> Result<(), Refusal> {
    if asked > limit {
        return Err(over(field, asked, limit));
    }
    Ok(())
}

/// Steps to integrate `span` seconds with `integrator` (an adaptive one at its smallest step).
fn steps(span: f64, integrator: &IntegratorChoice) -> f64 {
    let h = match integrator {
        IntegratorChoice::Rk4 { h } => *h,
        IntegratorChoice::Dopri(o) => o.h_min,
    };
    span / h
}

fn check_steps(field: &str, span: f64, integrator: &IntegratorChoice) -> Result<(), Refusal> {
    at_most(field, span, MAX_HORIZON)?;
    let n = steps(span, integrator);
    // NaN or a zero step: let the library name it (validated after these bounds).
    if n.is_finite() && n > MAX_STEPS {
        return Err(format!(
            "{field}: {span} s at that step is {n:.0} steps, over this server's limit of \
             {MAX_STEPS}"
        ));
    }
    Ok(())
}

/// A run's horizon, steps and samples.
pub fn run(field: &str, r: &RunSettings) -> Result<(), Refusal> {
    check_steps(&format!("{field}.t_end"), r.t_end, &r.integrator)?;
    at_most(
        &format!("{field}.sample (samples)"),
        r.t_end / r.sample,
        MAX_SAMPLES,
    )
}

/// An initial tilt (a NaN is left to the library to name).
pub fn tilt(field: &str, value: f64) -> Result<(), Refusal> {
    at_most(&format!("{field} (its size)"), value.abs(), MAX_TILT)
}

/// A simulation.
pub fn simulate(s: &SimSettings) -> Result<(), Refusal> {
    tilt("settings.phi0", s.phi0)?;
    run("settings.run", &s.run)
}

/// A phase portrait: its runs and the number of tilts.
pub fn phase(run_settings: &RunSettings, tilts: &[f64]) -> Result<(), Refusal> {
    at_most("settings.tilts", tilts.len() as f64, MAX_TILTS as f64)?;
    for t in tilts {
        tilt("settings.tilts", *t)?;
    }
    run("settings.run", run_settings)
}

/// A map: its points, and the steps of all of them.
pub fn map(s: &SweepSettings, points: usize) -> Result<(), Refusal> {
    tilt("settings.tilt", s.tilt)?;
    at_most(
        "settings.grid (points)",
        points as f64,
        MAX_MAP_POINTS as f64,
    )?;
    let m = &s.metric_settings;
    let span = (m.transient + m.t_sample * m.iterations as f64).max(m.t_end);
    let per_point = span / m.h;
    at_most("settings.metric_settings (horizon)", span, MAX_HORIZON)?;
    let total = per_point * points as f64;
    if total.is_finite() && total > MAX_MAP_STEPS {
        return Err(format!(
            "settings: {points} points × {per_point:.0} steps is over this server's limit of \
             {MAX_MAP_STEPS} steps per request (ask for fewer points at a time)"
        ));
    }
    Ok(())
}

/// A linear analysis: the points of its frequency response.
pub fn margins(s: &LinearSettings) -> Result<(), Refusal> {
    at_most(
        "settings.frequency_points",
        s.frequency_points as f64,
        MAX_FREQUENCY_POINTS as f64,
    )
}

/// A tuning.
pub fn tune(s: &TuneSettings) -> Result<(), Refusal> {
    let n = s.spec.requirements.len();
    at_most(
        "settings.spec (requirements)",
        n as f64,
        MAX_REQUIREMENTS as f64,
    )?;
    let o = &s.options;
    at_most(
        "settings.options.max_iterations",
        o.max_iterations as f64,
        MAX_TUNE_ITERATIONS as f64,
    )?;
    at_most(
        "settings.options.points_per_decade",
        o.points_per_decade as f64,
        MAX_TUNE_POINTS_PER_DECADE as f64,
    )?;
    Ok(())
}
