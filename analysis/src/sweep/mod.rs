//! Stability maps over controller gains, built to scale out: a grid whose points are numbered
//! in a fixed (row-major) order, shards that each compute one contiguous index range and are
//! written atomically and resumably, and a merge that checks completeness and draws the map.
//!
//! - [`Grid`], [`Axis`]: `--kp A:B:N --kd C:D:M [--ki E:F:L]`, index order Kp fastest, then
//!   Kd, then Ki.
//! - [`Shard`]: `i/N`, or from a Slurm array / Kubernetes indexed job ([`Shard::from_env`]).
//! - [`SweepConfig`]: everything a point depends on besides its index, hashed so shards of
//!   different sweeps are never merged.
//! - [`metric`]: the three metrics at one point ([`max_lyapunov_lanes`]: λ1 of a chunk of
//!   points eight at a time, with the bits of the one-point metric; `settle`: its settled
//!   tail, within [`SETTLED_TAIL_TOLERANCE`]); [`ShardFile`]: the shard format; [`merge()`]:
//!   the merge.
//!
//! Running the points (model dispatch, rayon, progress) is the CLI's job (`cli/sweep.rs`).

mod config;
mod error;
mod fall;
mod file;
mod grid;
mod lanes;
mod merge;
pub mod metric;
mod point;
mod settle;
mod shard;

pub use config::{Metric, MetricSettings, SweepConfig};
pub use error::{ranges, SweepError};
pub use fall::FallStop;
pub use file::{shard_files_named, shard_paths, ShardFile, SHARD_FORMAT};
pub use grid::{Axis, Grid, ParamAxis, TILT_AXIS};
pub use lanes::{max_lyapunov_lanes, DriverChoice};
pub use merge::{collect, merge, Map, MAP_FORMAT};
pub use point::{PointResult, Status};
pub use settle::SETTLED_TAIL_TOLERANCE;
pub use shard::Shard;
