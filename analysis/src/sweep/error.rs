//! Typed errors of sweeps: grid and shard specifications, shard files, and the merge checks.

use std::path::PathBuf;

/// Why a sweep could not be set up, written or merged.
#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    /// A `--kp/--kd/--ki A:B:N` axis that does not parse or is empty (named by its flag, so
    /// `against_values` is `--against-values`).
    #[error("--{} `{text}`: {reason} (want A:B:N, e.g. 0:8000:100)", .axis.replace('_', "-"))]
    Axis {
        axis: &'static str,
        text: String,
        reason: String,
    },
    /// A `--shard i/N` (or an environment variable) that does not name a shard.
    #[error("shard `{text}`: {reason}")]
    Shard { text: String, reason: String },
    /// A shard file that cannot be read or parsed.
    #[error("{path}: {reason}")]
    File { path: PathBuf, reason: String },
    /// The folder holds no shard files.
    #[error("{dir}: no shard files (shard-<i>-of-<N>.json)")]
    NoShards { dir: PathBuf },
    /// Shards of different sweeps in one folder.
    #[error(
        "{path} belongs to another sweep (config hash {found}, expected {expected} from {first})"
    )]
    MixedConfigs {
        path: PathBuf,
        found: String,
        expected: String,
        first: PathBuf,
    },
    /// Grid points with no result.
    #[error("{count} grid point(s) missing: indices {indices} (run the missing shards)")]
    Missing { count: usize, indices: String },
    /// Grid points with more than one result (overlapping shards, e.g. of two shard counts).
    #[error("{count} grid point(s) present more than once: indices {indices} (in {files})")]
    Duplicate {
        count: usize,
        indices: String,
        files: String,
    },
    /// A metric setting out of range.
    #[error("metric_settings.{field}: {reason}")]
    Setting { field: &'static str, reason: String },
    /// Writing the output failed.
    #[error(transparent)]
    Output(#[from] crate::output::OutputError),
    /// Drawing the map failed.
    #[error(transparent)]
    Plot(#[from] crate::plot::PlotError),
}

/// Index lists as compact ranges: `0-4, 9, 12-13`, at most 20 ranges.
pub fn ranges(indices: &[usize]) -> String {
    let mut parts: Vec<String> = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        parts.push(if i == j {
            indices[i].to_string()
        } else {
            format!("{}-{}", indices[i], indices[j])
        });
        i = j + 1;
    }
    if parts.len() > 20 {
        let more = parts.len() - 20;
        parts.truncate(20);
        parts.push(format!("… ({more} more ranges)"));
    }
    parts.join(", ")
}
