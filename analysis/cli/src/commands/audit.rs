//! `twv audit`: the generated vehicle models against the independent hand model, or any model
//! against the user's own hand file (`--hand`).

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use twv_analysis::api::{audit_hand, audit_model, HandSource, AUDITED};
use twv_analysis::audit::AuditSettings;
use twv_analysis::hand_file::{model_named_in, HandAuditSettings};

use crate::common::{print, print_result, Context, ModelArgs, Outcome};

/// Audit the derived (generated) model term by term against the hand model, plus physical checks;
/// with --hand, any model against your own hand file.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct AuditArgs {
    /// vehicle8, vehicle7, segway7 or all; with --hand any shipped model [default: all, or with
    /// --hand the file's `model`]
    #[arg(long, value_name = "NAME", conflicts_with = "ir")]
    pub model: Option<String>,
    /// A model IR file (twv-ir/1) to audit against --hand
    #[arg(long, value_name = "FILE", requires = "hand")]
    pub ir: Option<PathBuf>,
    /// Your own hand model (TOML: M, Cp or C, F, Q and qdot, or f; README "Your own hand model")
    #[arg(long, value_name = "FILE")]
    pub hand: Option<PathBuf>,
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
    /// With --hand: every second random sample varies each parameter by a factor in
    /// [1/SPREAD, SPREAD] (1: the given values only)
    #[arg(long, value_name = "SPREAD", default_value_t = 2.0, requires = "hand")]
    pub param_spread: f64,
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
    if let Some(hand) = &args.hand {
        return run_hand(args, hand, ctx);
    }
    let names: Vec<&str> = match args.model.as_deref().unwrap_or("all") {
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
                runtime: None,
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

/// `twv audit --hand FILE`: the model (from --model, --ir or the file's `model`) against the file.
fn run_hand(args: &AuditArgs, hand: &std::path::Path, ctx: &Context) -> Result<Outcome> {
    let settings = HandAuditSettings {
        samples: args.samples,
        seed: args.seed,
        tolerance: args.tolerance,
        param_spread: args.param_spread,
        ..HandAuditSettings::default()
    };
    // Read once: the file names its model and is then audited from the same text.
    let (text, origin) = HandSource::File(hand.to_path_buf()).read()?;
    let model = match (&args.model, &args.ir) {
        (Some(name), _) => Some(name.clone()),
        (None, Some(_)) => None,
        (None, None) => match model_named_in(&text, &origin)? {
            Some(name) => Some(name),
            None => bail!(
                "{}: says no `model = \"…\"`; name the model with --model or --ir",
                hand.display()
            ),
        },
    };
    let model = ModelArgs {
        model,
        ir: args.ir.clone(),
        params: args.params.clone(),
        runtime: None,
    }
    .resolve(ctx)?;
    let report = audit_hand(&model, &HandSource::Text { text, origin }, &settings)?;
    print_result(&report, args.json, || report.table())?;
    Ok(if report.passed {
        Outcome::Done
    } else {
        Outcome::Negative(format!(
            "the hand file {} disagrees with the derivation of {} in {} entries",
            report.hand_file,
            report.model,
            report.disagreements.len()
        ))
    })
}
