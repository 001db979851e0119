//! Every job with its settings and its result as JSON: the entry point of front ends that speak
//! JSON (the Python package, the live page), one loop over the [job registry](crate::jobs). The
//! settings are the job's settings type read by serde — unknown fields are refused, absent ones
//! take the defaults beside each field — optionally with the job's flat options laid over them
//! (what a Python call's keywords are), and the result is the same serialisation the CLI prints
//! with `--json`, so the two agree bit for bit.

use std::ops::Range;

use serde_json::Value;

use super::{compute_points, SweepSettings};
use crate::error::{Error, Result};
use crate::jobs;
use crate::model::ResolvedModel;
use crate::progress::Progress;

pub use crate::jobs::to_text;

/// The names of the jobs [`run`] knows (aliases are accepted too).
pub fn jobs() -> Vec<&'static str> {
    jobs::registry().iter().map(|j| j.name()).collect()
}

/// Reads a JSON text (the error names `what`).
pub fn parse(what: &str, text: &str) -> Result<Value> {
    serde_json::from_str(text).map_err(|e| Error::input(what, format!("not JSON: {e}")))
}

/// The default settings of `job` as pretty JSON.
pub fn default_settings(job: &str) -> Result<String> {
    to_text(&jobs::find(job)?.default_settings())
}

/// A job's result as JSON, and the time series the CLI writes beside it as CSV (the running
/// Lyapunov estimates, a simulation's samples), full precision.
#[derive(Debug, Clone, PartialEq)]
pub struct Output {
    /// The result, exactly as `twv <job> --json` prints it.
    pub result: String,
    /// The series (`running.csv`, `sim.csv`), if the job has one.
    pub csv: Option<String>,
    /// The few readable lines `twv <job>` prints.
    pub summary: String,
    /// The one-line verdict of a negative result (the CLI's exit status 3), if negative.
    pub negative: Option<String>,
}

/// The flat options of a JSON object `{name: value}`, in its order.
pub fn options_of(text: &str) -> Result<Vec<(String, Value)>> {
    match parse("options", text)? {
        Value::Object(map) => Ok(map.into_iter().collect()),
        Value::Null => Ok(Vec::new()),
        _ => Err(Error::input(
            "options",
            "must be a JSON object {name: value}",
        )),
    }
}

fn finish(out: Box<dyn jobs::Finished>) -> Result<Output> {
    Ok(Output {
        result: out.json()?,
        csv: out.csv(),
        summary: out.summary(),
        negative: match out.verdict() {
            jobs::Verdict::Done => None,
            jobs::Verdict::Negative(why) => Some(why),
        },
    })
}

/// Runs `job` on `model` with `settings` (a JSON object).
pub fn run(
    job: &str,
    model: &ResolvedModel,
    settings_json: &str,
    progress: &dyn Progress,
) -> Result<Output> {
    let job = jobs::find(job)?;
    let prepared = job.prepare_json(&parse("settings", settings_json)?)?;
    finish(prepared.run(model, progress)?)
}

/// Runs `job` on `model` with its flat options (a JSON object `{name: value}`, what the command
/// line's flags and Python's keywords are) laid over `settings_json` (or the defaults).
pub fn run_options(
    job: &str,
    model: &ResolvedModel,
    settings_json: Option<&str>,
    options_json: &str,
    progress: &dyn Progress,
) -> Result<Output> {
    let done = prepare_options(job, settings_json, options_json)?.run(model, progress)?;
    finish(done)
}

/// [`run_options`] that also writes the job's files into the folder `out`, as `twv <job> --out
/// DIR` does (all or nothing, with the folder's manifest).
pub fn run_options_to(
    job: &str,
    model: &ResolvedModel,
    settings_json: Option<&str>,
    options_json: &str,
    out: &std::path::Path,
    progress: &dyn Progress,
) -> Result<Output> {
    let done = prepare_options(job, settings_json, options_json)?.run(model, progress)?;
    done.files()?.write(out)?;
    finish(done)
}

fn prepare_options(
    job: &str,
    settings_json: Option<&str>,
    options_json: &str,
) -> Result<Box<dyn jobs::Prepared>> {
    let job = jobs::find(job)?;
    let base = settings_json.map(|t| parse("settings", t)).transpose()?;
    job.prepare_options(base.as_ref(), &options_of(options_json)?)
}

/// The settings `job` would run with these options (pretty JSON), validated but not run.
pub fn resolve_options(
    job: &str,
    settings_json: Option<&str>,
    options_json: &str,
) -> Result<String> {
    to_text(&prepare_options(job, settings_json, options_json)?.settings())
}

/// The points `range` of a sweep (a shard another process computes: the Python package hands
/// these to an executor), in index order, or an error if `progress` cancelled it.
pub fn sweep_range(
    model: &ResolvedModel,
    settings_json: &str,
    range: Range<usize>,
    progress: &dyn Progress,
) -> Result<String> {
    let s: SweepSettings = sweep_settings(settings_json)?;
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

fn sweep_settings(text: &str) -> Result<SweepSettings> {
    let prepared = jobs::find("sweep")?.prepare_json(&parse("settings", text)?)?;
    serde_json::from_value(prepared.settings())
        .map_err(|e| Error::input("settings", format!("sweep: {e}")))
}

/// The number of points of a sweep's grid (validated).
pub fn sweep_len(model: &ResolvedModel, settings_json: &str) -> Result<usize> {
    Ok(sweep_settings(settings_json)?.config(model)?.grid.len())
}
