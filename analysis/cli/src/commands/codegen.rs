//! `twv codegen`: the Rust the emitter produces for a model, formatted for people to audit.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use twv_analysis::api::{generate, CodegenSettings};
use twv_analysis::output::write_atomic;

use crate::common::{print, Context, ModelArgs, Outcome};

/// Print the generated Rust of a model (prettyplease-formatted).
#[derive(Args, Debug)]
pub struct CodegenArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Name of the emitted struct [default: the model name in CamelCase]
    #[arg(long, value_name = "IDENT")]
    pub name: Option<String>,
    /// Fold the parameters of --params (or the defaults) into the code as constants
    #[arg(long)]
    pub baked: bool,
    /// Write to this file (atomically) instead of stdout
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
}

pub fn run(args: &CodegenArgs, ctx: &Context) -> Result<Outcome> {
    let model = args.model.resolve(ctx)?;
    let source = generate(
        &model,
        &CodegenSettings {
            name: args.name.clone(),
            baked: args.baked || args.model.params.is_some(),
        },
    )?;
    match &args.out {
        Some(path) => write_atomic(path, source.as_bytes())?,
        None => print(&source)?,
    }
    Ok(Outcome::Done)
}
