//! `twv eval`: ẋ (and the Jacobians) of a model at one state, as JSON on stdout.

use anyhow::Result;
use clap::Args;
use twv_analysis::api::{evaluate, EvalSettings};

use crate::common::{parse_vector, print, Context, ModelArgs, Outcome};

/// Evaluate ẋ = f(x, u) (and ∂f/∂x, ∂f/∂u) at one point.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct EvalArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    /// State, comma-separated, in the model's state order (SI units, angles in rad)
    #[arg(long, value_name = "V1,V2,...", allow_hyphen_values = true)]
    pub x: String,
    /// Input, comma-separated (N, N m) [default: zeros]
    #[arg(long, value_name = "U1,...", allow_hyphen_values = true)]
    pub u: Option<String>,
    /// Also print jac_x = ∂f/∂x and jac_u = ∂f/∂u (row-major: one row per state)
    #[arg(long)]
    pub jac: bool,
}

pub fn run(args: &EvalArgs, ctx: &Context) -> Result<Outcome> {
    let model = args.model.resolve(ctx)?;
    let settings = EvalSettings {
        x: parse_vector("x", &args.x)?,
        u: args
            .u
            .as_deref()
            .map(|u| parse_vector("u", u))
            .transpose()?,
        jacobians: args.jac,
    };
    let out = evaluate(&model, &settings)?;
    print(&(serde_json::to_string(&out)? + "\n"))?;
    Ok(Outcome::Done)
}
