//! `twv ride`: one uncontrolled run — the model under constant inputs from a state, or from its
//! steady motion at a speed with some states pushed (the bicycle nobody steers).

use std::collections::BTreeMap;
use std::path::PathBuf;

use anyhow::{anyhow, bail, Result};
use clap::Args;
use twv_analysis::api::{ride, RideSettings};

use super::interrupted_or;
use crate::common::{
    parse_vector, print_result, write_files, Context, ModelArgs, Outcome, RunArgs,
};

/// Run the model with no controller: constant inputs, from a state or a steady motion.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct RideArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// Initial state, comma-separated in the model's state order (SI units, rad) [default: the
    /// steady motion at --speed, or rest]
    #[arg(long, value_name = "V1,V2,...", allow_hyphen_values = true)]
    pub x0: Option<String>,
    /// Start from the model's steady motion at this speed [m/s] (a model whose IR describes
    /// one: the bicycle's upright straight running)
    #[arg(long, value_name = "M/S", conflicts_with = "x0")]
    pub speed: Option<f64>,
    /// Pushes added to the initial state, NAME=VALUE,… (e.g. w_phi=0.05)
    #[arg(long, value_name = "NAME=V,...", allow_hyphen_values = true)]
    pub perturb: Option<String>,
    /// Constant inputs, comma-separated in the model's input order [default: all zero]
    #[arg(long, value_name = "U1,U2,...", allow_hyphen_values = true)]
    pub u: Option<String>,
    /// The state whose decay is judged and whose size past --fall-angle ends the run
    /// [default: phi]
    #[arg(long, value_name = "NAME")]
    pub watch: Option<String>,
    #[command(flatten)]
    pub run: RunArgs,
    /// Write ride.csv, ride.json and a figure per moving state (SVG and PNG) into this folder
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the result as JSON on stdout
    #[arg(long)]
    pub json: bool,
}

/// `a=1,b=-2` → {a: 1, b: -2}.
fn parse_pushes(text: &str) -> Result<BTreeMap<String, f64>> {
    let mut out = BTreeMap::new();
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (name, value) = part
            .split_once('=')
            .ok_or_else(|| anyhow!("--perturb: `{part}` is not NAME=VALUE"))?;
        let value: f64 = value
            .trim()
            .parse()
            .map_err(|_| anyhow!("--perturb: `{}` is not a number", value.trim()))?;
        if out.insert(name.trim().to_string(), value).is_some() {
            bail!("--perturb: `{}` is given twice", name.trim());
        }
    }
    Ok(out)
}

pub fn run(args: &RideArgs, ctx: &Context) -> Result<Outcome> {
    let defaults = RideSettings::default();
    let settings = RideSettings {
        x0: args
            .x0
            .as_deref()
            .map(|x| parse_vector("x0", x))
            .transpose()?,
        speed: args.speed,
        perturb: args
            .perturb
            .as_deref()
            .map(parse_pushes)
            .transpose()?
            .unwrap_or_default(),
        u: args
            .u
            .as_deref()
            .map(|u| parse_vector("u", u))
            .transpose()?,
        watch: args.watch.clone().unwrap_or(defaults.watch),
        run: args.run.settings(10.0),
    };
    let model = args.model.resolve(ctx)?;
    let bar = ctx.bar();
    let result = match interrupted_or(ride(&model, &settings, &bar), "the ride")? {
        Ok(r) => r,
        Err(outcome) => return Ok(outcome),
    };
    if let Some(dir) = &args.out {
        write_files(ctx, dir, &result.files()?)?;
    }
    // A fall is what the experiment found, not a failed check: exit 0, as `twv sim`.
    print_result(&result, args.json, || result.summary())?;
    Ok(Outcome::Done)
}
