//! Shards: a contiguous index range per job, chosen explicitly (`--shard i/N`) or from the
//! environment of a Slurm array or a Kubernetes indexed job, so one binary and one command line
//! serve every task of the array.

use std::ops::Range;

use serde::{Deserialize, Serialize};

use super::error::SweepError;

/// Shard `index` of `count` (0-based).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    pub index: usize,
    pub count: usize,
}

fn bad(text: &str, reason: impl Into<String>) -> SweepError {
    SweepError::Shard {
        text: text.to_string(),
        reason: reason.into(),
    }
}

fn number(name: &str, text: &str) -> Result<usize, SweepError> {
    text.trim()
        .parse()
        .map_err(|_| bad(text, format!("{name} is not a non-negative integer")))
}

impl Shard {
    /// The whole sweep in one shard.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// A checked shard (count ≥ 1, index < count).
    pub fn new(index: usize, count: usize) -> Result<Self, SweepError> {
        if count == 0 || index >= count {
            return Err(bad(&format!("{index}/{count}"), "need N ≥ 1 and 0 ≤ i < N"));
        }
        Ok(Self { index, count })
    }

    /// Parses `i/N`.
    pub fn parse(text: &str) -> Result<Self, SweepError> {
        let (i, n) = text
            .split_once('/')
            .ok_or_else(|| bad(text, "want i/N, e.g. 3/16"))?;
        Self::new(number("i", i)?, number("N", n)?)
            .map_err(|_| bad(text, "need N ≥ 1 and 0 ≤ i < N"))
    }

    /// The shard of this job from its environment (`var` looks a variable up; `shards` is
    /// `--shards N`, which wins over `TWV_SHARDS`):
    ///
    /// - Slurm array: index `SLURM_ARRAY_TASK_ID − SLURM_ARRAY_TASK_MIN` (MIN defaults to 0),
    ///   count `SLURM_ARRAY_TASK_COUNT` (or `--shards`/`TWV_SHARDS`); arrays with a step
    ///   (`--array=0-15:2`) are rejected, their IDs do not map onto 0..N.
    /// - Kubernetes indexed job: index `JOB_COMPLETION_INDEX`, count from `--shards` or
    ///   `TWV_SHARDS` (the job's `completions`).
    /// - Neither: the whole sweep (0/1); a shard count without an index is an error, since
    ///   silently running everything in every task would be wrong.
    pub fn from_env(
        var: impl Fn(&str) -> Option<String>,
        shards: Option<usize>,
    ) -> Result<Self, SweepError> {
        let count = |fallback: Option<String>, what: &str| -> Result<usize, SweepError> {
            if let Some(n) = shards {
                return Ok(n);
            }
            if let Some(t) = var("TWV_SHARDS") {
                return number("TWV_SHARDS", &t);
            }
            match fallback {
                Some(t) => number(what, &t),
                None => Err(bad(
                    what,
                    format!("unknown shard count: set --shards N or TWV_SHARDS ({what})"),
                )),
            }
        };
        if let Some(id) = var("SLURM_ARRAY_TASK_ID") {
            if let Some(step) = var("SLURM_ARRAY_TASK_STEP") {
                if number("SLURM_ARRAY_TASK_STEP", &step)? != 1 {
                    return Err(bad(&step, "Slurm arrays with a step are not supported"));
                }
            }
            let id = number("SLURM_ARRAY_TASK_ID", &id)?;
            let min = match var("SLURM_ARRAY_TASK_MIN") {
                Some(t) => number("SLURM_ARRAY_TASK_MIN", &t)?,
                None => 0,
            };
            let index = id.checked_sub(min).ok_or_else(|| {
                bad(
                    &id.to_string(),
                    "SLURM_ARRAY_TASK_ID < SLURM_ARRAY_TASK_MIN",
                )
            })?;
            let n = count(var("SLURM_ARRAY_TASK_COUNT"), "SLURM_ARRAY_TASK_COUNT")?;
            return Self::new(index, n);
        }
        if let Some(i) = var("JOB_COMPLETION_INDEX") {
            let index = number("JOB_COMPLETION_INDEX", &i)?;
            let n = count(None, "Kubernetes indexed job")?;
            return Self::new(index, n);
        }
        match shards.or(var("TWV_SHARDS")
            .map(|t| number("TWV_SHARDS", &t))
            .transpose()?)
        {
            None | Some(1) => Ok(Self::WHOLE),
            Some(n) => Err(bad(
                &n.to_string(),
                "a shard count without a shard index: give --shard i/N or run as a Slurm \
                 array / Kubernetes indexed job",
            )),
        }
    }

    /// This shard's contiguous part of `0..total`: `[total·i/N, total·(i+1)/N)`.
    pub fn range(&self, total: usize) -> Range<usize> {
        let at = |i: usize| (total as u128 * i as u128 / self.count as u128) as usize;
        at(self.index)..at(self.index + 1)
    }

    /// The shard's file name.
    pub fn file_name(&self) -> String {
        format!("shard-{}-of-{}.json", self.index, self.count)
    }
}
