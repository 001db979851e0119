//! `twv audit`: the generated vehicle models against the independent hand model.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use twv_analysis::api::{audit_model, AUDITED};
use twv_analysis::audit::AuditSettings;

use crate::common::{print, print_result, Context, ModelArgs, Outcome};

/// Audit the derived (generated) model term by term against the hand model, plus physical checks.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct AuditArgs {
    /// vehicle8, vehicle7, segway7 or all
    #[arg(long, value_name = "NAME", default_value = "all")]
    pub model: String,
    /// Parameter file (TOML) [default: each vehicle's own, embedded]
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// Random samples (states and inputs) besides the upright and hanging rest states
    #[arg(long, value_name = "N", default_value_t = 200)]
    pub samples: usize,
    /// Seed of the samples
    #[arg(long, value_name = "S", default_value_t = 2016)]
    pub seed: u64,
    /// Largest accepted normwise relative error of a term
    #[arg(long, value_name = "REL", default_value_t = 1e-11)]
    pub tolerance: f64,
    /// Print JSON instead of the table
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &AuditArgs, ctx: &Context) -> Result<Outcome> {
    let settings = AuditSettings {
        samples: args.samples,
        seed: args.seed,
        tolerance: args.tolerance,
        ..AuditSettings::default()
    };
    let names: Vec<&str> = match args.model.as_str() {
        "all" => AUDITED.to_vec(),
        one if AUDITED.contains(&one) => vec![one],
        other => bail!(
            "--model {other}: the audit covers {} or all",
            AUDITED.join(", ")
        ),
    };
    let reports = names
        .iter()
        .map(|name| {
            let model = ModelArgs {
                model: Some(name.to_string()),
                ir: None,
                params: args.params.clone(),
            }
            .resolve(ctx)?;
            Ok(audit_model(&model, &settings)?)
        })
        .collect::<Result<Vec<_>>>()?;
    if args.json {
        print_result(&reports, true, String::new)?;
    } else {
        print(&reports.iter().map(|r| r.table()).collect::<String>())?;
    }
    let failed: Vec<&str> = reports
        .iter()
        .filter(|r| !r.passed)
        .map(|r| r.model.as_str())
        .collect();
    Ok(if failed.is_empty() {
        Outcome::Done
    } else {
        Outcome::Negative(format!("audit failed for {}", failed.join(", ")))
    })
}
