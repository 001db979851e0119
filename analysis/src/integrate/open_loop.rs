//! A model under a constant input: the open-loop vector field.

use twv_model::Model;

use super::VectorField;

/// ẋ = f(x, u) with a constant input `u` (the study's open-loop runs, and constant external
/// forces). J = ∂f/∂x comes straight from the model's `f_jw` kernel.
#[derive(Debug)]
pub struct OpenLoop<'a, M, const NU: usize> {
    /// The model.
    pub model: &'a M,
    /// The constant input.
    pub u: [f64; NU],
}

// By hand: a derive would require `M: Copy`, but only the reference is copied.
impl<M, const NU: usize> Clone for OpenLoop<'_, M, NU> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<M, const NU: usize> Copy for OpenLoop<'_, M, NU> {}

impl<'a, M, const NU: usize> OpenLoop<'a, M, NU> {
    /// The model `model` driven by the constant input `u`.
    pub fn new(model: &'a M, u: [f64; NU]) -> Self {
        Self { model, u }
    }
}

impl<M, const NX: usize, const NU: usize> VectorField<NX> for OpenLoop<'_, M, NU>
where
    M: Model<NX, NU>,
{
    const COMPILED_IN: bool = M::COMPILED_IN;

    #[inline(always)]
    fn eval<const K: usize>(
        &self,
        _t: f64,
        x: &[f64; NX],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        jw: &mut [[f64; NX]; K],
    ) {
        self.model.f_jw(x, &self.u, w, f, jw);
    }

    #[inline(always)]
    fn eval_trace<const K: usize>(
        &self,
        _t: f64,
        x: &[f64; NX],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        jw: &mut [[f64; NX]; K],
    ) -> f64 {
        self.model.f_jw_trace(x, &self.u, w, f, jw)
    }

    #[inline(always)]
    fn rhs(&self, _t: f64, x: &[f64; NX], f: &mut [f64; NX]) {
        self.model.f(x, &self.u, f);
    }

    /// From the dense `jac_x`: one Jacobian evaluation instead of NX directional derivatives.
    #[inline]
    fn trace_jacobian(&self, _t: f64, x: &[f64; NX]) -> f64 {
        let mut j = [[0.0; NX]; NX];
        self.model.jac_x(x, &self.u, &mut j);
        diag_sum(&j)
    }

    fn jacobian(&self, _t: f64, x: &[f64; NX], out: &mut [[f64; NX]; NX]) {
        self.model.jac_x(x, &self.u, out);
    }
}

/// Σ a_ii.
#[inline(always)]
pub(crate) fn diag_sum<const N: usize>(a: &[[f64; N]; N]) -> f64 {
    a.iter().enumerate().map(|(i, row)| row[i]).sum()
}
