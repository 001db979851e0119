//! One file per command: its arguments, their translation into the library's settings, the
//! call, and what is written and printed.

pub mod audit;
pub mod codegen;
pub mod disturb;
pub mod eval;
pub mod linear;
pub mod lyap;
pub mod merge;
pub mod phase;
pub mod report;
pub mod ride;
pub mod serve;
pub mod sim;
pub mod sweep;
pub mod tune;

use anyhow::Result;

use crate::args::Command;
use crate::common::{Context, Outcome};

/// Runs one command.
pub fn run(command: &Command, ctx: &Context) -> Result<Outcome> {
    match command {
        Command::Eval(a) => eval::run(a, ctx),
        Command::Codegen(a) => codegen::run(a, ctx),
        Command::Audit(a) => audit::run(a, ctx),
        Command::Lyap(a) => lyap::run(a, ctx),
        Command::Sim(a) => sim::run(a, ctx),
        Command::Ride(a) => ride::run(a, ctx),
        Command::Disturb(a) => disturb::run(a, ctx),
        Command::Phase(a) => phase::run(a, ctx),
        Command::Linear(a) => linear::run(a, ctx),
        Command::Tune(a) => tune::run(a, ctx),
        Command::Report(a) => report::run(a, ctx),
        Command::Sweep(a) => sweep::run(a, ctx),
        Command::Merge(a) => merge::run(a, ctx),
        Command::Serve(a) => serve::run(a, ctx),
    }
}

/// A library error from an interrupted run as the command's outcome; other errors pass.
pub fn interrupted_or<T>(
    result: twv_analysis::Result<T>,
    what: &str,
) -> Result<Result<T, Outcome>> {
    use twv_analysis::{control::ControlError, lyapunov::LyapunovError, Error};
    match result {
        Ok(v) => Ok(Ok(v)),
        Err(Error::Interrupted)
        | Err(Error::Lyapunov(LyapunovError::Interrupted))
        | Err(Error::Control(ControlError::Interrupted)) => Ok(Err(Outcome::Interrupted(format!(
            "{what} stopped; nothing written"
        )))),
        Err(e) => Err(e.into()),
    }
}
