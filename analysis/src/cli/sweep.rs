//! `twv sweep` and `twv merge`: stability maps over (Kp, Kd[, Ki]), sharded for clusters.
//!
//! A shard runs its contiguous index range in parallel (rayon) and writes one file. The
//! interpreted model is `Send` but not `Sync`, and `ModelTask`/`ControlTask` get `&M` without
//! a `Sync` bound, so the range is split into chunks and every rayon task resolves its own
//! model with one `dispatch_control` per chunk (per run of points with the same number of
//! controller states: Ki = 0 and Ki ≠ 0 have different augmented sizes). The linear metric
//! builds the pitch loop once and shares it (plain matrices).

use std::ops::Range;
use std::path::PathBuf;
use std::time::Instant;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use twv_model::lanes::LANES;
use twv_model::Model;

use super::control_args::{dispatch_control, plant, ControlTask, ControllerArgs};
use super::linear::pitch_loop;
use super::model::{dispatch, parse_vector, to_array, LoadedModel, ModelArgs, ModelTask, Source};
use crate::control::PidLoop;
use crate::linear::{linearize, OperatingPoint, PidGains, PitchLoop};
use crate::sweep::{
    max_lyapunov_lanes, merge, metric, Axis, Grid, Metric, MetricSettings, PointResult, Shard,
    ShardFile, Status, SweepConfig,
};

/// Map a metric over a grid of PID gains (one shard of it).
#[derive(Args, Debug)]
pub struct SweepArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Kp axis A:B:N (N values from A to B) [N/rad]
    #[arg(long, value_name = "A:B:N")]
    pub kp: String,
    /// Kd axis C:D:M [N s/rad]
    #[arg(long, value_name = "C:D:M")]
    pub kd: String,
    /// Ki axis E:F:L [N/(rad s)] [default: Ki = 0, a PD law]
    #[arg(long, value_name = "E:F:L")]
    pub ki: Option<String>,
    /// What to map: max-lyapunov (λ1 of the nonlinear closed loop from the tilt, study preset
    /// T = 0.1 s, K = 100, RK4 h = 1 ms, one exponent), spectral-abscissa (largest real part of
    /// the linear pitch loop's poles at the upright) or settling-time (2 % settling of Φ after
    /// the tilt, 10 s run)
    #[arg(long, value_enum)]
    pub metric: Metric,
    /// Initial model state of the nonlinear metrics, in the model's state order [default: at
    /// rest with Φ = --tilt]
    #[arg(long, value_name = "V1,V2,...", allow_hyphen_values = true)]
    pub x0: Option<String>,
    /// Initial tilt Φ0 of the nonlinear metrics [rad]
    #[arg(
        long,
        value_name = "RAD",
        default_value_t = 0.1,
        allow_hyphen_values = true,
        conflicts_with = "x0"
    )]
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
    /// Folder of the shard files (shared by all shards; `twv merge` reads it)
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Recompute the shard even if its file is complete
    #[arg(long)]
    pub force: bool,
    /// No progress bar and no summary on stderr (errors are still reported)
    #[arg(long)]
    pub quiet: bool,
}

/// Merge the shards of a sweep into map.csv, map.json and map.svg.
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The folder the shards were written to (`twv sweep --out DIR`)
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
}

impl SweepArgs {
    /// The grid these arguments describe.
    pub fn grid(&self) -> Result<Grid> {
        Ok(Grid {
            kp: Axis::parse("kp", &self.kp)?,
            kd: Axis::parse("kd", &self.kd)?,
            ki: self
                .ki
                .as_deref()
                .map(|t| Axis::parse("ki", t))
                .transpose()?,
        })
    }

    /// This job's shard: `--shard`, else the environment.
    pub fn shard(&self) -> Result<Shard> {
        Ok(match &self.shard {
            Some(text) => Shard::parse(text)?,
            None => Shard::from_env(|k| std::env::var(k).ok(), self.shards)?,
        })
    }

