//! The continuous algebraic Riccati equation Aᵀ P + P A − P B R⁻¹ Bᵀ P + Q = 0, stabilising
//! solution.
//!
//! Method (chosen for robustness at 4–10 states without an ordered Schur decomposition, which
//! nalgebra does not offer):
//! 1. the matrix sign function of the Hamiltonian H = [[A, −B R⁻¹ Bᵀ], [−Q, −Aᵀ]] by the
//!    scaled Newton iteration Z ← (Z/c + c Z⁻¹)/2, c = |det Z|^{1/2n} (Byers 1987; it needs no
//!    stabilising start and converges quadratically); P is the least-squares solution of
//!    [W₁₂; W₂₂ + I] P = −[W₁₁ + I; W₂₁], W = sign H (Roberts 1971), because the stable
//!    invariant subspace of H is span [I; P] = ker(W + I);
//! 2. Newton–Kleinman steps from that P (each a Lyapunov solve with the closed loop
//!    A − B R⁻¹ Bᵀ P, which P makes stable) polish it to a relative residual near rounding.
//!
//! A Hamiltonian with eigenvalues on the imaginary axis (no stabilising solution: (A, B) not
//! stabilisable or (Q, A) not detectable, e.g. a drift mode with no weight and no input) shows
//! as a singular iterate or a non-stabilising result and is reported as a status.

use nalgebra::DMatrix;

use super::error::{check_finite, LinearError};
use super::lyap::solve_lyapunov;
use super::modes::{eigenvalues, spectral_abscissa};

/// How the Riccati solver ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum CareStatus {
    /// Stabilising solution found.
    Solved,
    /// The sign iteration did not converge in its budget (eigenvalues very near the axis).
    IterationLimit,
    /// The Hamiltonian has imaginary-axis eigenvalues or the result does not stabilise.
    NoStabilisingSolution,
}

/// The Riccati solution and how well it satisfies the equation.
#[derive(Debug, Clone, PartialEq)]
pub struct CareSolution {
    /// How the solver ended; `p` is meaningful only for `Solved`.
    pub status: CareStatus,
    /// The stabilising solution P = Pᵀ ⪰ 0.
    pub p: DMatrix<f64>,
    /// ‖Aᵀ P + P A − P G P + Q‖_F / (2‖Aᵀ P‖_F + ‖P G P‖_F + ‖Q‖_F), G = B R⁻¹ Bᵀ.
    pub residual: f64,
    /// Sign-function iterations used.
    pub iterations: usize,
}

