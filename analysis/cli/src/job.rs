//! Every job of the library's registry as a subcommand: its flags are the job's options (name,
//! help, unit and default all from the library), their values go back to the library as they
//! were typed, and the library lays them over its default settings, checks them and runs the
//! job. Nothing here restates a default or a rule between options.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use clap::{Arg, ArgAction, ArgMatches, Args, Command, FromArgMatches};
use serde_json::Value;
use twv_analysis::jobs::{AnyJob, Finished, Kind, OptionInfo, Prepared, Verdict};

use crate::common::{print, write_files, Context, ModelArgs, Outcome};

/// Front-end options every job's subcommand has besides its own.
const OUT: &str = "out";
const JSON: &str = "json";
const SETTINGS: &str = "settings";
const PRINT_SETTINGS: &str = "print-settings";

/// The flag of an option: `t_end` is `--t-end`.
pub fn flag_name(option: &str) -> String {
    option.replace('_', "-")
}

/// What a flag's value looks like, for `--help`.
fn value_name(o: &OptionInfo) -> String {
    match o.kind {
        Kind::Number => match o.unit {
            "" => "X".into(),
            unit if unit.contains(' ') || unit.contains(',') => "X".into(),
            unit => unit.to_uppercase(),
        },
        Kind::Integer => "N".into(),
        Kind::Vector => "V1,V2,...".into(),
        Kind::Choice => o.choices.join("|").to_uppercase(),
        Kind::Text | Kind::Flag => "TEXT".into(),
    }
}

/// The help line of an option: its help, unit and the library's default.
fn help(o: &OptionInfo) -> String {
    let mut text = o.help.to_string();
    if !o.unit.is_empty() && o.kind != Kind::Flag {
        text += &format!(" [{}]", o.unit);
    }
    if !matches!(o.kind, Kind::Flag) {
        match &o.default {
            Value::Null if o.required => text += " (required)",
            Value::Null => text += " [default: none]",
            v => text += &format!(" [default: {}]", twv_analysis::jobs::options::display(v)),
        }
    }
    text
}

/// The clap argument of an option.
fn arg(o: &OptionInfo) -> Arg {
    let name = flag_name(o.name);
    let mut a = Arg::new(o.name)
        .long(name)
        .help(help(o))
        .visible_aliases(o.aliases.iter().map(|a| flag_name(a)).collect::<Vec<_>>());
    a = match o.kind {
        Kind::Flag => a.action(ArgAction::SetTrue),
        _ => a
            .action(if o.many {
                ArgAction::Append
            } else {
                ArgAction::Set
            })
            .value_name(value_name(o))
            .allow_hyphen_values(true),
    };
    a
}

/// The subcommand of `job`, with the model's flags and `extra` ones of the front end.
pub fn command(job: &dyn AnyJob, files: &'static str) -> Command {
    // A `_` of a name is a `-` on the command line (`steer-map`); the name as the registry
    // spells it still answers.
    let kebab = job.name().replace('_', "-");
    let spelled = (kebab != job.name()).then(|| job.name().to_string());
    let mut cmd = Command::new(kebab)
        .about(job.summary())
        .visible_aliases(cli_aliases(job))
        .aliases(spelled)
        .aliases(
            job.aliases()
                .iter()
                .filter(|a| !cli_aliases(job).contains(a))
                .flat_map(|a| {
                    let kebab = a.replace('_', "-");
                    let both = if kebab == *a {
                        vec![kebab]
                    } else {
                        vec![a.to_string(), kebab]
                    };
                    both.into_iter()
                })
                .collect::<Vec<_>>(),
        )
        .allow_negative_numbers(true);
    cmd = ModelArgs::augment_args(cmd).about(job.summary());
    for o in job.options() {
        cmd = cmd.arg(arg(&o));
    }
    cmd.arg(
        Arg::new(OUT)
            .long(OUT)
            .value_name("DIR")
            .value_parser(clap::value_parser!(PathBuf))
            .help(format!("Write the results into this folder: {files}")),
    )
    .arg(
        Arg::new(JSON)
            .long(JSON)
            .action(ArgAction::SetTrue)
            .help("Print the result as JSON on stdout instead of the summary"),
    )
    .arg(
        Arg::new(SETTINGS)
            .long(SETTINGS)
            .value_name("FILE")
            .value_parser(clap::value_parser!(PathBuf))
            .help(
                "Start from these settings (the job's JSON settings, as `--print-settings` \
                 writes them) instead of the defaults; the flags are laid over them",
            ),
    )
    .arg(
        Arg::new(PRINT_SETTINGS)
            .long(PRINT_SETTINGS)
            .action(ArgAction::SetTrue)
            .help("Print the settings the job would run with, as JSON, and stop"),
    )
}