    /// The sweep's config (everything a point depends on besides its index).
    pub fn config(&self, loaded: &LoadedModel) -> Result<SweepConfig> {
        if self.metric == Metric::SpectralAbscissa && self.controller.any() {
            bail!("controller options apply to the nonlinear metrics, not to spectral-abscissa");
        }
        let grid = self.grid()?;
        if grid.ki.is_some_and(|a| a.lo < 0.0) {
            bail!("--ki: the integral gain must be ≥ 0");
        }
        let states: Vec<&str> = loaded.ir.states().iter().map(|s| s.name.as_str()).collect();
        let x0 = match &self.x0 {
            Some(text) => parse_vector("x0", text, &states)?,
            None => {
                let i = states
                    .iter()
                    .position(|s| *s == "phi")
                    .context("the model has no state `phi` to tilt")?;
                let mut x = vec![0.0; states.len()];
                x[i] = self.tilt;
                x
            }
        };
        if !self.tilt.is_finite() {
            bail!("--tilt {}: must be finite", self.tilt);
        }
        // The controller apart from the gains, as recorded (and validated) for the config.
        let controller = self.controller.settings(PidGains::default(), None, None)?;
        Ok(SweepConfig {
            model: loaded.name().to_string(),
            source: match &loaded.source {
                Source::Shipped(_) => "shipped".to_string(),
                Source::File(p) => p.display().to_string(),
            },
            params: loaded.params.clone(),
            metric: self.metric,
            grid,
            x0,
            controller: serde_json::to_value(&controller)?,
            settings: MetricSettings::default(),
        })
    }
}

/// The pitch loop at the upright (for the linear metric).
struct UprightPitch;

impl ModelTask for UprightPitch {
    type Output = PitchLoop;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<PitchLoop> {
        let lin = linearize(model, &OperatingPoint::Upright, &[0.0; NU])?;
        pitch_loop(&lin, &model.info(), loaded)
    }
}

/// A run of consecutive points with the same number of controller states.
struct Chunk<'a> {
    args: &'a SweepArgs,
    config: &'a SweepConfig,
    indices: Range<usize>,
    progress: &'a ProgressBar,
}

impl ControlTask for Chunk<'_> {
    type Output = Vec<PointResult>;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<Vec<PointResult>> {
        let x0: [f64; NX] = to_array(&self.config.x0);
        let plant = plant(model, loaded)?;
        let s = &self.config.settings;
        let controller_at = |index: usize| {
            let gains = self.config.grid.gains(index);
            self.args.controller.settings(gains, None, None)
        };
        let mut out = Vec::with_capacity(self.indices.len());
        let mut rest = self.indices.clone();
        if self.config.metric == Metric::MaxLyapunov {
            // Eight points at a time through the lanes kernel (same bits as one by one).
            while rest.len() >= LANES {
                let group: [usize; LANES] = std::array::from_fn(|l| rest.start + l);
                let controllers = group
                    .iter()
                    .map(|&i| controller_at(i))
                    .collect::<Result<Vec<_>>>()?;
                let loops = controllers
                    .iter()
                    .map(|c| PidLoop::<_, NX, NU, NA>::new(model, c, plant))
                    .collect::<Result<Vec<_>, _>>()?;
                let Ok(loops) = <[_; LANES]>::try_from(loops) else {
                    unreachable!("one loop per point of the group")
                };
                out.extend(max_lyapunov_lanes(&loops, &x0, s, group));
                self.progress.inc(LANES as u64);
                rest.start += LANES;
            }
        }
        for index in rest {
            let controller = controller_at(index)?;
            let field = PidLoop::<_, NX, NU, NA>::new(model, &controller, plant)?;
            out.push(match self.config.metric {
                Metric::MaxLyapunov => metric::max_lyapunov(&field, &x0, s, index),
                Metric::SettlingTime => metric::settling_time(&field, &x0, s, index),
                Metric::SpectralAbscissa => unreachable!("the linear metric runs without a model"),
            });
            self.progress.inc(1);
        }
        Ok(out)
    }
}

/// Splits `range` into runs of equal controller-state count, each at most `size` long.
fn chunks(grid: &Grid, range: Range<usize>, size: usize) -> Vec<(usize, Range<usize>)> {
    let nz = |i: usize| usize::from(grid.gains(i).ki != 0.0);
    let mut out: Vec<(usize, Range<usize>)> = Vec::new();
    for i in range {
        match out.last_mut() {
            Some((z, r)) if *z == nz(i) && r.len() < size => r.end = i + 1,
            _ => out.push((nz(i), i..i + 1)),
        }
    }
    out
}

