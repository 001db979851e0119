//! The shard file `shard-<i>-of-<N>.json`: the sweep config, its hash, the shard, its index
//! range and one result per index in order. Written atomically, so a file that exists is
//! complete unless its config differs — which is what makes shards resumable.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::config::SweepConfig;
use super::error::SweepError;
use super::point::PointResult;
use super::shard::Shard;
use crate::output::write_atomic;

/// Format tag of shard files.
pub const SHARD_FORMAT: &str = "twv-sweep-shard/1";

/// The contents of one shard file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ShardFile {
    pub format: String,
    pub config_hash: String,
    pub config: SweepConfig,
    pub shard: Shard,
    /// First index and one past the last.
    pub start: usize,
    pub end: usize,
    pub points: Vec<PointResult>,
}

impl ShardFile {
    /// A shard's file for `points`.
    pub fn new(config: SweepConfig, shard: Shard, points: Vec<PointResult>) -> Self {
        let range = shard.range(config.grid.len());
        Self {
            format: SHARD_FORMAT.to_string(),
            config_hash: config.hash(),
            config,
            shard,
            start: range.start,
            end: range.end,
            points,
        }
    }

    /// Reads and parses a shard file.
    pub fn read(path: &Path) -> Result<Self, SweepError> {
        let err = |reason: String| SweepError::File {
            path: path.to_path_buf(),
            reason,
        };
        let text = std::fs::read_to_string(path).map_err(|e| err(e.to_string()))?;
        let file: Self = serde_json::from_str(&text).map_err(|e| err(e.to_string()))?;
        if file.format != SHARD_FORMAT {
            return Err(err(format!(
                "format `{}`, expected `{SHARD_FORMAT}`",
                file.format
            )));
        }
        if file.config_hash != file.config.hash() {
            return Err(err(
                "the config hash does not match the config (edited?)".into()
            ));
        }
        Ok(file)
    }

    /// Whether this file holds every point of `shard` of the sweep `config`.
    pub fn is_complete_for(&self, config: &SweepConfig, shard: Shard) -> bool {
        let range = shard.range(config.grid.len());
        self.config == *config
            && self.shard == shard
            && (self.start, self.end) == (range.start, range.end)
            && self.points.len() == range.len()
            && self.points.iter().zip(range).all(|(p, i)| p.index == i)
    }

    /// Writes the file atomically to `dir`.
    pub fn write(&self, dir: &Path) -> Result<PathBuf, SweepError> {
        let path = dir.join(self.shard.file_name());
        let json = serde_json::to_string_pretty(self).expect("a shard serialises");
        write_atomic(&path, json.as_bytes())?;
        Ok(path)
    }
}

/// The shard files in `dir` (`shard-*-of-*.json`), sorted by name for a stable order.
pub fn shard_paths(dir: &Path) -> Result<Vec<PathBuf>, SweepError> {
    shard_files_named(dir, "shard-").map_err(|e| SweepError::File {
        path: dir.to_path_buf(),
        reason: e.to_string(),
    })
}

/// The files `<prefix>*-of-*.json` in `dir`, sorted by name: the shard files of a sweep, or of
/// another sharded job (`uncertainty-shard-`).
pub fn shard_files_named(dir: &Path, prefix: &str) -> std::io::Result<Vec<PathBuf>> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name().and_then(|n| n.to_str()).is_some_and(|n| {
                n.starts_with(prefix) && n.contains("-of-") && n.ends_with(".json")
            })
        })
        .collect();
    paths.sort();
    Ok(paths)
}
