//! The tangent dynamics restricted to a coordinate subspace: ẇ = P J P w with P the projector
//! onto the kept coordinates (the state itself evolves unchanged).
//!
//! When the dropped coordinates form an invariant subspace of J (nothing kept depends on them,
//! as for the drift directions x, y, θ of a vehicle), this is the quotient dynamics, and its
//! exponents are those of the full system minus the dropped subspace's — which for drift are
//! zero, and whose finite-time values (ln t / t from shear) would otherwise mask the sign of the
//! exponents that matter.

use super::VectorField;

/// `field` with its tangent dynamics projected onto the coordinates where `keep` is true.
#[derive(Debug, Clone, Copy)]
pub struct Projected<F, const N: usize> {
    /// The field.
    pub field: F,
    /// Which coordinates the tangent vectors keep.
    pub keep: [bool; N],
}

/// Zeroes the dropped coordinates of each tangent derivative.
#[inline(always)]
pub fn project<const N: usize>(keep: &[bool; N], w: &mut [f64; N]) {
    for (v, k) in w.iter_mut().zip(keep) {
        if !k {
            *v = 0.0;
        }
    }
}

impl<F: VectorField<N>, const N: usize> VectorField<N> for Projected<F, N> {
    const COMPILED_IN: bool = F::COMPILED_IN;

    #[inline(always)]
    fn eval<const K: usize>(
        &self,
        t: f64,
        x: &[f64; N],
        w: &[[f64; N]; K],
        f: &mut [f64; N],
        jw: &mut [[f64; N]; K],
    ) {
        self.field.eval(t, x, w, f, jw);
        for row in jw.iter_mut() {
            project(&self.keep, row);
        }
    }
}
