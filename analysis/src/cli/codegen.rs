//! `twv codegen`: the Rust the emitter produces for a model, formatted for people to audit.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use twv_emit::{format_model, Options, Params};

use super::model::ModelArgs;

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

fn camel(name: &str) -> String {
    name.split('_')
        .map(|w| {
            let mut c = w.chars();
            c.next()
                .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
                .unwrap_or_default()
        })
        .collect()
}

pub fn run(args: &CodegenArgs) -> Result<()> {
    let loaded = args.model.clone().with_default("vehicle8").load()?;
    let params = if args.baked || args.model.params.is_some() {
        Params::Baked {
            values: loaded.params.clone(),
            source: loaded.params_origin.clone(),
        }
    } else {
        Params::Runtime
    };
    let name = args.name.clone().unwrap_or_else(|| camel(loaded.name()));
    let source = format_model(&loaded.ir, &Options { name, params })?;
    match &args.out {
        Some(path) => crate::output::write_atomic(path, source.as_bytes())?,
        None => print!("{source}"),
    }
    Ok(())
}
