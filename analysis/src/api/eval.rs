//! ẋ = f(x, u) and its Jacobians at one state: `twv eval`.

use serde::Serialize;
use twv_model::Model;

use crate::error::{Error, Result};
use crate::model::{check_vector, dispatch, ModelTask, ResolvedModel};

/// What to evaluate. Defaults: u = 0, no Jacobians.
#[derive(Debug, Clone, Default, PartialEq, Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
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

/// Evaluates the model at one state (a batch of one, [`evaluate_batch`]); a non-finite output
/// is an error naming it and the state.
pub fn evaluate(model: &ResolvedModel, settings: &EvalSettings) -> Result<EvalResult> {
    let (states, inputs) = (model.states(), model.inputs());
    let (nx, nu) = (states.len(), inputs.len());
    check_vector("x", &settings.x, &states)?;
    let zeros = vec![0.0; nu];
    let u = settings.u.as_deref().unwrap_or(&zeros);
    check_vector("u", u, &inputs)?;
    let batch = Batch {
        x: &settings.x,
        u,
        v: &[],
    };
    let eval = |what: Quantity| -> Result<Vec<f64>> {
        let mut out = vec![0.0; what.width(nx, nu)];
        evaluate_batch(model, what, batch, &mut out)?;
        Ok(out)
    };
    let finite = |what: &str, values: &[f64]| {
        if values.iter().all(|v| v.is_finite()) {
            return Ok(());
        }
        let inputs = if nu > 0 {
            format!(", u = {u:?}")
        } else {
            String::new()
        };
        Err(Error::NonFinite {
            what: what.to_string(),
            at: format!("x = {:?}{inputs}", settings.x),
        })
    };
    let f = eval(Quantity::F)?;
    finite("f", &f)?;
    let rows = |m: &[f64], width: usize| -> Vec<Vec<f64>> {
        (0..nx).map(|i| m[i * width..][..width].to_vec()).collect()
    };
    let (jac_x, jac_u) = if settings.jacobians {
        let (jx, ju) = (eval(Quantity::JacX)?, eval(Quantity::JacU)?);
        finite("jac_x", &jx)?;
        finite("jac_u", &ju)?;
        (Some(rows(&jx, nx)), Some(rows(&ju, nu)))
    } else {
        (None, None)
    };
    Ok(EvalResult {
        model: model.name().to_string(),
        f,
        jac_x,
        jac_u,
    })
}

/// What [`evaluate_batch`] computes at each state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Quantity {
    /// ẋ = f(x, u): `nx` numbers per state.
    F,
    /// ∂f/∂x, row-major: `nx·nx` per state.
    JacX,
    /// ∂f/∂u, row-major: `nx·nu` per state.
    JacU,
    /// (∂f/∂x)·v for one tangent vector v per state: `nx` per state.
    Jw,
}

impl Quantity {
    /// Numbers per state.
    pub fn width(self, nx: usize, nu: usize) -> usize {
        match self {
            Quantity::F | Quantity::Jw => nx,
            Quantity::JacX => nx * nx,
            Quantity::JacU => nx * nu,
        }
    }
}

/// The rows of a batch: states `x` (row-major, `nx` per state), inputs `u` (`nu` per state, or
/// empty for zeros) and, for [`Quantity::Jw`], one tangent vector per state in `v`.
#[derive(Debug, Clone, Copy)]
pub struct Batch<'a> {
    /// States, `n·nx` numbers.
    pub x: &'a [f64],
    /// Inputs, `n·nu` numbers, or empty: u = 0.
    pub u: &'a [f64],
    /// Tangent vectors, `n·nx` numbers (only for `Jw`).
    pub v: &'a [f64],
}

struct EvalBatch<'a> {
    what: Quantity,
    batch: Batch<'a>,
    out: &'a mut [f64],
}

impl ModelTask for EvalBatch<'_> {
    type Output = ();
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        _: &ResolvedModel,
    ) -> Result<()> {
        let nu = model.info().inputs.len();
        let Batch { x, u, v } = self.batch;
        let n = x.len() / NX;
        let width = self.what.width(NX, nu);
        let sized = |name: &str, got: usize, per: usize| {
            if got == n * per {
                Ok(())
            } else {
                Err(Error::input(
                    name,
                    format!("{got} numbers for {n} states: want {per} per state"),
                ))
            }
        };
        sized("x", x.len(), NX)?;
        if !u.is_empty() {
            sized("u", u.len(), nu)?;
        }
        if self.what == Quantity::Jw {
            sized("v", v.len(), NX)?;
        }
        sized("out", self.out.len(), width)?;
        for (row, out) in self.out.chunks_exact_mut(width.max(1)).enumerate() {
            let xs: &[f64; NX] = x[row * NX..][..NX].try_into().expect("NX numbers");
            // An interpreted model may carry padding inputs after its own (see twv_ir).
            let mut us = [0.0; NU];
            if !u.is_empty() {
                us[..nu].copy_from_slice(&u[row * nu..][..nu]);
            }
            match self.what {
                Quantity::F => model.f(xs, &us, out.try_into().expect("NX numbers")),
                Quantity::JacX => {
                    let mut j = [[0.0; NX]; NX];
                    model.jac_x(xs, &us, &mut j);
                    out.copy_from_slice(j.as_flattened());
                }
                Quantity::JacU => {
                    let mut j = [[0.0; NU]; NX];
                    model.jac_u(xs, &us, &mut j);
                    for (o, r) in out.chunks_exact_mut(nu.max(1)).zip(&j) {
                        o.copy_from_slice(&r[..nu]);
                    }
                }
                Quantity::Jw => {
                    let w: [[f64; NX]; 1] = [v[row * NX..][..NX].try_into().expect("NX numbers")];
                    let mut o = [[0.0; NX]; 1];
                    model.jw::<1>(xs, &us, &w, &mut o);
                    out.copy_from_slice(&o[0]);
                }
            }
        }
        Ok(())
    }
}

/// Evaluates `what` at every state of `batch` into `out` (`n ·` [`Quantity::width`] numbers),
/// one dispatch for the whole batch and no allocation per state. The caller checks the inputs
/// for NaN (it knows their names); outputs are written as computed.
pub fn evaluate_batch(
    model: &ResolvedModel,
    what: Quantity,
    batch: Batch<'_>,
    out: &mut [f64],
) -> Result<()> {
    dispatch(model, EvalBatch { what, batch, out })
}
