//! Every job with its settings and its result as JSON: the entry point of front ends that speak
//! JSON (the Python package, the live page). The settings are the job's settings type read by
//! serde — unknown fields are refused, absent ones take the defaults beside each field — and the
//! result is the same serialisation the CLI prints with `--json`, so the two agree bit for bit.

use std::ops::Range;

use serde::de::DeserializeOwned;
use serde::Serialize;

use super::{
    analyse, audit_model, compute_points, simulate, spectrum, tune_model, LinearSettings,
    SimSettings, SpectrumSettings, SweepSettings, TuneSettings,
};
use crate::audit::AuditSettings;
use crate::error::{Error, Result};
use crate::model::ResolvedModel;
use crate::progress::Progress;

/// The jobs [`run`] knows, by name.
pub const JOBS: [&str; 6] = ["spectrum", "simulate", "linear", "tune", "sweep", "audit"];

/// The settings of `job` as JSON objects.
fn settings<T: DeserializeOwned>(job: &str, text: &str) -> Result<T> {
    serde_json::from_str(text).map_err(|e| Error::input("settings", format!("{job}: {e}")))
}

fn json<T: Serialize>(value: &T) -> Result<String> {
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
        "spectrum" => json(&SpectrumSettings::default()),
        "simulate" => json(&SimSettings::default()),
        "linear" => json(&LinearSettings::default()),
        "tune" => json(&TuneSettings::default()),
        "audit" => json(&AuditSettings::default()),
        "sweep" => Err(Error::input(
            "settings",
            "sweep: no default; give at least `grid` and `metric`",
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
                result: json(&r)?,
                csv: Some(r.running_csv()),
            })
        }
        "simulate" => {
            let r = simulate(model, &settings(job, settings_json)?, progress)?;
            Ok(Output {
                result: json(&r)?,
                csv: Some(r.csv()),
            })
        }
        "linear" => json(&analyse(model, &settings(job, settings_json)?)?).map(plain),
        "tune" => json(&tune_model(model, &settings(job, settings_json)?)?).map(plain),
        "audit" => json(&audit_model(model, &settings(job, settings_json)?)?).map(plain),
        "sweep" => {
            let s: SweepSettings = settings(job, settings_json)?;
            json(&super::sweep(model, &s, progress)?).map(plain)
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
    json(&computed.points)
}

/// The number of points of a sweep's grid (validated).
pub fn sweep_len(model: &ResolvedModel, settings_json: &str) -> Result<usize> {
    let s: SweepSettings = settings("sweep", settings_json)?;
    Ok(s.config(model)?.grid.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::ModelSpec;
    use crate::progress::Silent;

    #[test]
    fn default_settings_read_back_as_themselves() {
        for job in ["spectrum", "simulate", "linear", "tune", "audit"] {
            let text = default_settings(job).unwrap();
            let again = match job {
                "spectrum" => json(&settings::<SpectrumSettings>(job, &text).unwrap()),
                "simulate" => json(&settings::<SimSettings>(job, &text).unwrap()),
                "linear" => json(&settings::<LinearSettings>(job, &text).unwrap()),
                "tune" => json(&settings::<TuneSettings>(job, &text).unwrap()),
                _ => json(&settings::<AuditSettings>(job, &text).unwrap()),
            }
            .unwrap();
            assert_eq!(text, again, "{job}");
        }
        assert_eq!(
            settings::<SimSettings>("simulate", "{}").unwrap(),
            SimSettings::default()
        );
    }

    #[test]
    fn bad_settings_name_the_field() {
        let model = ModelSpec::shipped("vehicle8").resolve().unwrap();
        let e = run("linear", &model, r#"{"lqr_qq": 1}"#, &Silent).unwrap_err();
        assert!(e.to_string().contains("unknown field `lqr_qq`"), "{e}");
        let e = run("tune", &model, r#"{"spec": "dpm>=95"}"#, &Silent).unwrap_err();
        assert!(e.to_string().contains("dpm"), "{e}");
        let e = run("simulate", &model, r#"{"phi0": "a"}"#, &Silent).unwrap_err();
        assert!(e.to_string().starts_with("settings: simulate:"), "{e}");
        let e = run("fly", &model, "{}", &Silent).unwrap_err();
        assert!(e.to_string().contains("known: spectrum"), "{e}");
        let grid = r#"{"grid": {"kp": {"lo": 0, "hi": 8000, "n": 4}, "kd": {"lo": 0, "hi": 4000, "n": 4}, "ki": null}, "metric": "spectral-abscissa"}"#;
        assert_eq!(sweep_len(&model, grid).unwrap(), 16);
        let e = sweep_range(&model, grid, 10..17, &Silent).unwrap_err();
        assert!(e.to_string().contains("10..17"), "{e}");
    }

    #[test]
    fn a_spec_reads_as_text_or_as_written() {
        let text: TuneSettings = settings("tune", r#"{"spec": "dpm>=60,dgm>=6dB"}"#).unwrap();
        let written = json(&text).unwrap();
        let again: TuneSettings = settings("tune", &written).unwrap();
        assert_eq!(text, again);
    }
}
