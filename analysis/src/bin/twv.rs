//! The `twv` command line: a thin shell that turns the result of `run` into an exit code and
//! prints an error once, without a backtrace.

use clap::Parser;
use twv_analysis::cli::{run, Cli};

fn main() {
    let cli = Cli::parse();
    if let Err(err) = run(cli) {
        eprintln!("twv: error: {err:#}");
        std::process::exit(1);
    }
}
