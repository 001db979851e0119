//! `twv merge`: gather the shard files of one sweep, check that every index is present exactly
//! once, and write the map (CSV, JSON, SVG heat map with the stability boundary).
//!
//! The outputs depend only on the config and the points (in index order), never on how the
//! sweep was sharded: a sharded and an unsharded run merge to the same bytes.

use std::path::{Path, PathBuf};

use serde::Serialize;

use super::config::{Metric, SweepConfig};
use super::error::{ranges, SweepError};
use super::file::{shard_paths, ShardFile};
use super::grid::Axis;
use super::point::PointResult;
use crate::output::Files;
use crate::plot::{Figure, HeatMap};

/// Format tag of map.json.
pub const MAP_FORMAT: &str = "twv-sweep-map/1";

/// A complete sweep: one result per index, in index order.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Map {
    pub format: &'static str,
    pub config_hash: String,
    pub config: SweepConfig,
    pub points: Vec<PointResult>,
}

impl Map {
    /// A map of points computed in memory (no shard files): what the report draws.
    pub fn in_memory(
        model: &str,
        grid: super::grid::Grid,
        metric: Metric,
        points: Vec<PointResult>,
    ) -> Self {
        let config = SweepConfig {
            model: model.to_string(),
            source: String::new(),
            params: Vec::new(),
            metric,
            grid,
            x0: Vec::new(),
            controller: serde_json::Value::Null,
            settings: super::config::MetricSettings::default(),
        };
        Self {
            format: MAP_FORMAT,
            config_hash: config.hash(),
            config,
            points,
        }
    }
}

/// Reads every shard in `dir` and checks they form one complete sweep.
pub fn collect(dir: &Path) -> Result<Map, SweepError> {
    let paths = shard_paths(dir)?;
    let Some(first_path) = paths.first() else {
        return Err(SweepError::NoShards {
            dir: dir.to_path_buf(),
        });
    };
    let first = ShardFile::read(first_path)?;
    let total = first.config.grid.len();
    let mut slots: Vec<Option<(PointResult, usize)>> = vec![None; total];
    let mut duplicates: Vec<usize> = Vec::new();
    let mut duplicate_files: Vec<usize> = Vec::new();
    for (k, path) in paths.iter().enumerate() {
        let file = if k == 0 {
            first.clone()
        } else {
            ShardFile::read(path)?
        };
        if file.config_hash != first.config_hash || file.config != first.config {
            return Err(SweepError::MixedConfigs {
                path: path.clone(),
                found: file.config_hash,
                expected: first.config_hash.clone(),
                first: first_path.clone(),
            });
        }
        for p in file.points {
            let Some(slot) = slots.get_mut(p.index) else {
                return Err(SweepError::File {
                    path: path.clone(),
                    reason: format!("index {} outside the grid of {total} points", p.index),
                });
            };
            match slot {
                Some((_, other)) => {
                    duplicates.push(p.index);
                    duplicate_files.extend([*other, k]);
                }
                None => *slot = Some((p, k)),
            }
        }
    }
    let missing: Vec<usize> = (0..total).filter(|&i| slots[i].is_none()).collect();
    if !missing.is_empty() {
        return Err(SweepError::Missing {
            count: missing.len(),
            indices: ranges(&missing),
        });
    }
    if !duplicates.is_empty() {
        duplicates.sort_unstable();
        duplicates.dedup();
        duplicate_files.sort_unstable();
        duplicate_files.dedup();
        let files: Vec<String> = duplicate_files
            .iter()
            .map(|&k| paths[k].display().to_string())
            .collect();
        return Err(SweepError::Duplicate {
            count: duplicates.len(),
            indices: ranges(&duplicates),
            files: files.join(", "),
        });
    }
    Ok(Map {
        format: MAP_FORMAT,
        config_hash: first.config_hash.clone(),
        config: first.config,
        points: slots.into_iter().flatten().map(|(p, _)| p).collect(),
    })
}

impl Map {
    /// `index,kp,ki,kd,[parameters,]value,status`; an empty value where there is none.
    pub fn csv(&self) -> String {
        let grid = &self.config.grid;
        let mut s = String::from("index,kp,ki,kd,");
        for a in &grid.params {
            s += &format!("{},", a.name);
        }
        s += "value,status\n";
        for p in &self.points {
            let value = p.value.map(|v| v.to_string()).unwrap_or_default();
            let status = serde_json::to_value(p.status).expect("status serialises");
            let status = status.as_str().unwrap_or_default();
            s += &format!("{},{},{},{},", p.index, p.kp, p.ki, p.kd);
            for (_, v) in grid.param_values(grid.setting(p.index)) {
                s += &format!("{v},");
            }
            s += &format!("{value},{status}\n");
        }
        s
    }

