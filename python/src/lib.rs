//! `twv._native`: the twv-analysis API for Python. A [`Model`] evaluates f and its Jacobians on
//! NumPy batches in Rust; every analysis runs through `twv_analysis::api::json` (settings and
//! result as JSON, the CLI's own serialisation). The Python package (python/twv) gives these
//! keyword arguments, result objects and docstrings; nothing here parses arguments.
//!
//! Long jobs run on a worker thread while the calling thread, without the GIL, waits for the
//! result and looks for Ctrl-C between waits (raising the job's cancel flag); a panic of the
//! worker comes back as an exception, never across into Python. Each call has its own thread
//! pool, so a forked process (a fork-based process pool) computes as the parent does.

mod errors;
mod model;

use std::sync::mpsc;
use std::time::Duration;

use pyo3::prelude::*;
use twv_analysis::api::json;
use twv_analysis::api::{CancelFlag, Progress};

pub use errors::{to_py, InputError, ModelError, NumericalError, TwvError};
pub use model::Model;

/// The embedded default vehicle files, as in the `twv` binary.
pub const PAPER_TOML: &str = include_str!("../../vehicles/paper.toml");
/// See [`PAPER_TOML`].
pub const SEGWAY_TOML: &str = include_str!("../../vehicles/segway.toml");

/// How often the waiting thread looks for Ctrl-C.
const SIGNAL_POLL: Duration = Duration::from_millis(50);

/// A job's view of the cancel flag the waiting thread raises on Ctrl-C.
struct Flag<'a>(&'a CancelFlag);

impl Progress for Flag<'_> {
    fn cancelled(&self) -> bool {
        self.0.is_raised()
    }
}

/// Runs `job` on a worker thread, releasing the GIL; Ctrl-C cancels it at its next chunk
/// boundary and raises KeyboardInterrupt.
fn interruptible<T: Send>(
    py: Python<'_>,
    job: impl FnOnce(&dyn Progress) -> twv_analysis::Result<T> + Send,
) -> PyResult<T> {
    let flag = CancelFlag::new();
    let mut interrupt: Option<PyErr> = None;
    let outcome = std::thread::scope(|scope| {
        let (done, wait) = mpsc::channel();
        let flag = &flag;
        let worker = scope.spawn(move || {
            // A pool of this call's own, not rayon's global one: in a process forked after an
            // earlier call (a fork-based process pool) the global pool's threads are gone and
            // work queued to it would wait for ever.
            let out = match rayon::ThreadPoolBuilder::new().build() {
                Ok(pool) => pool.install(|| job(&Flag(flag))),
                Err(e) => Err(twv_analysis::Error::input("threads", e.to_string())),
            };
            // The receiver lives until the join below.
            let _ = done.send(());
            out
        });
        let mut wait = wait;
        loop {
            // The receiver moves into the GIL-free wait and back (it is Send, not Sync).
            let (finished, back) = py.detach(move || {
                let finished = match wait.recv_timeout(SIGNAL_POLL) {
                    Ok(()) | Err(mpsc::RecvTimeoutError::Disconnected) => true,
                    Err(mpsc::RecvTimeoutError::Timeout) => false,
                };
                (finished, wait)
            });
            wait = back;
            if finished {
                break;
            }
            if interrupt.is_none() {
                if let Err(e) = py.check_signals() {
                    flag.raise();
                    interrupt = Some(e);
                }
            }
        }
        py.detach(|| worker.join())
    });
    match (outcome, interrupt) {
        // Ctrl-C is KeyboardInterrupt whatever the job made of it (an interrupted
        // integration's error, or a result it finished anyway): never a ValueError that an
        // `except ValueError` would swallow.
        (_, Some(e)) => Err(e),
        (Ok(result), None) => result.map_err(to_py),
        (Err(panic), None) => Err(errors::panicked(panic)),
    }
}

/// Runs the analysis `job` (any of the registry's, by name or alias) on `model` with
/// `settings` (a JSON object); returns the result as JSON and its time series as CSV (or None).
#[pyfunction]
fn run(
    py: Python<'_>,
    job: &str,
    model: &Model,
    settings: &str,
) -> PyResult<(String, Option<String>)> {
    let resolved = model.resolved();
    let out = interruptible(py, |progress| json::run(job, resolved, settings, progress))?;
    Ok((out.result, out.csv))
}

/// Runs `job` with its flat options (`options`, a JSON object {name: value}: the keyword
/// arguments of the Python function) laid over `settings` (JSON, or the defaults); returns the
/// result as JSON, its series as CSV (or None), its summary text and the message of a negative
/// verdict (or None). With `out`, the job's files are written into that folder, as
/// `twv <job> --out DIR` writes them.
#[pyfunction]
#[pyo3(signature = (job, model, options, settings = None, out = None))]
fn run_options(
    py: Python<'_>,
    job: &str,
    model: &Model,
    options: &str,
    settings: Option<&str>,
    out: Option<std::path::PathBuf>,
) -> PyResult<(String, Option<String>, String, Option<String>)> {
    let resolved = model.resolved();
    let out = interruptible(py, |progress| match &out {
        Some(dir) => json::run_options_to(job, resolved, settings, options, dir, progress),
        None => json::run_options(job, resolved, settings, options, progress),
    })?;
    Ok((out.result, out.csv, out.summary, out.negative))
}

