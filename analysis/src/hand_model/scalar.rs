//! The number type the hand equations are written over.
//!
//! Every closed-form expression of the hand model is written once, generically over [`Real`], and
//! evaluated either with `f64` (the values) or with [`Dual`] (forward-mode derivative numbers). The
//! dual evaluation gives the Jacobians ∂f/∂x, ∂f/∂u, directional derivatives (∂f/∂x) w and the time
//! derivative Ṁ = Σ ∂M/∂q_i q̇_i to rounding error, with no step size to choose. That matters: the
//! audit compares Jacobians term by term at 1e-11 relative, which central differences (≈1e-8)
//! cannot meet, and the derivative still comes from the hand formulas alone.

use core::ops::{Add, Div, Mul, Neg, Sub};

/// A scalar the hand equations can be evaluated with: `f64` or [`Dual`].
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Mul<f64, Output = Self>
{
    /// A constant (zero derivative).
    fn cst(v: f64) -> Self;
    /// The value part (used to choose pivots and to read results).
    fn value(self) -> f64;
    /// sin.
    fn sin(self) -> Self;
    /// cos.
    fn cos(self) -> Self;
    /// Square root (a user's hand file may use it).
    fn sqrt(self) -> Self;
    /// Exponential.
    fn exp(self) -> Self;
    /// Natural logarithm.
    fn ln(self) -> Self;
}

impl Real for f64 {
    fn cst(v: f64) -> Self {
        v
    }
    fn value(self) -> f64 {
        self
    }
    fn sin(self) -> Self {
        f64::sin(self)
    }
    fn cos(self) -> Self {
        f64::cos(self)
    }
    fn sqrt(self) -> Self {
        f64::sqrt(self)
    }
    fn exp(self) -> Self {
        f64::exp(self)
    }
    fn ln(self) -> Self {
        f64::ln(self)
    }
}

/// A forward-mode dual number v + d ε with ε² = 0: `d` carries one directional derivative.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Dual {
    /// Value.
    pub v: f64,
    /// Derivative along the seeded direction.
    pub d: f64,
}

impl Dual {
    /// A dual number with value `v` and derivative `d`.
    pub const fn new(v: f64, d: f64) -> Self {
        Self { v, d }
    }
}

impl Add for Dual {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self::new(self.v + o.v, self.d + o.d)
    }
}

impl Sub for Dual {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self::new(self.v - o.v, self.d - o.d)
    }
}

impl Mul for Dual {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        Self::new(self.v * o.v, self.d * o.v + self.v * o.d)
    }
}

impl Div for Dual {
    type Output = Self;
    fn div(self, o: Self) -> Self {
        let q = self.v / o.v;
        Self::new(q, (self.d - q * o.d) / o.v)
    }
}

impl Neg for Dual {
    type Output = Self;
    fn neg(self) -> Self {
        Self::new(-self.v, -self.d)
    }
}

impl Add<f64> for Dual {
    type Output = Self;
    fn add(self, o: f64) -> Self {
        Self::new(self.v + o, self.d)
    }
}

impl Mul<f64> for Dual {
    type Output = Self;
    fn mul(self, o: f64) -> Self {
        Self::new(self.v * o, self.d * o)
    }
}

impl Real for Dual {
    fn cst(v: f64) -> Self {
        Self::new(v, 0.0)
    }
    fn value(self) -> f64 {
        self.v
    }
    fn sin(self) -> Self {
        Self::new(self.v.sin(), self.v.cos() * self.d)
    }
    fn cos(self) -> Self {
        Self::new(self.v.cos(), -self.v.sin() * self.d)
    }
    fn sqrt(self) -> Self {
        let r = self.v.sqrt();
        Self::new(r, self.d / (2.0 * r))
    }
    fn exp(self) -> Self {
        let e = self.v.exp();
        Self::new(e, e * self.d)
    }
    fn ln(self) -> Self {
        Self::new(self.v.ln(), self.d / self.v)
    }
}

/// Solves `a z = b` by Gaussian elimination with partial pivoting (pivots chosen on the value
/// part), on the stack. M is symmetric positive definite for physical parameters, so the pivoting
/// is only a guard; a singular matrix gives non-finite output, never a panic.
pub fn solve<S: Real, const N: usize>(mut a: [[S; N]; N], mut b: [S; N]) -> [S; N] {
    solve_in_place(&mut a, &mut b);
    b
}

/// [`solve`] on rows of any storage, overwriting `b` with z: the same operations in the same
/// order (so the same bits), for run-time sizes such as a user's hand file (`hand_file`).
pub fn solve_in_place<S: Real, R: AsMut<[S]>>(a: &mut [R], b: &mut [S]) {
    let n = b.len();
    for k in 0..n {
        let mut piv = k;
        let mut best = a[k].as_mut()[k].value().abs();
        for (i, row) in a.iter_mut().enumerate().skip(k + 1) {
            let m = row.as_mut()[k].value().abs();
            if m > best {
                best = m;
                piv = i;
            }
        }
        a.swap(k, piv);
        b.swap(k, piv);
        let (top, bottom) = a.split_at_mut(k + 1);
        let rowk = top[k].as_mut();
        let akk = rowk[k];
        for (i, row) in bottom.iter_mut().enumerate() {
            let row = row.as_mut();
            let l = row[k] / akk;
            for (aij, akj) in row.iter_mut().zip(rowk.iter()).skip(k) {
                *aij = *aij - l * *akj;
            }
            b[k + 1 + i] = b[k + 1 + i] - l * b[k];
        }
    }
    for k in (0..n).rev() {
        let row = a[k].as_mut();
        let mut acc = b[k];
        for j in k + 1..n {
            acc = acc - row[j] * b[j];
        }
        b[k] = acc / row[k];
    }
}
