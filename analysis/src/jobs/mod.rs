//! The job registry: every analysis twv runs, each with **one name** (the CLI subcommand, the
//! Python function, the JSON runner's job and the HTTP route), one settings type holding every
//! default and rule, and a typed, serialisable output with its verdict. Front ends are loops over
//! [`registry`]; none restates a default.
//!
//! ```
//! use twv_analysis::jobs::{self, Job};
//! use twv_analysis::model::ModelSpec;
//!
//! let model = ModelSpec::shipped("vehicle8").resolve()?;
//! // Typed: the settings type with its defaults, then the run.
//! let settings = jobs::Linearize::defaults();
//! let report = jobs::Linearize::run(&model, &settings, &twv_analysis::api::Silent)?;
//! assert!(report.pitch.as_ref().is_some_and(|p| p.margins.is_some()));
//! // By name, with flat options as the command line and Python give them.
//! let job = jobs::find("linear")?; // an alias of `linearize`
//! let prepared = job.prepare_options(None, &[("kd".into(), "900".into())])?;
//! let done = prepared.run(&model, &twv_analysis::api::Silent)?;
//! assert!(done.summary().contains("900"));
//! # Ok::<(), twv_analysis::Error>(())
//! ```

mod audit;
mod codegen;
mod disturb;
mod evaluate;
mod exponent;
mod export;
pub mod groups;
mod linearize;
mod lyapunov;
pub mod options;
mod phase;
mod ride;
mod simulate;
mod steady;
mod steer;
mod steer_map;
mod sweep;
mod tune;
mod uncertainty;

use std::marker::PhantomData;

use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;

pub use audit::{Audit, AuditOutput, AuditSettings};
pub use codegen::{Codegen, GeneratedCode};
pub use disturb::{Direction, Disturb, DisturbSettings};
pub use evaluate::Evaluate;
pub use exponent::{exponent_verdict, Exponent, ExponentSettings, ExponentVerdict, LoopExponent};
pub use export::{Export, Exported};
pub use linearize::Linearize;
pub use lyapunov::Lyapunov;
pub use options::{Kind, Opt, OptionInfo};
pub use phase::Phase;
pub use ride::Ride;
pub use simulate::Simulate;
pub use steady::Steady;
pub use steer::Steer;
pub use steer_map::SteerMap;
pub use sweep::{Sweep, SweepPoints};
pub use tune::Tune;
pub use uncertainty::Uncertainty;

use crate::error::{Error, Result};
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;

/// How much work a job's settings ask for, computed before it runs, so a front end can refuse
/// what is over its limits (the page's server) naming the field.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Budget {
    /// The longest model time of one run [s].
    pub horizon: f64,
    /// Integration steps of all runs together (an adaptive run counted at its smallest step:
    /// infinite when that is 0).
    pub steps: f64,
    /// Samples returned.
    pub samples: f64,
    /// Points (of a map), runs (of a portrait) or speeds.
    pub points: f64,
    /// Points of a frequency response.
    pub frequency_points: f64,
    /// Iterations of an optimiser, or requirements of a specification.
    pub iterations: f64,
}

/// How a run came out, computed from its numbers: the CLI's exit status 3 for a negative one.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Verdict {
    /// Done, with a positive verdict (or none to give).
    Done,
    /// Done, but negative: the message says why.
    Negative(String),
}

/// A job's result.
pub trait JobOutput: Serialize + Send + Sized + 'static {
    /// A few readable lines (what `twv <job>` prints).
    fn summary(&self) -> String;
    /// The files `twv <job> --out DIR` writes (by default the result as `result.json`).
    fn files(&self) -> Result<Files> {
        let mut f = Files::new();
        f.json("result.json", self);
        Ok(f)
    }
    /// The time series, as CSV (the Python result's arrays).
    fn csv(&self) -> Option<String> {
        None
    }
    /// The samples by column for the page (`{"t": […], "phi": […]}`).
    fn series(&self) -> Option<Value> {
        None
    }
    /// Whether the run's verdict is positive.
    fn verdict(&self) -> Verdict {
        Verdict::Done
    }
}

