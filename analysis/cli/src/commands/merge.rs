//! `twv merge`: the shards of a sweep (or of an uncertainty run) checked for completeness and
//! joined.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use twv_analysis::api::{merge_uncertainty_dir, uncertainty_shard_files};
use twv_analysis::jobs::{JobOutput, Verdict};
use twv_analysis::sweep::{merge, shard_paths, Status};

use crate::common::{print, Context, Outcome};

/// Merge the shards of a sweep into map.csv, map.json and map.svg (+ PNG), or those of an
/// uncertainty run into uncertainty.csv, uncertainty.json and its figures.
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The folder the shards were written to (`twv sweep --out DIR`, `twv uncertainty --out DIR`)
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
}

pub fn run(args: &MergeArgs, ctx: &Context) -> Result<Outcome> {
    let sweep_shards = shard_paths(&args.dir)?;
    if sweep_shards.is_empty() && !uncertainty_shard_files(&args.dir)?.is_empty() {
        let (whole, files) = merge_uncertainty_dir(&args.dir)?;
        for path in files {
            ctx.say(format!("wrote {}", path.display()));
        }
        print(&whole.summary())?;
        return Ok(match whole.verdict() {
            Verdict::Done => Outcome::Done,
            Verdict::Negative(why) => Outcome::Negative(why),
        });
    }
    let (map, files) = merge(&args.dir)?;
    for path in files {
        ctx.say(format!("wrote {}", path.display()));
    }
    let ok = map.points.iter().filter(|p| p.status == Status::Ok).count();
    print(&format!(
        "{} points of {} ({}): {ok} with a value\n",
        map.points.len(),
        map.config.model,
        map.config.metric.label()
    ))?;
    Ok(Outcome::Done)
}