/// Computes the points of `range`.
fn compute(
    args: &SweepArgs,
    loaded: &LoadedModel,
    config: &SweepConfig,
    range: Range<usize>,
) -> Result<Vec<PointResult>> {
    let progress = if args.quiet {
        ProgressBar::hidden()
    } else {
        ProgressBar::new(range.len() as u64)
    };
    progress.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} points, {elapsed} (eta {eta})")
            .expect("a valid template"),
    );
    let grid = &config.grid;
    let points = match config.metric {
        Metric::SpectralAbscissa => {
            let pitch = dispatch(loaded, UprightPitch)?;
            range
                .into_par_iter()
                .map(|i| {
                    let p = metric::spectral_abscissa(&pitch, i, &grid.gains(i));
                    progress.inc(1);
                    p
                })
                .collect()
        }
        Metric::MaxLyapunov | Metric::SettlingTime => {
            // The base controller's extra states (rate filter, velocity integral) plus ∫e.
            let base = args
                .controller
                .settings(PidGains::default(), None, None)?
                .n_states();
            let size = (range.len() / (rayon::current_num_threads() * 8)).clamp(1, 64);
            let parts: Vec<Vec<PointResult>> = chunks(grid, range, size)
                .into_par_iter()
                .map(|(nz, indices)| {
                    let task = Chunk {
                        args,
                        config,
                        indices,
                        progress: &progress,
                    };
                    dispatch_control(loaded, base + nz, task)
                })
                .collect::<Result<_>>()?;
            parts.into_iter().flatten().collect()
        }
    };
    progress.finish_and_clear();
    Ok(points)
}

pub fn run(args: &SweepArgs) -> Result<()> {
    let loaded = args.model.clone().with_default("vehicle8").load()?;
    let config = args.config(&loaded)?;
    let shard = args.shard()?;
    let range = shard.range(config.grid.len());
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let path = args.out.join(shard.file_name());
    if path.exists() && !args.force {
        match ShardFile::read(&path) {
            Ok(file) if file.is_complete_for(&config, shard) => {
                say(args, format_args!("{}: complete, skipped", path.display()));
                return Ok(());
            }
            Ok(file) if file.config_hash != config.hash() => bail!(
                "{} belongs to another sweep (config {}, this one {}): use another --out, or \
                 --force to replace it",
                path.display(),
                file.config_hash,
                config.hash()
            ),
            _ => say(
                args,
                format_args!("{}: incomplete or unreadable, recomputing", path.display()),
            ),
        }
    }
    let start = Instant::now();
    let points = compute(args, &loaded, &config, range.clone())?;
    let seconds = start.elapsed().as_secs_f64();
    let count = |s: Status| points.iter().filter(|p| p.status == s).count();
    let summary = format!(
        "shard {}/{}: points {}..{} of {} in {seconds:.2} s ({} ok, {} fell, {} blew up, {} not \
         settled, {} failed)",
        shard.index,
        shard.count,
        range.start,
        range.end,
        config.grid.len(),
        count(Status::Ok),
        count(Status::Fell),
        count(Status::BlewUp),
        count(Status::NotSettled),
        count(Status::Failed)
    );
    let written = ShardFile::new(config, shard, points).write(&args.out)?;
    say(args, format_args!("{summary}\nwrote {}", written.display()));
    Ok(())
}

/// A line on stderr, unless `--quiet`.
fn say(args: &SweepArgs, line: std::fmt::Arguments) {
    if !args.quiet {
        eprintln!("{line}");
    }
}

pub fn run_merge(args: &MergeArgs) -> Result<()> {
    let (map, files) = merge(&args.dir)?;
    for path in files {
        eprintln!("wrote {}", path.display());
    }
    let ok = map.points.iter().filter(|p| p.status == Status::Ok).count();
    println!(
        "{} points of {} ({}): {ok} with a value",
        map.points.len(),
        map.config.model,
        map.config.metric.label()
    );
    Ok(())
}