/// One job: its name, settings, options and run.
pub trait Job: Sized + 'static {
    /// The one name.
    const NAME: &'static str;
    /// Older names that still answer (documented as aliases).
    const ALIASES: &'static [&'static str] = &[];
    /// What it computes, one line.
    const SUMMARY: &'static str;
    /// Whether the page's server offers it (`POST /api/<name>`).
    const SERVED: bool = true;
    /// The files its output writes (`twv <job> --out DIR`), for help texts.
    const FILES: &'static str = "result.json";
    /// Its settings: `Default` holds every default.
    type Settings: Default + Clone + PartialEq + Serialize + DeserializeOwned + Send + Sync;
    /// Its result.
    type Output: JobOutput;

    /// The flat options (command-line flags, Python keywords), in the order they are applied.
    fn options() -> Vec<Opt<Self::Settings>>;
    /// Checks every setting; the error names the first bad one.
    fn validate(settings: &Self::Settings) -> Result<()>;
    /// The work `settings` ask of `model`.
    fn budget(_model: &ResolvedModel, _settings: &Self::Settings) -> Result<Budget> {
        Ok(Budget::default())
    }
    /// Runs the job (validating first).
    fn run(
        model: &ResolvedModel,
        settings: &Self::Settings,
        progress: &dyn Progress,
    ) -> Result<Self::Output>;

    /// The default settings.
    fn defaults() -> Self::Settings {
        Self::Settings::default()
    }
}

/// A job seen by name, with settings and results as JSON: what front ends loop over.
pub trait AnyJob: Send + Sync {
    /// The one name.
    fn name(&self) -> &'static str;
    /// Older names.
    fn aliases(&self) -> &'static [&'static str];
    /// One line.
    fn summary(&self) -> &'static str;
    /// Offered by the page's server.
    fn served(&self) -> bool;
    /// The files its output writes.
    fn files(&self) -> &'static str;
    /// The options with their defaults.
    fn options(&self) -> Vec<OptionInfo>;
    /// The default settings as JSON.
    fn default_settings(&self) -> Value;
    /// Settings from their JSON (absent fields take the defaults, unknown ones are refused),
    /// validated.
    fn prepare_json(&self, settings: &Value) -> Result<Box<dyn Prepared>>;
    /// Settings from flat options laid over `base` (JSON settings, default: the defaults),
    /// validated.
    fn prepare_options(
        &self,
        base: Option<&Value>,
        given: &[(String, Value)],
    ) -> Result<Box<dyn Prepared>>;
}

/// A job with validated settings, ready to run.
pub trait Prepared: Send + Sync {
    /// The job's name.
    fn job(&self) -> &'static str;
    /// The settings as JSON.
    fn settings(&self) -> Value;
    /// The work they ask of `model`.
    fn budget(&self, model: &ResolvedModel) -> Result<Budget>;
    /// Runs it.
    fn run(&self, model: &ResolvedModel, progress: &dyn Progress) -> Result<Box<dyn Finished>>;
}

/// A job's result, seen through its JSON.
pub trait Finished: Send {
    /// The result as pretty JSON (what `twv <job> --json` prints).
    fn json(&self) -> Result<String>;
    /// The result as a JSON value.
    fn value(&self) -> Result<Value>;
    /// See [`JobOutput::summary`].
    fn summary(&self) -> String;
    /// See [`JobOutput::files`].
    fn files(&self) -> Result<Files>;
    /// See [`JobOutput::csv`].
    fn csv(&self) -> Option<String>;
    /// See [`JobOutput::series`].
    fn series(&self) -> Option<Value>;
    /// See [`JobOutput::verdict`].
    fn verdict(&self) -> Verdict;
}

struct Erased<J>(PhantomData<fn() -> J>);

struct PreparedJob<J: Job>(J::Settings);

struct Done<J: Job>(J::Output);

/// A result or settings value as pretty JSON.
pub fn to_text<T: Serialize>(value: &T) -> Result<String> {
    serde_json::to_string_pretty(value)
        .map_err(|e| Error::input("result", format!("cannot be written as JSON: {e}")))
}

/// Settings of `job` from JSON, naming the field serde refused.
fn settings_from<T: DeserializeOwned>(job: &str, value: &Value) -> Result<T> {
    serde_path_to_error::deserialize(value).map_err(|e| {
        let path = e.path().to_string();
        let field = if path == "." || path == "?" {
            "settings".to_string()
        } else {
            path
        };
        Error::input(field, format!("{job}: {}", e.inner()))
    })
}

