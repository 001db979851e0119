//! What one request may cost. The library validates that settings make sense and computes the
//! work they ask for (a [`Budget`], before anything runs); these bound it, so that no request
//! ties a worker up for more than a few seconds: a request over a limit is refused with the
//! limit named, not started.

use serde::Serialize;
use twv_analysis::jobs::Budget;

/// Largest request body [bytes].
pub const MAX_BODY: usize = 256 * 1024;
/// Largest model time of one run [s].
pub const MAX_HORIZON: f64 = 120.0;
/// Most integration steps of one request, all runs and points together (an adaptive run
/// counted at its smallest step, `h_min`).
pub const MAX_STEPS: f64 = 2.5e7;
/// Most samples one request returns.
pub const MAX_SAMPLES: f64 = 50_000.0;
/// Most points of one map request (the page asks row by row), runs of a portrait or speeds.
pub const MAX_POINTS: f64 = 2_500.0;
/// Most points of a frequency response, or grid points per decade of a tuning.
pub const MAX_FREQUENCY_POINTS: f64 = 5_000.0;
/// Most subproblems of a tuning (or requirements of its spec).
pub const MAX_ITERATIONS: f64 = 200.0;

/// The limits, for `GET /api/model` (the page and scripts read them).
#[derive(Debug, Clone, Copy, Serialize)]
pub struct Limits {
    pub max_body_bytes: usize,
    pub max_horizon: f64,
    pub max_steps: f64,
    pub max_samples: f64,
    pub max_points: f64,
    pub max_frequency_points: f64,
    pub max_iterations: f64,
}

/// The limits in force.
pub const LIMITS: Limits = Limits {
    max_body_bytes: MAX_BODY,
    max_horizon: MAX_HORIZON,
    max_steps: MAX_STEPS,
    max_samples: MAX_SAMPLES,
    max_points: MAX_POINTS,
    max_frequency_points: MAX_FREQUENCY_POINTS,
    max_iterations: MAX_ITERATIONS,
};

/// `budget` within the limits, or the refusal naming what is over.
pub fn check(budget: &Budget) -> Result<(), String> {
    let checks = [
        ("horizon [s]", budget.horizon, MAX_HORIZON, "a shorter t_end"),
        (
            "integration steps",
            budget.steps,
            MAX_STEPS,
            "a larger step h (for dopri: h_min > 0 bounds its steps), a shorter run or fewer points",
        ),
        ("samples", budget.samples, MAX_SAMPLES, "a larger sample interval"),
        ("points", budget.points, MAX_POINTS, "fewer points per request"),
        (
            "frequency points",
            budget.frequency_points,
            MAX_FREQUENCY_POINTS,
            "fewer frequency points",
        ),
        ("iterations", budget.iterations, MAX_ITERATIONS, "fewer iterations"),
    ];
    for (what, asked, limit, hint) in checks {
        // NaN (an invalid setting the library names) never reaches here: settings are validated
        // before their budget is computed; an infinite ask is over any limit.
        if asked.is_nan() || asked > limit {
            let shown = if asked.is_finite() {
                format!("{asked:.0}")
            } else {
                "unbounded".to_string()
            };
            return Err(format!(
                "settings: {shown} {what} is over this server's limit of {limit} (ask for {hint})"
            ));
        }
    }
    Ok(())
}