/// Checks sizes, finiteness, symmetry and definiteness of the data.
fn validate(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<(), LinearError> {
    let n = a.nrows();
    let m = b.ncols();
    for (what, expected, got) in [
        ("A columns", n, a.ncols()),
        ("B rows", n, b.nrows()),
        ("Q rows", n, q.nrows()),
        ("Q columns", n, q.ncols()),
        ("R rows", m, r.nrows()),
        ("R columns", m, r.ncols()),
    ] {
        if expected != got {
            return Err(LinearError::Dimension {
                what,
                expected,
                got,
            });
        }
    }
    check_finite("A", a.iter())?;
    check_finite("B", b.iter())?;
    check_finite("Q", q.iter())?;
    check_finite("R", r.iter())?;
    let sym = |x: &DMatrix<f64>| (x - x.transpose()).amax() <= 1e-12 * x.amax().max(1e-300);
    if !sym(r) || r.clone().cholesky().is_none() {
        return Err(LinearError::Weight {
            what: "R",
            kind: "definite",
        });
    }
    let q_min = q.clone().symmetric_eigen().eigenvalues.min();
    if !sym(q) || q_min < -1e-12 * q.amax() {
        return Err(LinearError::Weight {
            what: "Q",
            kind: "semidefinite",
        });
    }
    Ok(())
}

/// Relative residual of the Riccati equation.
pub fn care_residual(
    a: &DMatrix<f64>,
    g: &DMatrix<f64>,
    q: &DMatrix<f64>,
    p: &DMatrix<f64>,
) -> f64 {
    let atp = a.transpose() * p;
    let pgp = p * g * p;
    let res = &atp + atp.transpose() - &pgp + q;
    let scale = 2.0 * atp.norm() + pgp.norm() + q.norm();
    if scale == 0.0 {
        0.0
    } else {
        res.norm() / scale
    }
}

/// Solves the CARE for the stabilising P (see the module doc for the method).
pub fn solve_care(
    a: &DMatrix<f64>,
    b: &DMatrix<f64>,
    q: &DMatrix<f64>,
    r: &DMatrix<f64>,
) -> Result<CareSolution, LinearError> {
    validate(a, b, q, r)?;
    let n = a.nrows();
    let r_inv = r.clone().try_inverse().ok_or(LinearError::Weight {
        what: "R",
        kind: "definite",
    })?;
    let g = b * &r_inv * b.transpose();
    let fail = |status, iterations| CareSolution {
        status,
        p: DMatrix::zeros(n, n),
        residual: f64::INFINITY,
        iterations,
    };

    let mut z = DMatrix::zeros(2 * n, 2 * n);
    z.view_mut((0, 0), (n, n)).copy_from(a);
    z.view_mut((0, n), (n, n)).copy_from(&(-&g));
    z.view_mut((n, 0), (n, n)).copy_from(&(-q));
    z.view_mut((n, n), (n, n)).copy_from(&(-a.transpose()));
    let mut iterations = 0;
    let mut converged = false;
    let mut scaling = true;
    while iterations < 100 {
        iterations += 1;
        let lu = z.clone().lu();
        let Some(z_inv) = lu.try_inverse() else {
            return Ok(fail(CareStatus::NoStabilisingSolution, iterations));
        };
        let c = if scaling {
            let det = lu.determinant().abs();
            let c = det.powf(1.0 / (2 * n) as f64);
            if c.is_finite() && c > 0.0 {
                c
            } else {
                1.0
            }
        } else {
            1.0
        };
        let next = (&z / c + &z_inv * c) * 0.5;
        let change = (&next - &z).norm() / next.norm();
        z = next;
        if !change.is_finite() {
            return Ok(fail(CareStatus::NoStabilisingSolution, iterations));
        }
        if change < 1e-2 {
            scaling = false; // scaling only speeds up the start; near the end it slows it
        }
        if change < 1e-13 {
            converged = true;
            break;
        }
    }
    if !converged {
        return Ok(fail(CareStatus::IterationLimit, iterations));
    }
    let eye = DMatrix::<f64>::identity(n, n);
    let mut lhs = DMatrix::zeros(2 * n, n);
    lhs.view_mut((0, 0), (n, n))
        .copy_from(&z.view((0, n), (n, n)));
    lhs.view_mut((n, 0), (n, n))
        .copy_from(&(z.view((n, n), (n, n)) + &eye));
    let mut rhs = DMatrix::zeros(2 * n, n);
    rhs.view_mut((0, 0), (n, n))
        .copy_from(&(-(z.view((0, 0), (n, n)) + &eye)));
    rhs.view_mut((n, 0), (n, n))
        .copy_from(&(-z.view((n, 0), (n, n))));
    let Ok(p) = lhs.svd(true, true).solve(&rhs, 1e-14) else {
        return Ok(fail(CareStatus::NoStabilisingSolution, iterations));
    };
    let mut p = (&p + p.transpose()) * 0.5;

    // Newton–Kleinman polishing.
    let mut residual = care_residual(a, &g, q, &p);
    for _ in 0..8 {
        if residual < 1e-14 {
            break;
        }
        let ak = a - &g * &p;
        let qk = q + &p * &g * &p;
        let Some(next) = solve_lyapunov(&ak, &qk) else {
            break;
        };
        let next_res = care_residual(a, &g, q, &next);
        if next_res >= residual {
            break;
        }
        p = next;
        residual = next_res;
    }
    let closed = a - &g * &p;
    let stabilising = spectral_abscissa(&eigenvalues(&closed)?) < 0.0;
    Ok(CareSolution {
        status: if stabilising && p.iter().all(|v| v.is_finite()) {
            CareStatus::Solved
        } else {
            CareStatus::NoStabilisingSolution
        },
        p,
        residual,
        iterations,
    })
}
