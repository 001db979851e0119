//! `twv merge`: the shards of a sweep checked for completeness and drawn.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use twv_analysis::sweep::{merge, Status};

use crate::common::{print, Context, Outcome};

/// Merge the shards of a sweep into map.csv, map.json and map.svg (+ PNG).
#[derive(Args, Debug)]
pub struct MergeArgs {
    /// The folder the shards were written to (`twv sweep --out DIR`)
    #[arg(value_name = "DIR")]
    pub dir: PathBuf,
}

pub fn run(args: &MergeArgs, ctx: &Context) -> Result<Outcome> {
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
