//! `twv codegen`: the registry's `codegen` job; `--out FILE` writes the source (atomically)
//! instead of printing it, and a parameter file folds its values in.

use anyhow::Result;
use clap::{ArgMatches, Command, FromArgMatches};
use serde_json::Value;
use twv_analysis::jobs::AnyJob;
use twv_analysis::output::write_atomic;

use crate::common::{print, Context, ModelArgs, Outcome};
use crate::job;

/// `--out` is the file of the source here.
pub fn augment(cmd: Command) -> Command {
    cmd.mut_arg("out", |a| {
        a.value_name("FILE")
            .help("Write the source to this file (atomically) instead of stdout")
    })
}

pub fn run(j: &dyn AnyJob, m: &ArgMatches, ctx: &Context) -> Result<Outcome> {
    let args = ModelArgs::from_arg_matches(m)?;
    // Parameters given in a file are what the code is for: fold them in.
    let more: Vec<(String, Value)> = if args.params.is_some() {
        vec![("baked".into(), Value::Bool(true))]
    } else {
        Vec::new()
    };
    let prepared = job::prepare(j, m, &more)?;
    if job::printed_settings(prepared.as_ref(), m)? {
        return Ok(Outcome::Done);
    }
    let done = prepared.run(&args.resolve(ctx)?, &ctx.bar())?;
    let source = done.summary();
    match job::out_dir(m) {
        Some(path) => write_atomic(path, source.as_bytes())?,
        None => print(&source)?,
    }
    Ok(Outcome::Done)
}
