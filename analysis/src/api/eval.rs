//! ẋ = f(x, u) and its Jacobians at one state: `twv eval`.

use serde::Serialize;
use twv_model::Model;

use crate::error::{Error, Result};
use crate::model::{dispatch, input_vector, state_vector, ModelTask, ResolvedModel};

/// What to evaluate. Defaults: u = 0, no Jacobians.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct EvalSettings {
    /// The state, in the model's state order (SI units, rad).
    pub x: Vec<f64>,
    /// The input, in the model's input order; `None`: zeros.
    pub u: Option<Vec<f64>>,
    /// Also ∂f/∂x and ∂f/∂u.
    pub jacobians: bool,
}

/// ẋ (and the Jacobians, row-major: one row per state) at the state.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct EvalResult {
    /// Model name.
    pub model: String,
    /// ẋ.
    pub f: Vec<f64>,
    /// ∂f/∂x, `jac_x[i][j] = ∂f_i/∂x_j`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub jac_x: Option<Vec<Vec<f64>>>,
    /// ∂f/∂u, `jac_u[i][j] = ∂f_i/∂u_j`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub jac_u: Option<Vec<Vec<f64>>>,
}

struct Eval<'a>(&'a EvalSettings);

impl ModelTask for Eval<'_> {
    type Output = EvalResult;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<EvalResult> {
        let info = model.info();
        let x: [f64; NX] = state_vector("x", &self.0.x, info.states)?;
        let u: [f64; NU] = match &self.0.u {
            Some(u) => input_vector("u", u, info.inputs)?,
            None => [0.0; NU],
        };
        let at = || {
            format!(
                "x = {:?}{}",
                x,
                if NU > 0 {
                    format!(", u = {u:?}")
                } else {
                    String::new()
                }
            )
        };
        let finite = |what: &str, values: &[f64]| {
            if values.iter().all(|v| v.is_finite()) {
                Ok(())
            } else {
                Err(Error::NonFinite {
                    what: what.to_string(),
                    at: at(),
                })
            }
        };
        let mut f = [0.0; NX];
        model.f(&x, &u, &mut f);
        finite("f", &f)?;
        let (jac_x, jac_u) = if self.0.jacobians {
            let mut jx = [[0.0; NX]; NX];
            let mut ju = [[0.0; NU]; NX];
            model.jac_x(&x, &u, &mut jx);
            model.jac_u(&x, &u, &mut ju);
            finite("jac_x", jx.as_flattened())?;
            finite("jac_u", ju.as_flattened())?;
            // An interpreted model may carry padding inputs after its own (see twv_ir).
            let nu = info.inputs.len();
            (
                Some(jx.iter().map(|r| r.to_vec()).collect()),
                Some(ju.iter().map(|r| r[..nu].to_vec()).collect()),
            )
        } else {
            (None, None)
        };
        Ok(EvalResult {
            model: resolved.name().to_string(),
            f: f.to_vec(),
            jac_x,
            jac_u,
        })
    }
}

/// Evaluates the model at one state; a non-finite output is an error naming it and the state.
pub fn evaluate(model: &ResolvedModel, settings: &EvalSettings) -> Result<EvalResult> {
    dispatch(model, Eval(settings))
}
