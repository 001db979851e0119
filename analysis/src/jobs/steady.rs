//! `steady`: the eigenvalues of a steady motion's modes against speed (the Whipple bicycle's
//! straight running), and its self-stable speed ranges with what bounds them.

use serde_json::{json, Value};

use super::options::{as_number, as_text, as_vector, Kind, Opt};
use super::{Budget, Job, JobOutput, Verdict};
use crate::api::{steady_motion, SteadyResult, SteadySettings, SteadyVerdict};
use crate::error::{Error, Result};
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;

/// Linearisation about straight running against speed.
pub struct Steady;

/// `LO:HI:STEP` as text, or `[lo, hi, step]`.
pub(super) fn speeds(v: &Value) -> Result<(f64, f64, f64)> {
    let [lo, hi, step] = speed_parts("speed", v, "LO:HI:STEP", "0:10:0.01")?;
    Ok((lo, hi, step))
}

/// N speeds as text separated by `:` (`form`, e.g. `LO:HI`), or a list of N numbers; the
/// errors name `field` and show `example`.
pub(super) fn speed_parts<const N: usize>(
    field: &str,
    v: &Value,
    form: &str,
    example: &str,
) -> Result<[f64; N]> {
    let parts = match v {
        Value::String(text) => text
            .split(':')
            .map(|p| as_number(field, &Value::String(p.to_string())))
            .collect::<Result<Vec<_>>>()?,
        Value::Array(_) => as_vector(field, v)?,
        other => {
            return Err(Error::input(
                field,
                format!(
                    "wants {form}, not {}",
                    as_text(field, other).unwrap_or("that")
                ),
            ))
        }
    };
    let count = ["no", "one", "two", "three"]
        .get(N)
        .copied()
        .unwrap_or("more");
    parts.try_into().map_err(|_| {
        Error::input(
            field,
            format!("wants {count} numbers {form} [m/s], e.g. {example}"),
        )
    })
}

impl Job for Steady {
    const NAME: &'static str = "steady";
    const ALIASES: &'static [&'static str] = &["steady_motion"];
    const FILES: &'static str = "eigenvalues.csv, eigenvalues.svg/.png and steady.json";
    const SUMMARY: &'static str = "Eigenvalues of the steady motion's modes against speed \
        (models whose IR describes straight running, e.g. whipple), and where it is self-stable";
    type Settings = SteadySettings;
    type Output = SteadyResult;

    fn options() -> Vec<Opt<SteadySettings>> {
        vec![Opt::new(
            "speed",
            Kind::Text,
            "m/s",
            "The speeds LO:HI:STEP (or [lo, hi, step])",
            |s: &mut SteadySettings, v| {
                (s.lo, s.hi, s.step) = speeds(v)?;
                Ok(())
            },
            |s| json!(format!("{}:{}:{}", s.lo, s.hi, s.step)),
        )
        .aliases(&["speeds"])]
    }

    fn validate(s: &SteadySettings) -> Result<()> {
        s.validate()
    }

    fn budget(_model: &ResolvedModel, s: &SteadySettings) -> Result<Budget> {
        Ok(Budget {
            points: ((s.hi - s.lo) / s.step).floor() + 1.0,
            ..Budget::default()
        })
    }

    fn run(model: &ResolvedModel, s: &SteadySettings, p: &dyn Progress) -> Result<SteadyResult> {
        steady_motion(model, s, p)
    }
}

impl JobOutput for SteadyResult {
    fn summary(&self) -> String {
        SteadyResult::summary(self)
    }
    fn files(&self) -> Result<Files> {
        SteadyResult::files(self)
    }
    fn csv(&self) -> Option<String> {
        Some(SteadyResult::csv(self))
    }
    fn verdict(&self) -> Verdict {
        match self.verdict {
            SteadyVerdict::SelfStable => Verdict::Done,
            SteadyVerdict::NowhereStable => {
                Verdict::Negative(format!("{} is nowhere self-stable on the grid", self.model))
            }
        }
    }
}
