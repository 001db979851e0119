//! Stability maps over PID gains: the points of a grid computed in memory (in parallel, with
//! progress and cancellation), and on top of it the shard layer that clusters run — one file
//! per shard, resumable, checkpointed when interrupted, in a folder that holds one sweep only.

use std::fs;
use std::ops::Range;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use twv_kernels::lanes::LANES;
use twv_model::Model;

use super::linear::pitch_loop;
use crate::control::{ControllerSettings, PidLoop, Plant};
use crate::error::{Error, Result};
use crate::linear::{linearize, OperatingPoint, PitchLoop};
use crate::model::{
    check_vector, dispatch, dispatch_control, ControlTask, ModelTask, ResolvedModel,
};
use crate::output::write_atomic;
use crate::progress::Progress;
use crate::sweep::{
    max_lyapunov_lanes, metric, Axis, DriverChoice, Grid, Metric, MetricSettings, PointResult,
    Shard, ShardFile, Status, SweepConfig, SweepError, TILT_AXIS,
};

/// The most points one sweep may have (each is a 10 s closed-loop run; the shard files hold
/// ~150 bytes per point): refused before anything is allocated.
pub const MAX_POINTS: usize = 10_000_000;

/// What to map. Defaults: a 100 × 100 map of the largest Lyapunov exponent over Kp 0…8000 N/rad
/// and Kd 0…4000 N s/rad, with the study's sampling after a tilt of 0.1 rad and the study's
/// controller apart from the swept gains.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SweepSettings {
    /// The (Kp, Kd[, Ki]) grid and the parameter axes.
    pub grid: Grid,
    /// What to map.
    pub metric: Metric,
    /// Initial model state of the nonlinear metrics; `None`: at rest with Φ = `tilt`.
    pub x0: Option<Vec<f64>>,
    /// Initial tilt of the nonlinear metrics [rad]. Default 0.1.
    pub tilt: f64,
    /// The controller apart from the gains (setpoint, saturation, outer loops).
    pub controller: ControllerSettings,
    /// The metrics' numerical settings.
    pub metric_settings: MetricSettings,
}

/// The default initial tilt of the nonlinear metrics [rad].
fn default_tilt() -> f64 {
    0.1
}

impl Default for SweepSettings {
    fn default() -> Self {
        Self::new(
            Grid {
                kp: Axis {
                    lo: 0.0,
                    hi: 8000.0,
                    n: 100,
                },
                kd: Axis {
                    lo: 0.0,
                    hi: 4000.0,
                    n: 100,
                },
                ki: None,
                params: Vec::new(),
            },
            Metric::MaxLyapunov,
        )
    }
}

impl SweepSettings {
    /// A sweep of `metric` over `grid` with every other setting at its default.
    pub fn new(grid: Grid, metric: Metric) -> Self {
        Self {
            grid,
            metric,
            x0: None,
            tilt: default_tilt(),
            controller: ControllerSettings::default(),
            metric_settings: MetricSettings::default(),
        }
    }

