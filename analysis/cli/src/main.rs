//! The `twv` command line: a thin shell over the twv-analysis library. Every job of the
//! library's registry is a subcommand whose flags are the job's options; the library lays them
//! over its default settings, checks them and runs the job; this binary writes the files,
//! prints the summary and turns the verdict into the exit status.
//!
//! Exit codes: 0 done; 1 an error (bad input, a failed run, an unwritable output), one line on
//! stderr naming the file, field or value; 2 a command-line syntax error; 3 the run completed
//! but its verdict is negative (an audit or a report check failed, a tuning specification is
//! not met, a pitch loop is unstable); 130 interrupted (a sweep leaves a checkpoint).

mod args;
mod commands;
mod common;
mod job;
mod progress;

use std::process::ExitCode;

use common::{Context, Outcome};

/// The study's vehicle and the Segway-like one, embedded so the binary runs from any folder;
/// they are the default parameters of the shipped vehicles. Editing them and running
/// `cargo build` rebuilds only this small crate.
const PAPER_TOML: &str = include_str!("../../../vehicles/paper.toml");
const SEGWAY_TOML: &str = include_str!("../../../vehicles/segway.toml");

/// Which build this is (`twv --version`, the same as Python's `twv.build_info()`).
fn version() -> &'static str {
    let info = twv_analysis::machine::BuildInfo::new(
        git_version::git_version!(args = ["--always", "--abbrev=12"], fallback = "unknown"),
        common::HAS_JIT,
    );
    Box::leak(info.line().into_boxed_str())
}

fn main() -> ExitCode {
    restore_default_sigpipe();
    let matches = args::command(version()).get_matches();
    let cli = args::globals(&matches);
    if let Some(limit) = cli.isa {
        let (wanted, used) = (limit.isa(), twv_kernels::isa::force(limit.isa()));
        if used != wanted && !cli.quiet {
            eprintln!(
                "twv: --isa: this CPU has no {} build; the kernels use {}",
                wanted.name(),
                used.name()
            );
        }
    }
    let ctx = Context::new(PAPER_TOML, SEGWAY_TOML, cli.quiet);
    common::install_interrupt_handler();
    let Some((name, sub)) = matches.subcommand() else {
        return ExitCode::from(2);
    };
    match commands::run(name, sub, &ctx) {
        Ok(Outcome::Done) => ExitCode::SUCCESS,
        Ok(Outcome::Negative(message)) => {
            eprintln!("twv: {message}");
            ExitCode::from(3)
        }
        Ok(Outcome::Interrupted(message)) => {
            eprintln!("twv: interrupted: {message}");
            ExitCode::from(130)
        }
        Err(err) => {
            eprintln!("twv: error: {}", common::describe(&err, name));
            ExitCode::from(1)
        }
    }
}

/// `twv ... | head` must end quietly when the reader goes away, like any Unix tool: Rust
/// ignores SIGPIPE, which turns the closed pipe into a write error.
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first in main, before any thread exists; SIG_DFL is a valid disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
