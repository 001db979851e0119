//! `twv sweep`: one shard of a stability map (the registry's `sweep` job, its options as flags)
//! written into a folder a cluster array shares, resumable from a checkpoint; `twv merge` joins
//! the shards.

use anyhow::{bail, Result};
use clap::{Arg, ArgAction, ArgMatches, Command, FromArgMatches};
use twv_analysis::api::{run_shard, status_counts, ShardOptions, ShardOutcome, SweepSettings};
use twv_analysis::jobs::AnyJob;
use twv_analysis::sweep::Shard;

use crate::common::{Context, ModelArgs, Outcome};
use crate::job;

/// The flags only the command line's sweep has: which shard, and whether to redo it.
pub fn augment(cmd: Command) -> Command {
    cmd.about(
        "Stability map over PID gains and model parameters: one shard of it into --out \
         (resumable; Slurm/Kubernetes arrays), `twv merge` joins them",
    )
    .arg(
        Arg::new("shard")
            .long("shard")
            .value_name("i/N")
            .help(
                "This job's shard i/N [default: from SLURM_ARRAY_TASK_ID/_MIN/_COUNT, or \
                 JOB_COMPLETION_INDEX with --shards/TWV_SHARDS; else the whole sweep]",
            ),
    )
    .arg(
        Arg::new("shards")
            .long("shards")
            .value_name("N")
            .value_parser(clap::value_parser!(usize))
            .conflicts_with("shard")
            .help("Number of shards for a Kubernetes indexed job (its `completions`) [env: TWV_SHARDS]"),
    )
    .arg(
        Arg::new("force")
            .long("force")
            .action(ArgAction::SetTrue)
            .help("Recompute the shard even if its file is complete (ignores a checkpoint)"),
    )
}

fn shard(m: &ArgMatches) -> Result<Shard> {
    Ok(match m.get_one::<String>("shard") {
        Some(text) => Shard::parse(text)?,
        None => Shard::from_env(
            |k| std::env::var(k).ok(),
            m.get_one::<usize>("shards").copied(),
        )?,
    })
}

pub fn run(j: &dyn AnyJob, m: &ArgMatches, ctx: &Context) -> Result<Outcome> {
    let prepared = job::prepare(j, m, &[])?;
    if job::printed_settings(prepared.as_ref(), m)? {
        return Ok(Outcome::Done);
    }
    let Some(out) = job::out_dir(m) else {
        bail!("--out is required: the folder of the shard files (shared by all shards; `twv merge` reads it)");
    };
    let settings: SweepSettings = serde_json::from_value(prepared.settings())?;
    let model = ModelArgs::from_arg_matches(m)?.resolve(ctx)?;
    let shard = shard(m)?;
    let bar = ctx.bar();
    let start = std::time::Instant::now();
    let options = ShardOptions {
        force: m.get_flag("force"),
    };
    match run_shard(&model, &settings, shard, out, options, &bar)? {
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
