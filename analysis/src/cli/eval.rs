//! `twv eval`: ẋ (and the Jacobians) of a model at one state, as JSON on stdout.

use anyhow::Result;
use clap::Args;
use serde::Serialize;
use twv_model::Model;

use super::model::{dispatch, parse_vector, to_array, LoadedModel, ModelArgs, ModelTask};

/// Evaluate ẋ = f(x, u) (and ∂f/∂x, ∂f/∂u) at one point.
#[derive(Args, Debug)]
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

#[derive(Serialize)]
struct EvalOutput {
    model: String,
    f: Vec<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    jac_x: Option<Vec<Vec<f64>>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    jac_u: Option<Vec<Vec<f64>>>,
}

struct Eval<'a>(&'a EvalArgs);

impl ModelTask for Eval<'_> {
    type Output = EvalOutput;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<EvalOutput> {
        let info = model.info();
        let x: [f64; NX] = to_array(&parse_vector("x", &self.0.x, info.states)?);
        let u: [f64; NU] = match &self.0.u {
            Some(text) => to_array(&parse_vector("u", text, info.inputs)?),
            None => [0.0; NU],
        };
        let mut f = [0.0; NX];
        model.f(&x, &u, &mut f);
        let (jac_x, jac_u) = if self.0.jac {
            let mut jx = [[0.0; NX]; NX];
            let mut ju = [[0.0; NU]; NX];
            model.jac_x(&x, &u, &mut jx);
            model.jac_u(&x, &u, &mut ju);
            // An interpreted model may carry padding inputs after its own (see twv_ir).
            let nu = info.inputs.len();
            (
                Some(jx.iter().map(|r| r.to_vec()).collect()),
                Some(ju.iter().map(|r| r[..nu].to_vec()).collect()),
            )
        } else {
            (None, None)
        };
        Ok(EvalOutput {
            model: loaded.name().to_string(),
            f: f.to_vec(),
            jac_x,
            jac_u,
        })
    }
}

pub fn run(args: &EvalArgs) -> Result<()> {
    let loaded = args.model.clone().with_default("vehicle8").load()?;
    let out = dispatch(&loaded, Eval(args))?;
    println!("{}", serde_json::to_string(&out)?);
    Ok(())
}
