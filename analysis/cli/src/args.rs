//! The command line's shape: one subcommand per job, raw arguments only (each command's file
//! turns them into the library's settings).

use clap::{Parser, Subcommand};

use crate::commands::{
    audit::AuditArgs, codegen::CodegenArgs, disturb::DisturbArgs, eval::EvalArgs,
    linear::LinearArgs, lyap::LyapArgs, merge::MergeArgs, phase::PhaseArgs, report::ReportArgs,
    ride::RideArgs, serve::ServeArgs, sim::SimArgs, sweep::SweepArgs, tune::TuneArgs,
};

/// twv: two-wheeled self-balancing vehicle dynamics — generated equations of motion, audit,
/// Lyapunov spectra, control and reports.
///
/// Exit status: 0 done; 1 error (one line naming the file, field or value); 2 command-line
/// syntax error; 3 completed with a negative verdict (audit or report check failed,
/// specification not met, pitch loop unstable); 130 interrupted.
#[derive(Parser, Debug)]
#[command(name = "twv", version, about, long_about)]
pub struct Cli {
    /// No progress bars and no informational lines on stderr (errors are still printed)
    #[arg(long, global = true)]
    pub quiet: bool,
    /// Use at most this instruction set for the generated kernels (what a CPU without the
    /// better ones runs; for benchmarks): the results are the same bits [default: the best this
    /// CPU has]
    #[arg(long, global = true, value_enum, value_name = "ISA")]
    pub isa: Option<IsaArg>,
    #[command(subcommand)]
    pub command: Command,
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

/// The jobs.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Evaluate ẋ = f(x, u) (and its Jacobians) at one state; JSON on stdout
    Eval(EvalArgs),
    /// Print the Rust code generated from a model's IR, for people to read and audit
    Codegen(CodegenArgs),
    /// Audit the generated vehicle models against the independent hand model, or any model against your own (--hand)
    Audit(AuditArgs),
    /// Lyapunov spectrum (Benettin–QR) with running estimates, errors and Σλ = ⟨tr J⟩
    Lyap(LyapArgs),
    /// Closed-loop run of the PID pitch controller (tilt recovery or a maneuver): CSV, figures,
    /// metrics
    Sim(SimArgs),
    /// Uncontrolled run under constant inputs, from a state or a steady motion at a speed (the
    /// bicycle nobody steers): CSV, figures, whether the push died out
    Ride(RideArgs),
    /// Recovery from a forward or backward tilt under the study's PD (its Figs. 5 and 6)
    Disturb(DisturbArgs),
    /// Phase portraits (Φ, dΦ/dt) for several gain sets side by side (the study's Fig. 4), or
    /// open loop under constant forces
    Phase(PhaseArgs),
    /// Linearisation at an equilibrium: modes, pitch-loop margins (gain, phase, disk), LQR
    Linear(LinearArgs),
    /// Fit PD/PID gains to a margin specification with Clarabel, with an independent certificate
    Tune(TuneArgs),
    /// Reproduce the study end to end into one HTML report (figures and data beside it)
    Report(ReportArgs),
    /// Stability map over PID gains (one shard of it; resumable; Slurm/Kubernetes arrays)
    Sweep(SweepArgs),
    /// Merge the shards of a sweep: check completeness, write map.csv, map.json, map.svg
    Merge(MergeArgs),
    /// A live page on 127.0.0.1: gains and parameters as sliders, the response, margins and
    /// maps redrawn as they move, and its JSON API under /api/
    Serve(ServeArgs),
}
