//! The continuous Lyapunov equation Aᵀ X + X A + Q = 0, solved through its Kronecker form
//! (I ⊗ Aᵀ + Aᵀ ⊗ I) vec X = −vec Q. That is an n² × n² dense solve: exact to rounding and
//! simple, and cheap for the 4–10 states of a vehicle (a Bartels–Stewart solver only pays
//! off far beyond that).

use nalgebra::DMatrix;

/// X with Aᵀ X + X A + Q = 0, symmetrised; `None` when A has eigenvalues λ_i + λ_j = 0
/// (the equation is then singular).
pub fn solve_lyapunov(a: &DMatrix<f64>, q: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = a.nrows();
    let at = a.transpose();
    let eye = DMatrix::<f64>::identity(n, n);
    let k = eye.kronecker(&at) + at.kronecker(&eye);
    let rhs = -DMatrix::from_column_slice(n * n, 1, q.as_slice());
    let x = k.lu().solve(&rhs)?;
    let x = DMatrix::from_column_slice(n, n, x.as_slice());
    let x = (&x + x.transpose()) * 0.5;
    x.iter().all(|v| v.is_finite()).then_some(x)
}
