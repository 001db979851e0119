//! The subcommands: every job of the registry through one generic path (`crate::job`), with
//! what only the command line does for a few of them — `sweep` writes resumable shards, `audit`
//! audits every vehicle by default, `codegen --out` writes a source file — and the tools that
//! are not jobs (`report`, `merge`, `serve`), one file each.

pub mod audit;
pub mod codegen;
pub mod merge;
pub mod report;
pub mod serve;
pub mod sweep;

use anyhow::Result;
use clap::{ArgMatches, FromArgMatches};
use serde_json::Value;
use twv_analysis::jobs::{self, AnyJob};

use crate::common::{Context, Outcome};
use crate::job;

/// The subcommand of a job.
pub fn job_command(j: &'static dyn AnyJob) -> clap::Command {
    let cmd = job::command(j, j.files());
    match j.name() {
        "sweep" => sweep::augment(cmd),
        "audit" => audit::augment(cmd),
        "codegen" => codegen::augment(cmd),
        _ => cmd,
    }
}

/// Runs the subcommand `name` with its matches.
pub fn run(name: &str, m: &ArgMatches, ctx: &Context) -> Result<Outcome> {
    match name {
        "report" => report::run(&report::ReportArgs::from_arg_matches(m)?, ctx),
        "merge" => merge::run(&merge::MergeArgs::from_arg_matches(m)?, ctx),
        "serve" => serve::run(&serve::ServeArgs::from_arg_matches(m)?, ctx),
        name => {
            let j = jobs::find(name)?;
            let has_out = job::out_dir(m).is_some();
            match j.name() {
                "sweep" => sweep::run(j, m, ctx),
                "audit" => audit::run(j, m, ctx),
                "codegen" => codegen::run(j, m, ctx),
                // The running estimates only when they are written.
                "lyapunov" if !has_out => job::run(j, m, ctx, &[("running".into(), false.into())]),
                // The frequency response for the figures, when they are written.
                "linearize" if has_out => job::run(
                    j,
                    m,
                    ctx,
                    &[(
                        "frequency_points".into(),
                        Value::from(twv_analysis::api::FIGURE_FREQUENCY_POINTS),
                    )],
                ),
                _ => job::run(j, m, ctx, &[]),
            }
        }
    }
}

/// A library error from an interrupted run as the command's outcome; other errors pass.
pub fn interrupted_or<T>(
    result: twv_analysis::Result<T>,
    what: &str,
) -> Result<Result<T, Outcome>> {
    match result {
        Ok(v) => Ok(Ok(v)),
        Err(e) if e.is_interrupted() => Ok(Err(Outcome::Interrupted(format!(
            "{what} stopped; nothing written"
        )))),
        Err(e) => Err(e.into()),
    }
}