    /// The sweep's config for `model` (everything a point depends on besides its index),
    /// validated.
    pub fn config(&self, model: &ResolvedModel) -> Result<SweepConfig> {
        let size = self.grid.params.iter().fold(
            (self.grid.kp.n as u128) * (self.grid.kd.n as u128) * (self.grid.n_ki() as u128),
            |s, a| s.saturating_mul(a.n as u128),
        );
        if size > MAX_POINTS as u128 {
            return Err(Error::input(
                "grid",
                format!(
                    "{size} points; at most {MAX_POINTS} per sweep (split it into several sweeps)"
                ),
            ));
        }
        debug_assert_eq!(self.grid.len() as u128, size);
        if self.grid.ki.is_some_and(|a| a.lo < 0.0) {
            return Err(Error::input("ki", "the integral gain must be ≥ 0"));
        }
        check_param_axes(model, &self.grid.params)?;
        if !self.tilt.is_finite() {
            return Err(Error::input(
                "tilt",
                format!("{} must be finite", self.tilt),
            ));
        }
        let nonlinear = self.metric != Metric::SpectralAbscissa;
        if !nonlinear && self.controller != ControllerSettings::default() {
            return Err(Error::input(
                "controller",
                "controller options apply to the nonlinear metrics, not to spectral-abscissa",
            ));
        }
        self.controller.validate()?;
        self.metric_settings.validate()?;
        if self.grid.params.iter().any(|a| a.name == TILT_AXIS) {
            if !nonlinear {
                return Err(Error::input(
                    "param",
                    "the tilt axis applies to the nonlinear metrics, not to spectral-abscissa",
                ));
            }
            if self.x0.is_some() {
                return Err(Error::input(
                    "param",
                    "give either an initial state (x0) or a tilt axis, not both",
                ));
            }
            model.state_index("phi").ok_or_else(|| {
                Error::input(
                    "param",
                    format!("{} has no state phi to tilt", model.name()),
                )
            })?;
        }
        let x0 = match &self.x0 {
            Some(x) => {
                check_vector("x0", x, &model.states())?;
                x.clone()
            }
            None => model.rest_with("phi", self.tilt)?,
        };
        Ok(SweepConfig {
            model: model.name().to_string(),
            source: model.source_label(),
            params: model.params.clone(),
            metric: self.metric,
            grid: self.grid.clone(),
            x0,
            controller: serde_json::to_value(&self.controller).unwrap_or_default(),
            settings: self.metric_settings,
        })
    }
}

/// Checks the parameter axes against the model: known names, each once, and every corner of
/// the parameter box a valid vehicle (the checks of a parameter file are bounds, so the box is
/// valid when its corners are).
fn check_param_axes(model: &ResolvedModel, axes: &[crate::sweep::ParamAxis]) -> Result<()> {
    for (k, a) in axes.iter().enumerate() {
        if a.name != TILT_AXIS && !model.ir.params().iter().any(|p| p.name == a.name) {
            let known: Vec<&str> = model.ir.params().iter().map(|p| p.name.as_str()).collect();
            return Err(Error::input(
                "param",
                format!(
                    "`{}` is not a parameter of {} (known: {})",
                    a.name,
                    model.name(),
                    known.join(", ")
                ),
            ));
        }
        if axes[..k].iter().any(|b| b.name == a.name) {
            return Err(Error::input("param", format!("`{}` has two axes", a.name)));
        }
    }
    let axes: Vec<&crate::sweep::ParamAxis> = axes.iter().filter(|a| a.name != TILT_AXIS).collect();
    for corner in 0..(1usize << axes.len().min(16)) {
        let values: Vec<(String, f64)> = axes
            .iter()
            .enumerate()
            .map(|(k, a)| {
                (
                    a.name.clone(),
                    if corner >> k & 1 == 1 { a.hi } else { a.lo },
                )
            })
            .collect();
        model.with_param_values(&values, "the sweep's parameter axes")?;
    }
    Ok(())
}

/// The model at parameter setting `setting` of `grid` (the model itself without parameter
/// axes).
fn model_at<'a>(
    model: &'a ResolvedModel,
    grid: &Grid,
    setting: usize,
) -> Result<std::borrow::Cow<'a, ResolvedModel>> {
    let values = grid.model_values(setting);
    if values.is_empty() {
        return Ok(std::borrow::Cow::Borrowed(model));
    }
    Ok(std::borrow::Cow::Owned(model.with_param_values(
        &values,
        "the sweep's parameter axes",
    )?))
}

/// The model of every parameter setting that `ranges` touch, sorted by setting, each built
/// (and checked) once; a borrow of `model` for a grid without parameter axes.
fn models_by_setting<'a>(
    model: &'a ResolvedModel,
    grid: &Grid,
    ranges: &[Range<usize>],
) -> Result<Vec<(usize, std::borrow::Cow<'a, ResolvedModel>)>> {
    let mut settings: Vec<usize> = ranges
        .iter()
        .filter(|r| !r.is_empty())
        .flat_map(|r| grid.setting(r.start)..=grid.setting(r.end - 1))
        .collect();
    settings.sort_unstable();
    settings.dedup();
    settings
        .into_par_iter()
        .map(|k| Ok((k, model_at(model, grid, k)?)))
        .collect()
}

