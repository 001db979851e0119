//! A model with `NU` inputs seen as one with `P ≥ NU`: the real inputs first, the rest ignored,
//! and ∂f/∂u zero in their columns. Interpreted models always take 4 inputs (`twv_ir::MAX_NU`);
//! padding a generated model to the same count lets code that is generic over [`Model`] be
//! compiled once per state count for both, instead of once more for every generated model.

use crate::{Model, ModelInfo, LANES};

/// `M`, which has `NU` inputs, as a model of `P ≥ NU` inputs (see the module documentation).
/// Every output is the bits of `M`'s own kernel; only ∂f/∂u is copied, into the wider rows.
#[derive(Debug, Clone, Copy)]
pub struct Padded<M, const NU: usize>(pub M);

/// The first `NU` of `P` entries, without a copy.
#[inline(always)]
fn head<T, const P: usize, const NU: usize>(u: &[T; P]) -> &[T; NU] {
    const { assert!(NU <= P, "a padded model has at least its own inputs") };
    u[..NU].try_into().expect("NU ≤ P")
}

/// `wide[i] = [narrow[i]…, zero…]`: rows of NU entries written into rows of P.
#[inline(always)]
fn widen<T: Copy, const NX: usize, const NU: usize, const P: usize>(
    narrow: &[[T; NU]; NX],
    zero: T,
    wide: &mut [[T; P]; NX],
) {
    for (w, n) in wide.iter_mut().zip(narrow) {
        w[..NU].copy_from_slice(n);
        w[NU..].fill(zero);
    }
}

