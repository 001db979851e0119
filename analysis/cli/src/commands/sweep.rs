//! `twv sweep`: one shard of a stability map over (Kp, Kd[, Ki]) and model parameters, for a
//! cluster array job.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::{Args, ValueEnum};
use twv_analysis::api::{run_shard, status_counts, ShardOptions, ShardOutcome, SweepSettings};
use twv_analysis::control::{ControllerSettings, STUDY_PD};
use twv_analysis::sweep::{Axis, Grid, Metric, MetricSettings, ParamAxis, Shard};

use crate::common::{parse_vector, Context, ControllerArgs, ModelArgs, Outcome};

/// What to map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MetricArg {
    /// λ1 of the nonlinear closed loop's pitch-loop states (the drift directions projected
    /// off), from the tilt, 1 s transient then T = 0.1 s, K = 100, RK4 h = 1 ms
    MaxLyapunov,
    /// Largest real part of the linear pitch loop's poles at the upright
    SpectralAbscissa,
    /// 2 % settling time of Φ after the tilt (10 s run)
    SettlingTime,
}

impl From<MetricArg> for Metric {
    fn from(m: MetricArg) -> Self {
        match m {
            MetricArg::MaxLyapunov => Metric::MaxLyapunov,
            MetricArg::SpectralAbscissa => Metric::SpectralAbscissa,
            MetricArg::SettlingTime => Metric::SettlingTime,
        }
    }
}

/// Map a metric over a grid of PID gains and model parameters (one shard of it).
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct SweepArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Kp axis A:B:N (N values from A to B) [N/rad] [default: 3860, the study's, with
    /// --param axes; required without them]
    #[arg(long, value_name = "A:B:N", allow_hyphen_values = true)]
    pub kp: Option<String>,
    /// Kd axis C:D:M [N s/rad] [default: 1980, the study's, with --param axes; required
    /// without them]
    #[arg(long, value_name = "C:D:M", allow_hyphen_values = true)]
    pub kd: Option<String>,
    /// Ki axis E:F:L [N/(rad s)] [default: Ki = 0, a PD law]
    #[arg(long, value_name = "E:F:L", allow_hyphen_values = true)]
    pub ki: Option<String>,
    /// A model parameter axis NAME=A:B:N (the IR's parameter names: m2, b, I2_xx, …);
    /// repeatable, each varying slower than the gains and than the axes before it
    #[arg(long = "param", value_name = "NAME=A:B:N", allow_hyphen_values = true)]
    pub param_axes: Vec<String>,
    /// What to map
    #[arg(long, value_enum)]
    pub metric: MetricArg,
    /// Initial model state of the nonlinear metrics, in the model's state order [default: at
    /// rest with Φ = --tilt]
    #[arg(long, value_name = "V1,V2,...", allow_hyphen_values = true)]
    pub x0: Option<String>,
    /// Initial tilt Φ0 of the nonlinear metrics [rad]
    #[arg(long, value_name = "RAD", default_value_t = 0.1, conflicts_with = "x0")]
    pub tilt: f64,
    /// Controller options of the nonlinear metrics (the swept gains replace Kp, Ki, Kd)
    #[command(flatten)]
    pub controller: ControllerArgs,
    /// This job's shard i/N [default: from SLURM_ARRAY_TASK_ID/_MIN/_COUNT, or
    /// JOB_COMPLETION_INDEX with --shards/TWV_SHARDS; else the whole sweep]
    #[arg(long, value_name = "i/N")]
    pub shard: Option<String>,
    /// Number of shards for a Kubernetes indexed job (its `completions`) [env: TWV_SHARDS]
    #[arg(long, value_name = "N", conflicts_with = "shard")]
    pub shards: Option<usize>,
    /// Folder of the shard files (shared by all shards; `twv merge` reads it); it holds one
    /// sweep only
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Recompute the shard even if its file is complete (ignores a checkpoint)
    #[arg(long)]
    pub force: bool,
    /// max-lyapunov: step every point to the end of its horizon, without the settled tail
    /// (a loop at rest finished from its linearisation, λ1 within 10⁻³ /s; README)
    #[arg(long)]
    pub full_horizon: bool,
}

impl SweepArgs {
    fn settings(&self) -> Result<SweepSettings> {
        let params = self
            .param_axes
            .iter()
            .map(|t| ParamAxis::parse(t))
            .collect::<Result<Vec<_>, _>>()?;
        // With parameter axes the gains may stay at the study's PD; without, they are the map.
        let gain = |name: &'static str, given: &Option<String>, study: f64| -> Result<Axis> {
            match given {
                Some(text) => Ok(Axis::parse(name, text)?),
                None if !params.is_empty() => Ok(Axis {
                    lo: study,
                    hi: study,
                    n: 1,
                }),
                None => bail!("--{name} is required (or map over parameters with --param)"),
            }
        };
        let grid = Grid {
            kp: gain("kp", &self.kp, STUDY_PD.kp)?,
            kd: gain("kd", &self.kd, STUDY_PD.kd)?,
            ki: self
                .ki
                .as_deref()
                .map(|t| Axis::parse("ki", t))
                .transpose()?,
            params,
        };
        if self.full_horizon && self.metric != MetricArg::MaxLyapunov {
            bail!("--full-horizon applies to --metric max-lyapunov only (the other metrics have no settled tail)");
        }
        let controller = if self.controller.any() {
            self.controller.settings(Default::default(), None)?
        } else {
            ControllerSettings::default()
        };
        Ok(SweepSettings {
            grid,
            metric: self.metric.into(),
            x0: self
                .x0
                .as_deref()
                .map(|x| parse_vector("x0", x))
                .transpose()?,
            tilt: self.tilt,
            controller,
            metric_settings: MetricSettings {
                settle_distance: MetricSettings::default()
                    .settle_distance
                    .filter(|_| !self.full_horizon),
                ..MetricSettings::default()
            },
        })
    }

    fn shard(&self) -> Result<Shard> {
        Ok(match &self.shard {
            Some(text) => Shard::parse(text)?,
            None => Shard::from_env(|k| std::env::var(k).ok(), self.shards)?,
        })
    }
}

pub fn run(args: &SweepArgs, ctx: &Context) -> Result<Outcome> {
    let model = args.model.resolve(ctx)?;
    let settings = args.settings()?;
    let shard = args.shard()?;
    let bar = ctx.bar();
    let start = std::time::Instant::now();
    let options = ShardOptions { force: args.force };
    match run_shard(&model, &settings, shard, &args.out, options, &bar)? {
        ShardOutcome::Skipped { path } => {
            ctx.say(format!("{}: complete, skipped", path.display()));
            Ok(Outcome::Done)
        }
        ShardOutcome::Written {
            path,
            points,
            resumed,
        } => {
            let range = shard.range(settings.grid.len());
            ctx.say(format!(
                "shard {}/{}: points {}..{} of {} in {:.2} s ({}{})\nwrote {}",
                shard.index,
                shard.count,
                range.start,
                range.end,
                settings.grid.len(),
                start.elapsed().as_secs_f64(),
                status_counts(&points),
                if resumed > 0 {
                    format!("; {resumed} taken from the checkpoint")
                } else {
                    String::new()
                },
                path.display()
            ));
            Ok(Outcome::Done)
        }
        ShardOutcome::Interrupted {
            checkpoint,
            done,
            total,
        } => Ok(Outcome::Interrupted(format!(
            "{done} of {total} points of shard {}/{} kept in {}; run the same command again to \
             resume",
            shard.index,
            shard.count,
            checkpoint.display()
        ))),
    }
}
