//! The `twv` command line: a thin shell that turns the result of `run` into an exit code and
//! prints an error once, without a backtrace.

use clap::Parser;
use twv_analysis::cli::{run, Cli};

fn main() {
    restore_default_sigpipe();
    let cli = Cli::parse();
    if let Err(err) = run(cli) {
        eprintln!("twv: error: {err:#}");
        std::process::exit(1);
    }
}

/// `twv ... | head` must end quietly when the reader goes away, like any Unix tool: Rust
/// ignores SIGPIPE, which turns the closed pipe into a panic inside `println!`.
fn restore_default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: called first in main, before any thread exists; SIG_DFL is a valid disposition.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
