//! `twv audit`: the registry's `audit` job, and by default every vehicle the hand model covers
//! (`--model all`); with `--hand`, any model against your own hand file.

use anyhow::{bail, Result};
use clap::{ArgMatches, Command, FromArgMatches};
use twv_analysis::api::AUDITED;
use twv_analysis::hand_file::model_named_in;
use twv_analysis::jobs::{AnyJob, Verdict};

use crate::common::{print, Context, ModelArgs, Outcome};
use crate::job;

/// `--model` also takes `all` here.
pub fn augment(cmd: Command) -> Command {
    cmd.mut_arg("model", |a| {
        a.help(format!(
            "{}, or all; with --hand any shipped model [default: all, or with --hand the \
             file's `model`]",
            AUDITED.join(", ")
        ))
    })
}

pub fn run(j: &dyn AnyJob, m: &ArgMatches, ctx: &Context) -> Result<Outcome> {
    let prepared = job::prepare(j, m, &[])?;
    if job::printed_settings(prepared.as_ref(), m)? {
        return Ok(Outcome::Done);
    }
    let args = ModelArgs::from_arg_matches(m)?;
    let hand = m.get_one::<String>("hand");
    let names: Vec<Option<String>> = match (hand, args.model.as_deref()) {
        (Some(path), None) if args.ir.is_none() => {
            let text = std::fs::read_to_string(path)
                .map_err(|e| anyhow::anyhow!("cannot read {path}: {e}"))?;
            match model_named_in(&text, path)? {
                Some(name) => vec![Some(name)],
                None => {
                    bail!("{path}: says no `model = \"…\"`; name the model with --model or --ir")
                }
            }
        }
        (Some(_), name) => vec![name.map(str::to_string)],
        (None, _) if args.ir.is_some() => {
            bail!("--ir needs --hand: the audit of an IR is against your hand file")
        }
        (None, None | Some("all")) => AUDITED.iter().map(|n| Some(n.to_string())).collect(),
        (None, Some(one)) if AUDITED.contains(&one) => vec![Some(one.to_string())],
        (None, Some(other)) => bail!(
            "--model {other}: the audit covers {} or all",
            AUDITED.join(", ")
        ),
    };
    let mut results = Vec::new();
    let mut failed = Vec::new();
    for name in names {
        let model = ModelArgs {
            model: name,
            ..args.clone()
        }
        .resolve(ctx)?;
        let done = prepared.run(&model, &ctx.bar())?;
        if let Verdict::Negative(why) = done.verdict() {
            failed.push(why);
        }
        results.push(done);
    }
    if m.get_flag("json") {
        let values = results
            .iter()
            .map(|d| d.value())
            .collect::<Result<Vec<_>, _>>()?;
        let text = if values.len() == 1 {
            serde_json::to_string_pretty(&values[0])?
        } else {
            serde_json::to_string_pretty(&values)?
        };
        print(&(text + "\n"))?;
    } else {
        print(&results.iter().map(|d| d.summary()).collect::<String>())?;
    }
    Ok(if failed.is_empty() {
        Outcome::Done
    } else {
        Outcome::Negative(failed.join("; "))
    })
}
