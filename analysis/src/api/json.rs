//! Every job with its settings and its result as JSON: the entry point of front ends that speak
//! JSON (the Python package, the live page). The settings are the job's settings type read by
//! serde — unknown fields are refused, absent ones take the defaults beside each field — and the
//! result is the same serialisation the CLI prints with `--json`, so the two agree bit for bit.

use std::ops::Range;

use serde::de::DeserializeOwned;
use serde::Serialize;

use super::{
    analyse, audit_model, compute_points, ride, simulate, spectrum, steady_motion, tune_model,
    HandAuditJob, LinearSettings, RideSettings, SimSettings, SpectrumSettings, SteadySettings,
    SweepSettings, TuneSettings,
};
use crate::audit::AuditSettings;
use crate::error::{Error, Result};
use crate::model::ResolvedModel;
use crate::progress::Progress;

/// The jobs [`run`] knows, by name.
pub const JOBS: [&str; 9] = [
    "spectrum",
    "simulate",
    "ride",
    "linear",
    "tune",
    "sweep",
    "audit",
    "audit_hand",
    "steady",
];

/// Reads the settings of `job` from a JSON object (the error names the job and the field).
pub fn settings<T: DeserializeOwned>(job: &str, text: &str) -> Result<T> {
    serde_json::from_str(text).map_err(|e| Error::input("settings", format!("{job}: {e}")))
}

/// A result or settings value as pretty JSON, the way [`run`] returns it.
pub fn to_text<T: Serialize>(value: &T) -> Result<String> {
    serde_json::to_string_pretty(value)
        .map_err(|e| Error::input("result", format!("cannot be written as JSON: {e}")))
}

fn unknown(job: &str) -> Error {
    Error::input(
        "job",
        format!("unknown job `{job}`; known: {}", JOBS.join(", ")),
    )
}

/// The default settings of `job` as JSON (a sweep has no default grid: its settings need
/// `grid` and `metric`).
pub fn default_settings(job: &str) -> Result<String> {
    match job {
        "spectrum" => to_text(&SpectrumSettings::default()),
        "simulate" => to_text(&SimSettings::default()),
        "ride" => to_text(&RideSettings::default()),
        "linear" => to_text(&LinearSettings::default()),
        "tune" => to_text(&TuneSettings::default()),
        "audit" => to_text(&AuditSettings::default()),
        "steady" => to_text(&SteadySettings::default()),
        "sweep" => Err(Error::input(
            "settings",
            "sweep: no default; give at least `grid` and `metric`",
        )),
        "audit_hand" => Err(Error::input(
            "settings",
            "audit_hand: no default; give at least `hand` (the hand file's text)",
        )),
        _ => Err(unknown(job)),
    }
}

/// A job's result as JSON, and the time series the CLI writes beside it as CSV (the running
/// Lyapunov estimates, a simulation's samples), full precision.
#[derive(Debug, Clone, PartialEq)]
pub struct Output {
    /// The result, exactly as `twv <job> --json` prints it.
    pub result: String,
    /// The series (`running.csv`, `sim.csv`), if the job has one.
    pub csv: Option<String>,
}

/// Runs `job` on `model` with `settings` (a JSON object). A sweep returns its points in index
/// order.
pub fn run(
    job: &str,
    model: &ResolvedModel,
    settings_json: &str,
    progress: &dyn Progress,
) -> Result<Output> {
    let plain = |result: String| Output { result, csv: None };
    match job {
        "spectrum" => {
            let r = spectrum(model, &settings(job, settings_json)?, progress)?;
            Ok(Output {
                result: to_text(&r)?,
                csv: Some(r.running_csv()),
            })
        }
        "simulate" => {
            let r = simulate(model, &settings(job, settings_json)?, progress)?;
            Ok(Output {
                result: to_text(&r)?,
                csv: Some(r.csv()),
            })
        }
        "ride" => {
            let r = ride(model, &settings(job, settings_json)?, progress)?;
            Ok(Output {
                result: to_text(&r)?,
                csv: Some(r.csv()),
            })
        }
        "linear" => to_text(&analyse(model, &settings(job, settings_json)?)?).map(plain),
        "tune" => to_text(&tune_model(model, &settings(job, settings_json)?)?).map(plain),
        "audit" => to_text(&audit_model(model, &settings(job, settings_json)?)?).map(plain),
        "audit_hand" => {
            let job: HandAuditJob = settings(job, settings_json)?;
            to_text(&job.run(model)?).map(plain)
        }
        "steady" => {
            let r = steady_motion(model, &settings(job, settings_json)?)?;
            Ok(Output {
                result: to_text(&r)?,
                csv: Some(r.csv()),
            })
        }
        "sweep" => {
            let s: SweepSettings = settings(job, settings_json)?;
            to_text(&super::sweep(model, &s, progress)?).map(plain)
        }
        _ => Err(unknown(job)),
    }
}

/// The points `range` of a sweep (a shard another process computes: the Python package hands
/// these to an executor), in index order, or an error if `progress` cancelled it.
pub fn sweep_range(
    model: &ResolvedModel,
    settings_json: &str,
    range: Range<usize>,
    progress: &dyn Progress,
) -> Result<String> {
    let s: SweepSettings = settings("sweep", settings_json)?;
    let config = s.config(model)?;
    let total = config.grid.len();
    if range.start > range.end || range.end > total {
        return Err(Error::input(
            "range",
            format!(
                "{}..{} is not inside the grid's {total} points",
                range.start, range.end
            ),
        ));
    }
    let computed = compute_points(model, &s, &config, &[range], progress)?;
    if !computed.complete {
        return Err(Error::Interrupted);
    }
    to_text(&computed.points)
}

/// The number of points of a sweep's grid (validated).
pub fn sweep_len(model: &ResolvedModel, settings_json: &str) -> Result<usize> {
    let s: SweepSettings = settings("sweep", settings_json)?;
    Ok(s.config(model)?.grid.len())
}