impl<J: Job> AnyJob for Erased<J> {
    fn name(&self) -> &'static str {
        J::NAME
    }
    fn aliases(&self) -> &'static [&'static str] {
        J::ALIASES
    }
    fn summary(&self) -> &'static str {
        J::SUMMARY
    }
    fn served(&self) -> bool {
        J::SERVED
    }
    fn files(&self) -> &'static str {
        J::FILES
    }
    fn options(&self) -> Vec<OptionInfo> {
        let defaults = J::defaults();
        J::options().iter().map(|o| o.info(&defaults)).collect()
    }
    fn default_settings(&self) -> Value {
        serde_json::to_value(J::defaults()).unwrap_or(Value::Null)
    }
    fn prepare_json(&self, settings: &Value) -> Result<Box<dyn Prepared>> {
        let s: J::Settings = settings_from(J::NAME, settings)?;
        J::validate(&s)?;
        Ok(Box::new(PreparedJob::<J>(s)))
    }
    fn prepare_options(
        &self,
        base: Option<&Value>,
        given: &[(String, Value)],
    ) -> Result<Box<dyn Prepared>> {
        let mut s: J::Settings = match base {
            Some(v) => settings_from(J::NAME, v)?,
            None => J::defaults(),
        };
        options::apply(J::NAME, &J::options(), &mut s, given)?;
        J::validate(&s)?;
        Ok(Box::new(PreparedJob::<J>(s)))
    }
}

impl<J: Job> Prepared for PreparedJob<J> {
    fn job(&self) -> &'static str {
        J::NAME
    }
    fn settings(&self) -> Value {
        serde_json::to_value(&self.0).unwrap_or(Value::Null)
    }
    fn budget(&self, model: &ResolvedModel) -> Result<Budget> {
        J::budget(model, &self.0)
    }
    fn run(&self, model: &ResolvedModel, progress: &dyn Progress) -> Result<Box<dyn Finished>> {
        Ok(Box::new(Done::<J>(J::run(model, &self.0, progress)?)))
    }
}

impl<J: Job> Finished for Done<J> {
    fn json(&self) -> Result<String> {
        to_text(&self.0)
    }
    fn value(&self) -> Result<Value> {
        serde_json::to_value(&self.0)
            .map_err(|e| Error::input("result", format!("cannot be written as JSON: {e}")))
    }
    fn summary(&self) -> String {
        self.0.summary()
    }
    fn files(&self) -> Result<Files> {
        self.0.files()
    }
    fn csv(&self) -> Option<String> {
        self.0.csv()
    }
    fn series(&self) -> Option<Value> {
        self.0.series()
    }
    fn verdict(&self) -> Verdict {
        self.0.verdict()
    }
}

macro_rules! registry {
    ($($job:ty),* $(,)?) => {
        /// Every job, in the order front ends list them.
        static JOBS: &[&dyn AnyJob] = &[$(&Erased::<$job>(PhantomData)),*];
    };
}

registry![
    Evaluate,
    Codegen,
    Audit,
    Lyapunov,
    Simulate,
    Disturb,
    Ride,
    Phase,
    Linearize,
    Steady,
    Steer,
    SteerMap,
    Uncertainty,
    Tune,
    Sweep,
    Exponent,
    Export,
];

/// Every job.
pub fn registry() -> &'static [&'static dyn AnyJob] {
    JOBS
}

/// The job of this name or alias.
pub fn find(name: &str) -> Result<&'static dyn AnyJob> {
    let key = name.replace('-', "_");
    JOBS.iter()
        .copied()
        .find(|j| j.name() == key || j.aliases().contains(&key.as_str()))
        .ok_or_else(|| {
            let names: Vec<&str> = JOBS.iter().map(|j| j.name()).collect();
            Error::input(
                "job",
                format!("unknown job `{name}`; the jobs: {}", names.join(", ")),
            )
        })
}

/// Steps to integrate `span` seconds with `integrator` (an adaptive one at its smallest step:
/// infinite when that is 0, so a budget refuses it until `h_min` is given).
pub fn steps(span: f64, integrator: &crate::lyapunov::IntegratorChoice) -> f64 {
    use crate::lyapunov::IntegratorChoice;
    let h = match integrator {
        IntegratorChoice::Rk4 { h } => *h,
        IntegratorChoice::Dopri(o) => o.h_min,
    };
    if h > 0.0 {
        span / h
    } else {
        f64::INFINITY
    }
}

/// The budget of one run of `run`.
pub fn run_budget(run: &crate::control::RunSettings, runs: f64) -> Budget {
    Budget {
        horizon: run.t_end,
        steps: runs * steps(run.t_end, &run.integrator),
        samples: runs * (run.t_end / run.sample + 1.0),
        points: runs,
        ..Budget::default()
    }
}