/// The short names people type (`sim`, `lyap`, `linear`, `eval`), shown in `--help`.
fn cli_aliases(job: &dyn AnyJob) -> Vec<&'static str> {
    job.aliases()
        .iter()
        .copied()
        .filter(|a| matches!(*a, "sim" | "lyap" | "linear" | "eval"))
        .collect()
}

/// The options given on the command line, as they were typed (flags as `true`).
pub fn given(job: &dyn AnyJob, m: &ArgMatches) -> Vec<(String, Value)> {
    let mut out = Vec::new();
    for o in job.options() {
        if o.kind == Kind::Flag {
            if m.get_flag(o.name) {
                out.push((o.name.to_string(), Value::Bool(true)));
            }
        } else if o.many {
            if let Some(v) = m.get_many::<String>(o.name) {
                out.push((
                    o.name.to_string(),
                    Value::Array(v.cloned().map(Value::String).collect()),
                ));
            }
        } else if let Some(v) = m.get_one::<String>(o.name) {
            out.push((o.name.to_string(), Value::String(v.clone())));
        }
    }
    out
}

/// The output folder (`--out`).
pub fn out_dir(m: &ArgMatches) -> Option<&Path> {
    m.get_one::<PathBuf>(OUT).map(PathBuf::as_path)
}

/// The job's settings: `--settings FILE` (or the defaults) with the flags laid over them and
/// `more` (options the front end adds) after them.
pub fn prepare(
    job: &dyn AnyJob,
    m: &ArgMatches,
    more: &[(String, Value)],
) -> Result<Box<dyn Prepared>> {
    let base = match m.get_one::<PathBuf>(SETTINGS) {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("--settings: cannot read {}", path.display()))?;
            Some(
                serde_json::from_str::<Value>(&text)
                    .with_context(|| format!("--settings: {} is not JSON", path.display()))?,
            )
        }
        None => None,
    };
    let mut options = given(job, m);
    for (name, value) in more {
        if !options.iter().any(|(n, _)| n == name) {
            options.push((name.clone(), value.clone()));
        }
    }
    Ok(job.prepare_options(base.as_ref(), &options)?)
}

/// Whether `--print-settings` was given: prints the settings and says so.
pub fn printed_settings(prepared: &dyn Prepared, m: &ArgMatches) -> Result<bool> {
    if !m.get_flag(PRINT_SETTINGS) {
        return Ok(false);
    }
    print(&(serde_json::to_string_pretty(&prepared.settings())? + "\n"))?;
    Ok(true)
}

/// Runs `job` as the command line asks: writes its files (with `--out`), prints its summary
/// (or JSON), and turns its verdict into the outcome.
pub fn run(
    job: &dyn AnyJob,
    m: &ArgMatches,
    ctx: &Context,
    more: &[(String, Value)],
) -> Result<Outcome> {
    let model_args = ModelArgs::from_arg_matches(m)?;
    let prepared = prepare(job, m, more)?;
    if printed_settings(prepared.as_ref(), m)? {
        return Ok(Outcome::Done);
    }
    let model = model_args.resolve(ctx)?;
    let bar = ctx.bar();
    let done = match crate::commands::interrupted_or(
        prepared.run(&model, &bar),
        &format!("the {}", job.name()),
    )? {
        Ok(done) => done,
        Err(outcome) => return Ok(outcome),
    };
    finish(done.as_ref(), m, ctx)
}

/// Writes, prints and judges a finished job.
pub fn finish(done: &dyn Finished, m: &ArgMatches, ctx: &Context) -> Result<Outcome> {
    if let Some(dir) = out_dir(m) {
        write_files(ctx, dir, &done.files()?)?;
    }
    if m.get_flag(JSON) {
        print(&(done.json()? + "\n"))?;
    } else {
        print(&done.summary())?;
    }
    Ok(match done.verdict() {
        Verdict::Done => Outcome::Done,
        Verdict::Negative(why) => Outcome::Negative(why),
    })
}