/// The entry of setting `k` in a list sorted by setting that holds it.
fn at_setting<T>(list: &[(usize, T)], k: usize) -> &T {
    &list[list.partition_point(|(s, _)| *s < k)].1
}

/// The pitch loop at the upright (for the linear metric).
struct UprightPitch;

impl ModelTask for UprightPitch {
    type Output = PitchLoop;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<PitchLoop> {
        let lin = linearize(model, &OperatingPoint::Upright, &[0.0; NU])?;
        pitch_loop(&lin, &model.info(), resolved)
    }
}

/// A run of consecutive points with the same number of controller states.
struct Chunk<'a> {
    config: &'a SweepConfig,
    base: &'a ControllerSettings,
    indices: Range<usize>,
    /// The maps' driver build for the whole sweep.
    choice: &'a DriverChoice,
}

impl ControlTask for Chunk<'_> {
    type Output = Vec<PointResult>;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<Vec<PointResult>> {
        let mut x0 = [0.0; NX];
        x0.iter_mut()
            .zip(&self.config.x0)
            .for_each(|(o, v)| *o = *v);
        // An operating-point axis: this chunk's runs start from its tilt.
        let setting = self.config.grid.setting(self.indices.start);
        if let (Some(tilt), Some(phi)) =
            (self.config.grid.tilt(setting), resolved.state_index("phi"))
        {
            x0[phi] = tilt;
        }
        let plant = Plant::from_info(&model.info(), &|n| resolved.param(n))?;
        let s = &self.config.settings;
        let controller_at = |index: usize| ControllerSettings {
            pitch: crate::control::PitchPid {
                gains: self.config.grid.gains(index),
                ..self.base.pitch
            },
            ..self.base.clone()
        };
        let indices: Vec<usize> = self.indices.collect();
        let controllers: Vec<ControllerSettings> =
            indices.iter().map(|&i| controller_at(i)).collect();
        let loops = controllers
            .iter()
            .map(|c| PidLoop::<_, NX, NU, NA>::new(model, c, plant))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(match self.config.metric {
            // Eight points at a time through the lanes kernel (same bits as one by one).
            Metric::MaxLyapunov => max_lyapunov_lanes(&loops, &x0, s, &indices, self.choice),
            Metric::SettlingTime => (loops.iter().zip(indices))
                .map(|(field, index)| metric::settling_time(field, &x0, s, index))
                .collect(),
            Metric::SpectralAbscissa => unreachable!("the linear metric runs without a model"),
        })
    }
}

/// Splits `range` into runs of equal controller-state count and parameter setting, each at
/// most `size` long.
fn chunks(grid: &Grid, range: Range<usize>, size: usize) -> Vec<(usize, Range<usize>)> {
    let nz = |i: usize| usize::from(grid.gains(i).ki != 0.0);
    let mut out: Vec<(usize, Range<usize>)> = Vec::new();
    for i in range {
        match out.last_mut() {
            Some((z, r))
                if *z == nz(i) && grid.setting(r.start) == grid.setting(i) && r.len() < size =>
            {
                r.end = i + 1
            }
            _ => out.push((nz(i), i..i + 1)),
        }
    }
    out
}

/// The points of `ranges` in index order, computed in parallel (rayon); `complete` is false
/// when `progress` cancelled the run, and `points` then holds the chunks that finished.
#[derive(Debug, Clone, PartialEq)]
pub struct Computed {
    /// Results, sorted by index.
    pub points: Vec<PointResult>,
    /// Whether every index of the ranges is there.
    pub complete: bool,
}

/// Computes the points of `ranges` of the sweep `settings` (whose config for `model` is
/// `config`).
pub fn compute_points(
    model: &ResolvedModel,
    settings: &SweepSettings,
    config: &SweepConfig,
    ranges: &[Range<usize>],
    progress: &dyn Progress,
) -> Result<Computed> {
    let total: usize = ranges.iter().map(|r| r.len()).sum();
    progress.start(total as u64, "points");
    let result = compute_inner(model, &settings.controller, config, ranges, total, progress);
    progress.finish();
    result
}

