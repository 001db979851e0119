//! A, B of a model at an operating point, from the model's own Jacobians (the generated
//! `jac_x`, `jac_u`), so linear analysis uses exactly the derivatives the simulations use.

use nalgebra::{DMatrix, SMatrix};
use twv_model::Model;

use super::error::{check_finite, LinearError};

/// Name of the pitch angle state in every twv vehicle model (docs/src/conventions.md).
pub const PHI: &str = "phi";
/// Name of the pitch rate state (w_y = Φ̇).
pub const PITCH_RATE: &str = "w_y";

/// Where to linearise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OperatingPoint<const NX: usize> {
    /// x = 0: the pendulum upright, everything at rest.
    Upright,
    /// Φ = π, the rest zero: the pendulum hanging.
    Hanging,
    /// A given state (need not be an equilibrium: see [`Linearization::residual`]).
    State([f64; NX]),
}

/// ẋ ≈ f(x0, u0) + A (x − x0) + B (u − u0).
#[derive(Debug, Clone, PartialEq)]
pub struct Linearization<const NX: usize, const NU: usize> {
    /// ∂f/∂x at the operating point.
    pub a: SMatrix<f64, NX, NX>,
    /// ∂f/∂u at the operating point.
    pub b: SMatrix<f64, NX, NU>,
    /// The state linearised about.
    pub x0: [f64; NX],
    /// The input linearised about.
    pub u0: [f64; NU],
    /// max |f(x0, u0)|: zero at an equilibrium; otherwise A, B describe a trajectory, not a
    /// rest point, and eigenvalues are only a local (frozen-time) indication.
    pub residual: f64,
    /// f(x0, u0) itself (its largest entry is `residual`).
    pub f: [f64; NX],
    /// State names, from the model's `info()`.
    pub states: Vec<String>,
    /// Input names, from the model's `info()`.
    pub inputs: Vec<String>,
}

/// Index of a state by name.
pub fn state_index(states: &[String], name: &str) -> Result<usize, LinearError> {
    states
        .iter()
        .position(|s| s == name)
        .ok_or_else(|| LinearError::UnknownState(name.to_string()))
}

/// Linearises `model` at `at` with input `u0`.
pub fn linearize<M, const NX: usize, const NU: usize>(
    model: &M,
    at: &OperatingPoint<NX>,
    u0: &[f64; NU],
) -> Result<Linearization<NX, NU>, LinearError>
where
    M: Model<NX, NU>,
{
    let info = model.info();
    let states: Vec<String> = info.states.iter().map(|s| s.to_string()).collect();
    let inputs: Vec<String> = info.inputs.iter().map(|s| s.to_string()).collect();
    let x0 = match at {
        OperatingPoint::Upright => [0.0; NX],
        OperatingPoint::Hanging => {
            let mut x = [0.0; NX];
            x[state_index(&states, PHI)?] = std::f64::consts::PI;
            x
        }
        OperatingPoint::State(x) => *x,
    };
    check_finite("operating state", x0.iter())?;
    check_finite("operating input", u0.iter())?;

    let mut jx = [[0.0; NX]; NX];
    let mut ju = [[0.0; NU]; NX];
    let mut f = [0.0; NX];
    model.jac_x(&x0, u0, &mut jx);
    model.jac_u(&x0, u0, &mut ju);
    model.f(&x0, u0, &mut f);
    let a = SMatrix::<f64, NX, NX>::from_fn(|i, j| jx[i][j]);
    let b = SMatrix::<f64, NX, NU>::from_fn(|i, j| ju[i][j]);
    check_finite("∂f/∂x", a.iter())?;
    check_finite("∂f/∂u", b.iter())?;
    let residual = f.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    Ok(Linearization {
        a,
        b,
        x0,
        u0: *u0,
        residual,
        f,
        states,
        inputs,
    })
}

impl<const NX: usize, const NU: usize> Linearization<NX, NU> {
    /// A and B as dynamic matrices (the closed-loop and Riccati code works on any size).
    pub fn dynamic(&self) -> (DMatrix<f64>, DMatrix<f64>) {
        (
            DMatrix::from_fn(NX, NX, |i, j| self.a[(i, j)]),
            DMatrix::from_fn(NX, NU, |i, j| self.b[(i, j)]),
        )
    }

    /// The rows and columns of A (and rows of B) of the named states, e.g. the cart–pendulum
    /// part `["phi", "x", "w_y", "v_x"]` of a vehicle, for an LQR design on the states that
    /// matter. Refuses (`Coupled`) when a dropped state drives a kept one, because then the
    /// reduced model would not describe the kept states.
    pub fn subsystem(&self, keep: &[&str]) -> Result<(DMatrix<f64>, DMatrix<f64>), LinearError> {
        let idx = keep
            .iter()
            .map(|n| state_index(&self.states, n))
            .collect::<Result<Vec<_>, _>>()?;
        let scale = self.a.amax().max(1.0);
        for &k in &idx {
            for d in (0..NX).filter(|d| !idx.contains(d)) {
                let v = self.a[(k, d)];
                if v.abs() > 1e-12 * scale {
                    return Err(LinearError::Coupled {
                        kept: self.states[k].clone(),
                        dropped: self.states[d].clone(),
                        value: v,
                    });
                }
            }
        }
        let n = idx.len();
        Ok((
            DMatrix::from_fn(n, n, |i, j| self.a[(idx[i], idx[j])]),
            DMatrix::from_fn(n, NU, |i, j| self.b[(idx[i], j)]),
        ))
    }
}