/// The settings `job` runs with for these options (JSON), validated, without running it.
#[pyfunction]
#[pyo3(signature = (job, options, settings = None))]
fn resolve_options(job: &str, options: &str, settings: Option<&str>) -> PyResult<String> {
    json::resolve_options(job, settings, options).map_err(to_py)
}

/// Every job of the library's registry as JSON: name, aliases, summary and its options (name,
/// kind, unit, help, default — the library's own).
#[pyfunction]
fn jobs() -> PyResult<String> {
    #[derive(serde::Serialize)]
    struct Job {
        name: &'static str,
        aliases: &'static [&'static str],
        summary: &'static str,
        options: Vec<twv_analysis::jobs::OptionInfo>,
    }
    let all: Vec<Job> = twv_analysis::jobs::registry()
        .iter()
        .map(|j| Job {
            name: j.name(),
            aliases: j.aliases(),
            summary: j.summary(),
            options: j.options(),
        })
        .collect();
    json::to_text(&all).map_err(to_py)
}

/// Which build this is (version, commit, profile, architecture, kernels' ISA, JIT), as JSON.
#[pyfunction]
fn build_info() -> PyResult<String> {
    let info = twv_analysis::machine::BuildInfo::new(
        git_version::git_version!(args = ["--always", "--abbrev=12"], fallback = "unknown"),
        true,
    );
    json::to_text(&info).map_err(to_py)
}

/// The points `start..stop` of a sweep, as JSON (a shard for an executor).
#[pyfunction]
fn sweep_range(
    py: Python<'_>,
    model: &Model,
    settings: &str,
    start: usize,
    stop: usize,
) -> PyResult<String> {
    let resolved = model.resolved();
    interruptible(py, |progress| {
        json::sweep_range(resolved, settings, start..stop, progress)
    })
}

/// The number of points of a sweep's grid.
#[pyfunction]
fn sweep_len(model: &Model, settings: &str) -> PyResult<usize> {
    json::sweep_len(model.resolved(), settings).map_err(to_py)
}

/// The default settings of a job, as JSON.
#[pyfunction]
fn default_settings(job: &str) -> PyResult<String> {
    json::default_settings(job).map_err(to_py)
}

/// The shipped models' names.
#[pyfunction]
fn shipped_models() -> Vec<&'static str> {
    twv_analysis::model::shipped_models()
}

/// The measured bicycle of the report's Monte Carlo, embedded (as vehicles/paper.toml is).
fn measured_bicycle() -> twv_analysis::model::ParamSource {
    twv_analysis::model::ParamSource::Text {
        text: include_str!("../../vehicles/bicycles/browser.toml").to_string(),
        origin: "vehicles/bicycles/browser.toml (embedded)".to_string(),
    }
}

/// Builds the study's report into `out` (index.html, figures, data, results.json) from the
/// embedded vehicle files or the parameter file `params`; returns results.json's text.
#[pyfunction]
#[pyo3(signature = (out, *, params = None, quick = false))]
fn report(
    py: Python<'_>,
    out: std::path::PathBuf,
    params: Option<std::path::PathBuf>,
    quick: bool,
) -> PyResult<String> {
    use twv_analysis::model::{vehicle_defaults, ParamSource};
    use twv_analysis::report::{build, ReportSettings};
    let settings = match params {
        Some(p) => ReportSettings {
            params: ParamSource::File(p),
            quick,
            measured_bicycle: Some(measured_bicycle()),
            ..ReportSettings::default()
        },
        None => ReportSettings {
            params: vehicle_defaults("vehicle8", PAPER_TOML, SEGWAY_TOML).unwrap_or_default(),
            segway_params: vehicle_defaults("segway7", PAPER_TOML, SEGWAY_TOML),
            params_text: Some(PAPER_TOML.to_string()),
            quick,
            measured_bicycle: Some(measured_bicycle()),
            ..ReportSettings::default()
        },
    };
    interruptible(py, |progress| {
        let report = build(&settings, progress)?;
        report.files.write(&out)?;
        serde_json::to_string_pretty(&report.results)
            .map_err(|e| twv_analysis::Error::input("result", e.to_string()))
    })
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add_class::<Model>()?;
    m.add("TwvError", py.get_type::<TwvError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("ModelError", py.get_type::<ModelError>())?;
    m.add("NumericalError", py.get_type::<NumericalError>())?;
    m.add(
        "SETTLED_TAIL_TOLERANCE",
        twv_analysis::sweep::SETTLED_TAIL_TOLERANCE,
    )?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(run_options, m)?)?;
    m.add_function(wrap_pyfunction!(resolve_options, m)?)?;
    m.add_function(wrap_pyfunction!(jobs, m)?)?;
    m.add_function(wrap_pyfunction!(build_info, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_range, m)?)?;
    m.add_function(wrap_pyfunction!(sweep_len, m)?)?;
    m.add_function(wrap_pyfunction!(default_settings, m)?)?;
    m.add_function(wrap_pyfunction!(shipped_models, m)?)?;
    m.add_function(wrap_pyfunction!(report, m)?)?;
    Ok(())
}
