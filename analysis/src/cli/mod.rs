//! The `twv` command line: raw arguments (clap) are kept apart from the validated settings the
//! library runs on; every command returns a `Result`, and the binary prints an error once.

pub mod audit;
pub mod codegen;
pub mod control_args;
pub mod disturb;
pub mod eval;
pub mod linear;
pub mod lyap;
pub mod model;
pub mod phase;
pub mod report;
pub mod sim;
pub mod sweep;
pub mod tune;

use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::{Parser, Subcommand};

/// twv: two-wheeled self-balancing vehicle dynamics — generated equations of motion, audit,
/// Lyapunov spectra, control and reports.
#[derive(Parser, Debug)]
#[command(name = "twv", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Evaluate ẋ = f(x, u) (and its Jacobians) at one state; JSON on stdout
    Eval(eval::EvalArgs),
    /// Print the Rust code generated from a model's IR, for people to read and audit
    Codegen(codegen::CodegenArgs),
    /// Audit the generated vehicle models against the independent hand model
    Audit(audit::AuditArgs),
    /// Lyapunov spectrum (Benettin–QR) with running estimates, errors and Σλ = ⟨tr J⟩
    Lyap(lyap::LyapArgs),
    /// Closed-loop run of the PID pitch controller (tilt recovery or a maneuver): CSV, figures,
    /// metrics
    Sim(sim::SimArgs),
    /// Recovery from a forward or backward tilt under the study's PD (its Figs. 5 and 6)
    Disturb(disturb::DisturbArgs),
    /// Phase portraits (Φ, Φ̇) for several gain sets side by side (the study's Fig. 4), or open
    /// loop under constant forces
    Phase(phase::PhaseArgs),
    /// Linearisation at an equilibrium: modes, pitch-loop margins (gain, phase, disk), LQR
    Linear(linear::LinearArgs),
    /// Fit PD/PID gains to a margin specification with Clarabel, with an independent certificate
    Tune(tune::TuneArgs),
    /// Reproduce the study end to end into one HTML report (figures and data beside it)
    Report(report::ReportArgs),
    /// Stability map over PID gains (one shard of it; resumable; Slurm/Kubernetes arrays)
    Sweep(sweep::SweepArgs),
    /// Merge the shards of a sweep: check completeness, write map.csv, map.json, map.svg
    Merge(sweep::MergeArgs),
}

/// Run one command.
pub fn run(cli: Cli) -> Result<()> {
    match &cli.command {
        Command::Eval(args) => eval::run(args),
        Command::Codegen(args) => codegen::run(args),
        Command::Audit(args) => audit::run(args),
        Command::Lyap(args) => lyap::run(args),
        Command::Sim(args) => sim::run(args),
        Command::Disturb(args) => disturb::run(args),
        Command::Phase(args) => phase::run(args),
        Command::Linear(args) => linear::run(args),
        Command::Tune(args) => tune::run(args),
        Command::Report(args) => report::run(args),
        Command::Sweep(args) => sweep::run(args),
        Command::Merge(args) => sweep::run_merge(args),
    }
}

/// Writes a command's result files into a folder and returns their paths.
pub(crate) type WriteFiles<T> = fn(&Path, &T) -> Result<Vec<PathBuf>>;

/// The common ending of a command: write its files (if asked) and name them on stderr, then
/// print the result as JSON or as its readable summary on stdout.
pub(crate) fn finish<T: serde::Serialize>(
    out: &T,
    files: Option<(&Path, WriteFiles<T>)>,
    json: bool,
    summary: fn(&T) -> String,
) -> Result<()> {
    if let Some((dir, write)) = files {
        for path in write(dir, out)? {
            eprintln!("wrote {}", path.display());
        }
    }
    if json {
        println!("{}", serde_json::to_string_pretty(out)?);
    } else {
        print!("{}", summary(out));
    }
    Ok(())
}
