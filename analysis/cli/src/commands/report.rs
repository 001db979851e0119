//! `twv report`: the whole study reproduced into one self-contained HTML page.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use twv_analysis::model::ParamSource;
use twv_analysis::report::{build, ReportSettings};

use crate::common::{Context, Outcome};

/// Reproduce the study end to end: model and audit, Lyapunov spectra, phase portraits, tilt
/// recovery, linear analysis and tuning, a stability map, and the study's claims checked.
/// Exit status 3 when a check fails (the report is written first, so the reader sees why).
#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Parameter file (TOML, SI units) of the vehicles [default: the study's vehicle,
    /// vehicles/paper.toml (segway7 in the audit: vehicles/segway.toml), embedded]
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// Output folder (index.html, figures/, data/, results.json) [default: report]
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Shorter horizons and a coarser map (for a quick look and the tests)
    #[arg(long)]
    pub quick: bool,
    /// Largest accepted normwise relative error of a term in the audit [default: the audit's,
    /// 1e-11]
    #[arg(long, value_name = "REL")]
    pub audit_tolerance: Option<f64>,
}

/// The measured bicycle of the report's Monte Carlo, embedded (as vehicles/paper.toml is).
fn measured_bicycle() -> ParamSource {
    ParamSource::Text {
        text: include_str!("../../../../vehicles/bicycles/browser.toml").to_string(),
        origin: "vehicles/bicycles/browser.toml (embedded)".to_string(),
    }
}

pub fn run(args: &ReportArgs, ctx: &Context) -> Result<Outcome> {
    let defaults = ReportSettings::default();
    let audit_tolerance = args.audit_tolerance.unwrap_or(defaults.audit_tolerance);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from(ReportSettings::DEFAULT_OUT));
    let settings = match &args.params {
        Some(p) => ReportSettings {
            params: ParamSource::File(p.clone()),
            segway_params: None,
            params_text: None,
            quick: args.quick,
            audit_tolerance,
            measured_bicycle: Some(measured_bicycle()),
        },
        None => ReportSettings {
            params: ctx.vehicle_defaults("vehicle8").unwrap_or_default(),
            segway_params: ctx.vehicle_defaults("segway7"),
            params_text: Some(ctx.paper_toml().to_string()),
            quick: args.quick,
            audit_tolerance,
            measured_bicycle: Some(measured_bicycle()),
        },
    };
    let bar = ctx.bar();
    let report = match super::interrupted_or(build(&settings, &bar), "the report")? {
        Ok(report) => report,
        Err(outcome) => return Ok(outcome),
    };
    let files = report.files.entries.len();
    for note in report.files.write(&out)?.left {
        ctx.say(format!("note: {note}"));
    }
    let index = out.join("index.html");
    ctx.say(format!(
        "wrote {files} files in {} ({:.1} s); open {}",
        out.display(),
        report.results.wall_time_s,
        index.display()
    ));
    let failed = report.failed_checks();
    if failed.is_empty() {
        return Ok(Outcome::Done);
    }
    let names: Vec<String> = failed
        .iter()
        .map(|c| format!("{} ({})", c.name, c.detail))
        .collect();
    Ok(Outcome::Negative(format!(
        "report written to {}, but {} check(s) failed: {}",
        index.display(),
        failed.len(),
        names.join("; ")
    )))
}