    /// One heat map over cells `(x, y)` of the points at `indices` (x fastest).
    fn heat_map(
        &self,
        title: String,
        (x, y): (&(String, Axis), &(String, Axis)),
        indices: &[usize],
    ) -> Figure {
        let signed = self.config.metric != Metric::SettlingTime;
        let points: Vec<&PointResult> = indices.iter().map(|&i| &self.points[i]).collect();
        Figure::Heat(HeatMap {
            title,
            x_label: x.0.clone(),
            y_label: y.0.clone(),
            value_label: self.config.metric.label().into(),
            xs: x.1.values(),
            ys: y.1.values(),
            values: points.iter().map(|p| p.value.unwrap_or(f64::NAN)).collect(),
            missing: points
                .iter()
                .map(|p| p.value.is_none().then(|| p.status.label()))
                .collect(),
            boundary: points
                .iter()
                .map(|p| p.stability_indicator(signed))
                .collect(),
            signed,
            marks: Vec::new(),
            size: (960, 700),
        })
    }

    /// With parameter axes: heat maps over the first two axes that have more than one value
    /// (in index order: Kp, Kd, Ki, the parameters), one per combination of the others —
    /// `map.svg`, then `map-<k>.svg` — each titled with the values held fixed.
    fn parameter_figures(&self) -> Vec<(String, Figure)> {
        let axes = self.config.grid.axes();
        let mut strides = vec![1usize; axes.len()];
        for k in 1..axes.len() {
            strides[k] = strides[k - 1] * axes[k - 1].1.n;
        }
        let mut plane: Vec<usize> = (0..axes.len()).filter(|&k| axes[k].1.n > 1).collect();
        for k in 0..axes.len() {
            if plane.len() < 2 && !plane.contains(&k) {
                plane.push(k);
            }
        }
        plane.truncate(2);
        plane.sort_unstable();
        let (px, py) = (plane[0], plane[1]);
        let others: Vec<usize> = (0..axes.len()).filter(|k| !plane.contains(k)).collect();
        let slices: usize = others.iter().map(|&k| axes[k].1.n).product();
        (0..slices)
            .map(|slice| {
                let (mut rest, mut base, mut fixed) = (slice, 0, Vec::new());
                for &k in &others {
                    let i = rest % axes[k].1.n;
                    rest /= axes[k].1.n;
                    base += i * strides[k];
                    fixed.push(format!("{} = {}", axes[k].0, axes[k].1.value(i)));
                }
                let (sx, sy) = (strides[px], strides[py]);
                let nx = axes[px].1.n;
                let indices: Vec<usize> = (0..axes[py].1.n)
                    .flat_map(|j| (0..nx).map(move |i| base + i * sx + j * sy))
                    .collect();
                let title = format!(
                    "{}: {}{}{}",
                    self.config.model,
                    self.config.metric.label(),
                    if fixed.is_empty() { "" } else { ", " },
                    fixed.join(", ")
                );
                let name = if slice == 0 {
                    "map.svg".to_string()
                } else {
                    format!("map-{slice}.svg")
                };
                (name, self.heat_map(title, (&axes[px], &axes[py]), &indices))
            })
            .collect()
    }

    /// Heat maps over (Kp, Kd), one per Ki value: `map.svg` for the first Ki (the only one
    /// without a Ki axis), `map-ki-<k>.svg` for the k-th after it; with parameter axes see
    /// `parameter_figures`.
    pub fn figures(&self) -> Vec<(String, Figure)> {
        let grid = &self.config.grid;
        if !grid.params.is_empty() {
            return self.parameter_figures();
        }
        let axes = grid.axes();
        let n = grid.map_len();
        (0..grid.n_ki())
            .map(|k| {
                let ki = grid.ki.map_or(0.0, |a| a.value(k));
                let title = format!(
                    "{} over (Kp, Kd), Ki = {ki}: {}",
                    self.config.model,
                    self.config.metric.label()
                );
                let indices: Vec<usize> = (k * n..(k + 1) * n).collect();
                let name = if k == 0 {
                    "map.svg".to_string()
                } else {
                    format!("map-ki-{k}.svg")
                };
                (name, self.heat_map(title, (&axes[0], &axes[1]), &indices))
            })
            .collect()
    }
}

impl Map {
    /// map.csv, map.json and the figures (SVG and PNG).
    pub fn files(&self) -> Result<Files, SweepError> {
        let mut files = Files::new();
        files.text("map.csv", self.csv());
        files.json("map.json", self);
        for (name, figure) in self.figures() {
            files.figure(&name, &figure)?;
        }
        Ok(files)
    }
}

/// Merges the shards in `dir` and writes map.csv, map.json and the figures there (all or
/// nothing).
pub fn merge(dir: &Path) -> Result<(Map, Vec<PathBuf>), SweepError> {
    let map = collect(dir)?;
    let written = map.files()?.write(dir)?.files;
    Ok((map, written))
}
