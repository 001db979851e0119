//! `uncertainty`: a measured bicycle's parameters drawn within their stated uncertainty, and the
//! weave and capsize speeds and one steer design's margins as distributions over the draws.

use serde_json::{json, Value};

use super::groups::{rate_filter, steer_gains_json, steer_gains_value};
use super::options::{as_integer, field, integer, is_none, number, Kind, Opt};
use super::steady::speed_parts;
use super::tune::spec_value;
use super::{Budget, Job, JobOutput, Verdict};
use crate::api::{uncertainty, UncertaintyResult, UncertaintySettings, UncertaintyVerdict};
use crate::error::{Error, Result};
use crate::linear::SteerGains;
use crate::model::ResolvedModel;
use crate::output::Files;
use crate::progress::Progress;
use crate::sweep::Shard;

/// Monte Carlo over the parameter file's `[uncertainty]`.
pub struct Uncertainty;

impl Job for Uncertainty {
    const NAME: &'static str = "uncertainty";
    const FILES: &'static str = "uncertainty.csv, uncertainty.json, speeds.svg and margins.svg \
        (and PNGs); a shard writes uncertainty-shard-i-of-N.csv and .json, which `twv merge` \
        joins";
    const SUMMARY: &'static str = "Monte Carlo over a measured bicycle's parameter \
        uncertainty (the --params file's [uncertainty] table): weave and capsize speeds and a \
        steer design's closed-loop margins as distributions (shardable over a Slurm array)";
    type Settings = UncertaintySettings;
    type Output = UncertaintyResult;

    fn options() -> Vec<Opt<UncertaintySettings>> {
        vec![
            integer(
                "samples",
                "",
                "Number of draws of the parameters",
                field(|s: &mut UncertaintySettings| &mut s.samples),
            )
            .aliases(&["draws"]),
            Opt::new(
                "seed",
                Kind::Integer,
                "",
                "Seed of the draws (draw k depends only on the seed and k)",
                |s: &mut UncertaintySettings, v| {
                    s.seed = as_integer("seed", v)?;
                    Ok(())
                },
                |s| json!(s.seed),
            ),
            Opt::new(
                "speeds",
                Kind::Text,
                "m/s",
                "The speeds LO:HI searched for the self-stable band nobody steering",
                |s: &mut UncertaintySettings, v| {
                    [s.lo, s.hi] = speed_parts("speeds", v, "LO:HI", "0:10")?;
                    Ok(())
                },
                |s| json!(format!("{}:{}", s.lo, s.hi)),
            ),
            number(
                "speed",
                "m/s",
                "The speed at which the steer design is checked on every draw",
                field(|s: &mut UncertaintySettings| &mut s.speed),
            ),
            Opt::new(
                "gains",
                Kind::Text,
                "N m/rad, N m s/rad",
                "The steer gains checked on every draw, named k_phi=…,k_delta=…,k_phi_dot=…,\
                 k_delta_dot=… (the others 0); none: tuned on the nominal bicycle to --spec",
                |s: &mut UncertaintySettings, v| {
                    s.gains = if is_none(v) {
                        None
                    } else {
                        Some(steer_gains_value("gains", v, SteerGains::default())?)
                    };
                    Ok(())
                },
                |s| s.gains.as_ref().map_or(Value::Null, steer_gains_json),
            ),
            rate_filter(|s: &mut UncertaintySettings| &mut s.rate_filter),
            Opt::new(
                "spec",
                Kind::Text,
                "",
                "The margins each draw's closed loop is checked against (and the design tuned \
                 to): dpm>=DEG, dgm>=DB dB or dgm>=FACTOR, ms<=PEAK, comma-separated",
                |s: &mut UncertaintySettings, v| {
                    s.spec = spec_value(v)?;
                    Ok(())
                },
                |s| json!(s.spec.to_string()),
            ),
            Opt::new(
                "shard",
                Kind::Text,
                "",
                "Compute only shard i/N of the draws (e.g. $SLURM_ARRAY_TASK_ID/$SLURM_ARRAY_TASK_COUNT); \
                 `twv merge DIR` joins the shards' files",
                |s: &mut UncertaintySettings, v| {
                    s.shard = match v {
                        Value::String(t) => Shard::parse(t),
                        other => serde_json::from_value(other.clone()).map_err(|_| {
                            crate::sweep::SweepError::Shard {
                                text: other.to_string(),
                                reason: "want i/N".into(),
                            }
                        }),
                    }
                    .map_err(|e| Error::input("shard", e.to_string()))?;
                    Ok(())
                },
                |s| json!(format!("{}/{}", s.shard.index, s.shard.count)),
            ),
        ]
    }

    fn validate(s: &UncertaintySettings) -> Result<()> {
        s.validate()
    }

    fn budget(_model: &ResolvedModel, s: &UncertaintySettings) -> Result<Budget> {
        Ok(Budget {
            points: s.samples as f64,
            ..Budget::default()
        })
    }

    fn run(
        model: &ResolvedModel,
        s: &UncertaintySettings,
        p: &dyn Progress,
    ) -> Result<UncertaintyResult> {
        uncertainty(model, s, p)
    }
}

impl JobOutput for UncertaintyResult {
    fn summary(&self) -> String {
        UncertaintyResult::summary(self)
    }
    fn files(&self) -> Result<Files> {
        UncertaintyResult::files(self)
    }
    fn csv(&self) -> Option<String> {
        Some(UncertaintyResult::csv(self))
    }
    fn verdict(&self) -> Verdict {
        match self.verdict {
            UncertaintyVerdict::AllStable => Verdict::Done,
            UncertaintyVerdict::NotAllStable => Verdict::Negative(format!(
                "the steer design's closed loop at {} m/s is stable in {} of {} physical draws",
                self.speed, self.stable, self.physical
            )),
        }
    }
}
