//! `twv report`: the whole study reproduced into one self-contained HTML page.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use crate::report::{build, ReportSettings};

/// Reproduce the study end to end: model and audit, Lyapunov spectra, phase portraits, tilt
/// recovery, linear analysis and tuning, and a comparison with the study's claims.
#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Parameter file (TOML, SI units) [default: the study's vehicle, vehicles/paper.toml,
    /// embedded in the binary]
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// Output folder (index.html, figures/, data/, results.json)
    #[arg(long, value_name = "DIR", default_value = "report")]
    pub out: PathBuf,
    /// Shorter horizons (for a quick look and the tests)
    #[arg(long)]
    pub quick: bool,
}

pub fn run(args: &ReportArgs) -> Result<()> {
    let settings = ReportSettings {
        params: args.params.clone(),
        quick: args.quick,
    };
    let (files, seconds) = build(&settings, &args.out)?;
    eprintln!(
        "wrote {} files in {} ({seconds:.1} s); open {}",
        files.len(),
        args.out.display(),
        args.out.join("index.html").display()
    );
    Ok(())
}