impl<M, const NX: usize, const NU: usize, const P: usize> Model<NX, P> for Padded<M, NU>
where
    M: Model<NX, NU>,
{
    const COMPILED_IN: bool = M::COMPILED_IN;

    #[inline]
    fn info(&self) -> ModelInfo {
        self.0.info()
    }

    #[inline]
    fn f(&self, x: &[f64; NX], u: &[f64; P], out: &mut [f64; NX]) {
        self.0.f(x, head(u), out);
    }

    #[inline]
    fn jac_x(&self, x: &[f64; NX], u: &[f64; P], out: &mut [[f64; NX]; NX]) {
        self.0.jac_x(x, head(u), out);
    }

    #[inline]
    fn jac_u(&self, x: &[f64; NX], u: &[f64; P], out: &mut [[f64; P]; NX]) {
        let mut narrow = [[0.0; NU]; NX];
        self.0.jac_u(x, head(u), &mut narrow);
        widen(&narrow, 0.0, out);
    }

    #[inline]
    fn jac_x_colind(&self) -> &[usize] {
        self.0.jac_x_colind()
    }

    #[inline]
    fn jac_x_row(&self) -> &[usize] {
        self.0.jac_x_row()
    }

    #[inline]
    fn jac_x_sparse(&self, x: &[f64; NX], u: &[f64; P], values: &mut [f64]) {
        self.0.jac_x_sparse(x, head(u), values);
    }

    #[inline]
    fn f_jw<const K: usize>(
        &self,
        x: &[f64; NX],
        u: &[f64; P],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        out: &mut [[f64; NX]; K],
    ) {
        self.0.f_jw(x, head(u), w, f, out);
    }

    #[inline]
    fn f_jw_trace<const K: usize>(
        &self,
        x: &[f64; NX],
        u: &[f64; P],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        out: &mut [[f64; NX]; K],
    ) -> f64 {
        self.0.f_jw_trace(x, head(u), w, f, out)
    }

    #[inline]
    fn f_jw_jac_u<const K: usize>(
        &self,
        x: &[f64; NX],
        u: &[f64; P],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        out: &mut [[f64; NX]; K],
        jac_u: &mut [[f64; P]; NX],
    ) {
        let mut narrow = [[0.0; NU]; NX];
        self.0.f_jw_jac_u(x, head(u), w, f, out, &mut narrow);
        widen(&narrow, 0.0, jac_u);
    }

    #[inline]
    fn f_jw_jac_u_lanes(
        &self,
        x: &[[f64; NX]; LANES],
        u: &[[f64; P]; LANES],
        w: &[[f64; NX]; LANES],
        f: &mut [[f64; NX]; LANES],
        out: &mut [[f64; NX]; LANES],
        jac_u: &mut [[[f64; P]; NX]; LANES],
    ) {
        let narrow_u: [[f64; NU]; LANES] = core::array::from_fn(|l| *head(&u[l]));
        let mut narrow = [[[0.0; NU]; NX]; LANES];
        self.0
            .f_jw_jac_u_lanes(x, &narrow_u, w, f, out, &mut narrow);
        for (wide, narrow) in jac_u.iter_mut().zip(&narrow) {
            widen(narrow, 0.0, wide);
        }
    }

    #[inline]
    fn f_jw_jac_u_lane_arrays(
        &self,
        x: &[[f64; LANES]; NX],
        u: &[[f64; LANES]; P],
        w: &[[f64; LANES]; NX],
        f: &mut [[f64; LANES]; NX],
        out: &mut [[f64; LANES]; NX],
        jac_u: &mut [[[f64; LANES]; P]; NX],
    ) {
        let mut narrow = [[[0.0; LANES]; NU]; NX];
        self.0
            .f_jw_jac_u_lane_arrays(x, head(u), w, f, out, &mut narrow);
        widen(&narrow, [0.0; LANES], jac_u);
    }

    #[inline]
    fn f_jw_jac_u_lane_arrays_given(
        &self,
        x: &[[f64; LANES]; NX],
        u: &[[f64; LANES]; P],
        w: &[[f64; LANES]; NX],
        f: &mut [[f64; LANES]; NX],
        out: &mut [[f64; LANES]; NX],
        jac_u: &mut [[[f64; LANES]; P]; NX],
        given: (usize, &([f64; LANES], [f64; LANES])),
    ) {
        let mut narrow = [[[0.0; LANES]; NU]; NX];
        self.0
            .f_jw_jac_u_lane_arrays_given(x, head(u), w, f, out, &mut narrow, given);
        widen(&narrow, [0.0; LANES], jac_u);
    }

    #[inline]
    fn jw<const K: usize>(
        &self,
        x: &[f64; NX],
        u: &[f64; P],
        w: &[[f64; NX]; K],
        out: &mut [[f64; NX]; K],
    ) {
        self.0.jw(x, head(u), w, out);
    }
}

/// A model that cannot exist: the empty slot of a state count with fewer generated models than
/// another (`twv_analysis`'s one model type per state count has two slots).
#[derive(Debug, Clone, Copy)]
pub enum NoModel {}

impl<const NX: usize, const NU: usize> Model<NX, NU> for NoModel {
    /// No code at all: it adds nothing to the other slots of an enum of models.
    const COMPILED_IN: bool = false;

    fn info(&self) -> ModelInfo {
        match *self {}
    }
    fn f(&self, _: &[f64; NX], _: &[f64; NU], _: &mut [f64; NX]) {
        match *self {}
    }
    fn jac_x(&self, _: &[f64; NX], _: &[f64; NU], _: &mut [[f64; NX]; NX]) {
        match *self {}
    }
    fn jac_u(&self, _: &[f64; NX], _: &[f64; NU], _: &mut [[f64; NU]; NX]) {
        match *self {}
    }
    fn jac_x_colind(&self) -> &[usize] {
        match *self {}
    }
    fn jac_x_row(&self) -> &[usize] {
        match *self {}
    }
    fn jac_x_sparse(&self, _: &[f64; NX], _: &[f64; NU], _: &mut [f64]) {
        match *self {}
    }
    fn f_jw<const K: usize>(
        &self,
        _: &[f64; NX],
        _: &[f64; NU],
        _: &[[f64; NX]; K],
        _: &mut [f64; NX],
        _: &mut [[f64; NX]; K],
    ) {
        match *self {}
    }
}
