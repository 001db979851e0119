//! The command line's shape: a subcommand per job of the library's registry (its flags made
//! from the job's options), plus the tools that are not jobs: `report`, `merge`, `serve`.

use clap::{Args, Command, FromArgMatches, Parser};

use crate::commands::{merge::MergeArgs, report::ReportArgs, serve::ServeArgs};

/// twv: two-wheeled vehicle dynamics — generated equations of motion, audit, Lyapunov
/// spectra, control and reports.
///
/// Exit status: 0 done; 1 error (one line naming the file, field or value); 2 command-line
/// syntax error; 3 completed with a negative verdict (audit or report check failed,
/// specification not met, pitch loop unstable); 130 interrupted.
#[derive(Parser, Debug)]
#[command(name = "twv", about, long_about)]
pub struct Cli {
    /// No progress bars and no informational lines on stderr (errors are still printed)
    #[arg(long, global = true)]
    pub quiet: bool,
    /// Use at most this instruction set for the generated kernels (what a CPU without the
    /// better ones runs; for benchmarks): the results are the same bits [default: the best this
    /// CPU has]
    #[arg(long, global = true, value_enum, value_name = "ISA")]
    pub isa: Option<IsaArg>,
}

/// An instruction-set limit for `--isa`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum IsaArg {
    /// The target's baseline (x86-64: SSE2)
    Baseline,
    /// NEON (aarch64; the lanes kernel's 2-wide build)
    Neon,
    /// AVX2 (the lanes kernel's 4-wide build)
    Avx2,
    /// AVX-512F/VL
    Avx512,
}

impl IsaArg {
    /// The kernels' instruction set.
    pub fn isa(self) -> twv_kernels::isa::Isa {
        use twv_kernels::isa::Isa;
        match self {
            IsaArg::Baseline => Isa::Baseline,
            IsaArg::Neon => Isa::Neon,
            IsaArg::Avx2 => Isa::Avx2,
            IsaArg::Avx512 => Isa::Avx512,
        }
    }
}

/// The whole command line: the jobs in the registry's order, then the tools.
pub fn command(version: &'static str) -> Command {
    let mut cmd = Cli::command().version(version).subcommand_required(true);
    for job in twv_analysis::jobs::registry() {
        cmd = cmd.subcommand(crate::commands::job_command(*job));
    }
    cmd.subcommand(ReportArgs::augment_args(Command::new("report").about(
        "Reproduce the study end to end into one HTML report (figures and data beside it)",
    )))
    .subcommand(MergeArgs::augment_args(Command::new("merge").about(
        "Merge the shards of a sweep: check completeness, write map.csv, map.json, map.svg",
    )))
    .subcommand(ServeArgs::augment_args(Command::new("serve").about(
        "A live page on 127.0.0.1: gains and parameters as sliders, the response, margins and \
         maps redrawn as they move, and its JSON API under /api/",
    )))
}

/// The global flags of parsed matches.
pub fn globals(m: &clap::ArgMatches) -> Cli {
    Cli::from_arg_matches(m).unwrap_or(Cli {
        quiet: false,
        isa: None,
    })
}

use clap::CommandFactory;