fn compute_inner(
    model: &ResolvedModel,
    base: &ControllerSettings,
    config: &SweepConfig,
    ranges: &[Range<usize>],
    total: usize,
    progress: &dyn Progress,
) -> Result<Computed> {
    let grid = &config.grid;
    let models = models_by_setting(model, grid, ranges)?;
    let mut points: Vec<PointResult> = match config.metric {
        Metric::SpectralAbscissa => {
            // One pitch loop per parameter setting.
            let loops: Vec<(usize, PitchLoop)> = models
                .par_iter()
                .map(|(k, m)| Ok((*k, dispatch(m, UprightPitch)?)))
                .collect::<Result<_>>()?;
            let indices: Vec<usize> = ranges.iter().cloned().flatten().collect();
            indices
                .par_chunks(4096)
                .map(|part| {
                    if progress.cancelled() {
                        return Vec::new();
                    }
                    let p: Vec<PointResult> = part
                        .iter()
                        .map(|&i| {
                            let pitch = at_setting(&loops, grid.setting(i));
                            metric::spectral_abscissa(pitch, i, &grid.gains(i))
                        })
                        .collect();
                    progress.advance(p.len() as u64);
                    p
                })
                .flatten()
                .collect()
        }
        Metric::MaxLyapunov | Metric::SettlingTime => {
            // The base controller's extra states (rate filter, velocity integral) plus ∫e.
            let nz0 = ControllerSettings {
                pitch: crate::control::PitchPid {
                    gains: Default::default(),
                    ..base.pitch
                },
                ..base.clone()
            }
            .n_states();
            let size = (total / (rayon::current_num_threads() * 8)).clamp(LANES, 64);
            let work: Vec<(usize, Range<usize>)> = ranges
                .iter()
                .flat_map(|r| chunks(grid, r.clone(), size))
                .collect();
            let choice = DriverChoice::for_chunks(work.len());
            let parts: Vec<Option<Vec<PointResult>>> = work
                .into_par_iter()
                .map(|(nz, indices)| {
                    if progress.cancelled() {
                        return Ok(None);
                    }
                    let n = indices.len() as u64;
                    let at = at_setting(&models, grid.setting(indices.start));
                    let task = Chunk {
                        config,
                        base,
                        indices,
                        choice: &choice,
                    };
                    let p = dispatch_control(at, nz0 + nz, task)?;
                    progress.advance(n);
                    Ok(Some(p))
                })
                .collect::<Result<_>>()?;
            parts.into_iter().flatten().flatten().collect()
        }
    };
    points.sort_by_key(|p| p.index);
    Ok(Computed {
        complete: points.len() == total,
        points,
    })
}

/// The points of the whole grid, in memory.
pub fn sweep(
    model: &ResolvedModel,
    settings: &SweepSettings,
    progress: &dyn Progress,
) -> Result<Vec<PointResult>> {
    let config = settings.config(model)?;
    let whole = std::iter::once(0..config.grid.len()).collect::<Vec<_>>();
    let computed = compute_points(model, settings, &config, &whole, progress)?;
    if !computed.complete {
        return Err(Error::Interrupted);
    }
    Ok(computed.points)
}

// ---------------------------------------------------------------------------------------------
// The shard layer.

/// Format tag of the folder's manifest and of checkpoints.
pub const SWEEP_FOLDER_FORMAT: &str = "twv-sweep-folder/1";

/// `sweep.json`: which sweep a folder holds, so a second sweep cannot overwrite it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Manifest {
    format: String,
    config_hash: String,
    config: SweepConfig,
}

/// The completed points of an interrupted shard: `checkpoint-<i>-of-<N>.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
struct Checkpoint {
    format: String,
    config_hash: String,
    shard: Shard,
    points: Vec<PointResult>,
}

/// How a shard run ended.
#[derive(Debug, Clone, PartialEq)]
pub enum ShardOutcome {
    /// The shard file was already complete: nothing computed.
    Skipped {
        /// The shard file.
        path: PathBuf,
    },
    /// Computed and written.
    Written {
        /// The shard file.
        path: PathBuf,
        /// Its points.
        points: Vec<PointResult>,
        /// Points taken over from a checkpoint.
        resumed: usize,
    },
    /// Cancelled: the finished points are in a checkpoint that the next run resumes from.
    Interrupted {
        /// The checkpoint.
        checkpoint: PathBuf,
        /// Points done.
        done: usize,
        /// Points of the shard.
        total: usize,
    },
}

