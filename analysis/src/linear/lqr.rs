//! Linear-quadratic regulator u = −K x minimising ∫ xᵀQx + uᵀRu dt, for comparison with the
//! study's PID: K = R⁻¹ Bᵀ P with P the stabilising Riccati solution ([`super::care`]).

use nalgebra::{Complex, DMatrix};

use super::care::{solve_care, CareStatus};
use super::error::LinearError;
use super::modes::{eigenvalues, spectral_abscissa};

/// An LQR design and its check.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Lqr {
    /// How the Riccati solver ended; the rest is meaningful only for `Solved`.
    pub status: CareStatus,
    /// Gain K (m × n), u = −K x; in JSON one list per row.
    #[serde(serialize_with = "crate::linear::rows")]
    pub k: DMatrix<f64>,
    /// Riccati solution P; in JSON one list per row.
    #[serde(serialize_with = "crate::linear::rows")]
    pub p: DMatrix<f64>,
    /// Relative Riccati residual.
    pub residual: f64,
    /// Eigenvalues of A − B K.
    pub closed_loop_eigenvalues: Vec<Complex<f64>>,
    /// Largest real part of those.
    pub spectral_abscissa: f64,
}

/// LQR gain for ẋ = A x + B u with weights Q ⪰ 0, R ≻ 0.
pub fn lqr(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<Lqr, LinearError> {
    let sol = solve_care(a, b, q, r)?;
    let r_inv = r.clone().try_inverse().ok_or(LinearError::Weight {
        what: "R",
        kind: "definite",
    })?;
    let k = r_inv * b.transpose() * &sol.p;
    let closed_loop_eigenvalues = eigenvalues(&(a - b * &k))?;
    Ok(Lqr {
        status: sol.status,
        spectral_abscissa: spectral_abscissa(&closed_loop_eigenvalues),
        closed_loop_eigenvalues,
        k,
        p: sol.p,
        residual: sol.residual,
    })
}
