//! `twv serve`: the live page and its JSON API for one model, until Ctrl-C.

use std::io::Write;
use std::net::IpAddr;

use anyhow::Result;
use clap::Args;
use twv_serve::{ServeSettings, Server};

use crate::common::{Context, ModelArgs, Outcome, CANCEL};

/// Serve the page and the API until interrupted.
#[derive(Args, Debug, Clone)]
pub struct ServeArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Port to listen on (0: any free port; the address is printed) [default: 8040]
    #[arg(long, value_name = "N")]
    pub port: Option<u16>,
    /// Address to listen on; anything but 127.0.0.1 lets other machines reach the page
    /// [default: 127.0.0.1]
    #[arg(long, value_name = "ADDR")]
    pub bind: Option<IpAddr>,
}

pub fn run(args: &ServeArgs, ctx: &Context) -> Result<Outcome> {
    let model = args.model.resolve(ctx)?;
    let defaults = ServeSettings::default();
    let settings = ServeSettings {
        bind: args.bind.unwrap_or(defaults.bind),
        port: args.port.unwrap_or(defaults.port),
        ..defaults
    };
    let server = Server::bind(model, &settings)?;
    // The address first and flushed: scripts and tests that start the server read it.
    println!("twv serve: {} (Ctrl-C stops)", server.url());
    std::io::stdout().flush()?;
    server.run(&CANCEL);
    Ok(Outcome::Done)
}