/// Options of a shard run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ShardOptions {
    /// Recompute even a complete shard file.
    pub force: bool,
}

fn folder_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Sweep(SweepError::File {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}

/// An exclusive lock on `path` (created if missing), held while the value lives.
struct Lock(#[allow(dead_code)] fs::File);

/// The lock on `path`, or `None` while another process holds it.
fn try_lock(path: &Path) -> Result<Option<Lock>> {
    let file = fs::OpenOptions::new()
        .create(true)
        .truncate(false)
        .write(true)
        .open(path)
        .map_err(|e| folder_error(path, e))?;
    match file.try_lock() {
        Ok(()) => Ok(Some(Lock(file))),
        Err(fs::TryLockError::WouldBlock) => Ok(None),
        Err(fs::TryLockError::Error(e)) => Err(folder_error(path, e)),
    }
}

/// How long a task waits for another to finish claiming the folder (milliseconds of work)
/// before giving up.
const CLAIM_WAIT: std::time::Duration = std::time::Duration::from_secs(30);

/// Claims `dir` for the sweep `config`: writes its manifest the first time; refuses a folder
/// that holds another sweep (or other files) so no run overwrites another's results. The tasks
/// of an array job start together and take turns at this short set-up, each waiting up to
/// [`CLAIM_WAIT`] for the lock (found by the Slurm test: the second task had been refused).
fn claim_folder(dir: &Path, config: &SweepConfig) -> Result<()> {
    let start = std::time::Instant::now();
    let _lock = loop {
        if let Some(lock) = try_lock(&dir.join(".twv-sweep.lock"))? {
            break lock;
        }
        if start.elapsed() >= CLAIM_WAIT {
            return Err(folder_error(
                dir,
                format!(
                    "another twv process has been setting up this folder for {} s",
                    CLAIM_WAIT.as_secs()
                ),
            ));
        }
        std::thread::sleep(std::time::Duration::from_millis(10));
    };
    let manifest = dir.join("sweep.json");
    let hash = config.hash();
    if manifest.exists() {
        let text = fs::read_to_string(&manifest).map_err(|e| folder_error(&manifest, e))?;
        let found: Manifest =
            serde_json::from_str(&text).map_err(|e| folder_error(&manifest, e))?;
        if found.config_hash != hash || found.config != *config {
            return Err(folder_error(
                dir,
                format!(
                    "holds another sweep (config {}, this one {hash}): use another --out, or \
                     delete the folder",
                    found.config_hash
                ),
            ));
        }
        return Ok(());
    }
    let stranger = fs::read_dir(dir)
        .map_err(|e| folder_error(dir, e))?
        .filter_map(|e| e.ok())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .find(|n| !n.starts_with('.'));
    if let Some(name) = stranger {
        return Err(folder_error(
            dir,
            format!(
                "is not empty ({name}) and holds no sweep.json: give --out an empty or new folder"
            ),
        ));
    }
    let m = Manifest {
        format: SWEEP_FOLDER_FORMAT.into(),
        config_hash: hash,
        config: config.clone(),
    };
    let json = serde_json::to_string_pretty(&m).unwrap_or_default();
    write_atomic(&manifest, json.as_bytes())?;
    Ok(())
}

fn checkpoint_path(dir: &Path, shard: Shard) -> PathBuf {
    dir.join(format!(
        "checkpoint-{}-of-{}.json",
        shard.index, shard.count
    ))
}

/// The index ranges of `range` not in `done` (sorted by index).
fn missing(range: Range<usize>, done: &[PointResult]) -> Vec<Range<usize>> {
    let mut out = Vec::new();
    let mut next = range.start;
    for p in done {
        if p.index > next {
            out.push(next..p.index);
        }
        next = p.index + 1;
    }
    if next < range.end {
        out.push(next..range.end);
    }
    out
}

/// Runs one shard of the sweep `settings` into `dir` (created if missing): skips a complete
/// shard file unless `force`, resumes from a checkpoint, writes a checkpoint when `progress`
/// cancels. The folder is locked per shard, so the tasks of an array job share it safely.
pub fn run_shard(
    model: &ResolvedModel,
    settings: &SweepSettings,
    shard: Shard,
    dir: &Path,
    options: ShardOptions,
    progress: &dyn Progress,
) -> Result<ShardOutcome> {
    let config = settings.config(model)?;
    let created = !dir.exists();
    fs::create_dir_all(dir).map_err(|e| folder_error(dir, e))?;
    let result = run_shard_in(model, settings, &config, shard, dir, options, progress);
    if result.is_err() && created {
        // Nothing of a failed first run stays behind (the manifest included).
        let _ = fs::remove_dir_all(dir);
    }
    result
}

fn run_shard_in(
    model: &ResolvedModel,
    settings: &SweepSettings,
    config: &SweepConfig,
    shard: Shard,
    dir: &Path,
    options: ShardOptions,
    progress: &dyn Progress,
) -> Result<ShardOutcome> {
    claim_folder(dir, config)?;
    let path = dir.join(shard.file_name());
    let _lock = try_lock(&dir.join(format!(".{}.lock", shard.file_name())))?
        .ok_or_else(|| folder_error(&path, "another twv process is computing this shard"))?;
    if path.exists() && !options.force {
        if let Ok(file) = ShardFile::read(&path) {
            if file.is_complete_for(config, shard) {
                return Ok(ShardOutcome::Skipped { path });
            }
        }
    }
    let range = shard.range(config.grid.len());
    let hash = config.hash();
    let cp_path = checkpoint_path(dir, shard);
    let mut done: Vec<PointResult> = match fs::read_to_string(&cp_path) {
        Ok(text) if !options.force => serde_json::from_str::<Checkpoint>(&text)
            .ok()
            .filter(|c| c.config_hash == hash && c.shard == shard)
            .map(|c| c.points)
            .unwrap_or_default(),
        _ => Vec::new(),
    };
    done.retain(|p| range.contains(&p.index));
    done.sort_by_key(|p| p.index);
    done.dedup_by_key(|p| p.index);
    let resumed = done.len();
    let todo = missing(range.clone(), &done);
    // From here to the checkpoint's rename a second Ctrl-C waits (see output::InFlight): once
    // cancelled, the chunk under way ends and the checkpoint is written, or all is lost.
    let _checkpoint = crate::output::InFlight::new();
    let computed = compute_points(model, settings, config, &todo, progress)?;
    let complete = computed.complete;
    done.extend(computed.points);
    done.sort_by_key(|p| p.index);
    if !complete {
        let cp = Checkpoint {
            format: SWEEP_FOLDER_FORMAT.into(),
            config_hash: hash,
            shard,
            points: done.clone(),
        };
        let json = serde_json::to_string(&cp).unwrap_or_default();
        write_atomic(&cp_path, json.as_bytes())?;
        return Ok(ShardOutcome::Interrupted {
            checkpoint: cp_path,
            done: done.len(),
            total: range.len(),
        });
    }
    let written = ShardFile::new(config.clone(), shard, done.clone()).write(dir)?;
    let _ = fs::remove_file(&cp_path);
    Ok(ShardOutcome::Written {
        path: written,
        points: done,
        resumed,
    })
}

/// "N ok, M fell, …" for a summary line.
pub fn status_counts(points: &[PointResult]) -> String {
    let count = |s: Status| points.iter().filter(|p| p.status == s).count();
    let settled = points.iter().filter(|p| p.settled_at.is_some()).count();
    let tail = if settled > 0 {
        format!(" ({settled} finished by the settled tail)")
    } else {
        String::new()
    };
    format!(
        "{} ok{tail}, {} fell, {} blew up, {} not settled, {} failed",
        count(Status::Ok),
        count(Status::Fell),
        count(Status::BlewUp),
        count(Status::NotSettled),
        count(Status::Failed)
    )
}
