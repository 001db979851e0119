//! One model type per state count: the generated models of that count and the interpreter
//! behind one enum. The jobs are generic over the model, so every distinct model type compiles
//! every job once more; with one type per state count, a shipped model costs the build nothing
//! beyond its kernels. The price at run time is one predictable branch per call.
//!
//! The open-loop jobs see 4 inputs (an interpreted model's count, `twv_ir::MAX_NU`; a
//! generated model's own first, see [`twv_model::Padded`]). The control jobs run the hot loops
//! (maps, the closed loop's spectrum) and only models with 1 or 2 inputs, so there every type
//! has 2 and a generated vehicle runs unpadded: no copy, no padding lanes in the loop's
//! arithmetic.

use twv_generated::{HenonHeiles, Lorenz, Segway7, Vehicle7, Vehicle8};
use twv_ir::{Interpreted, MAX_NU};
use twv_model::{Model, ModelInfo, NoModel, Padded, LANES};

use super::{Engine, ResolvedModel};
use crate::error::{Error, Result};

/// The model of a state count: up to two generated models of that count, or the interpreter
/// (or the IR's native code) for any other IR of that count.
#[derive(Debug, Clone)]
pub enum SizedModel<A, B, const NX: usize, const NU: usize> {
    /// The first generated model of this count.
    First(A),
    /// The second generated model of this count.
    Second(B),
    /// An IR on the interpreter or its native code.
    Interpreted(OutOfLine<Interpreted<NX, NU>>),
}

/// The Lorenz system's count (3 states), for the open-loop jobs.
pub type Model3 = SizedModel<Padded<Lorenz, 0>, NoModel, 3, MAX_NU>;
/// Hénon–Heiles' count (4 states), for the open-loop jobs.
pub type Model4 = SizedModel<Padded<HenonHeiles, 0>, NoModel, 4, MAX_NU>;
/// vehicle7's and segway7's count, for the open-loop jobs.
pub type Model7 = SizedModel<Padded<Vehicle7, 2>, Padded<Segway7, 2>, 7, MAX_NU>;
/// vehicle8's count, for the open-loop jobs.
pub type Model8 = SizedModel<Padded<Vehicle8, 2>, NoModel, 8, MAX_NU>;
/// The control jobs' model of 7 states: vehicle7, segway7 or an IR.
pub type Control7 = SizedModel<Vehicle7, Segway7, 7, 2>;
/// The control jobs' model of 8 states: vehicle8 or an IR.
pub type Control8 = SizedModel<Vehicle8, NoModel, 8, 2>;

/// A generated model a [`SizedModel`] slot can hold, built from checked parameter values.
pub trait Shipped: Sized {
    /// Its name (`--model NAME`); empty for the empty slot.
    const NAME: &'static str;
    /// The model with these values (IR order).
    fn build(params: &[f64]) -> Result<Self>;
}

macro_rules! shipped {
    ($($ty:ident, $nu:literal);* $(;)?) => {$(
        impl Shipped for $ty {
            const NAME: &'static str = $ty::NAME;
            fn build(params: &[f64]) -> Result<Self> {
                let values: [f64; $ty::NP] = params.try_into().map_err(|_| {
                    Error::input(
                        "params",
                        format!("{} parameter values for a model with {}", params.len(), $ty::NP),
                    )
                })?;
                Ok($ty::new(values))
            }
        }

        impl Shipped for Padded<$ty, $nu> {
            const NAME: &'static str = $ty::NAME;
            fn build(params: &[f64]) -> Result<Self> {
                const { assert!($ty::NU == $nu) };
                Ok(Padded($ty::build(params)?))
            }
        }
    )*};
}

shipped!(Vehicle8, 2; Vehicle7, 2; Segway7, 2; Lorenz, 0; HenonHeiles, 0);

impl Shipped for NoModel {
    const NAME: &'static str = "";
    fn build(_: &[f64]) -> Result<Self> {
        Err(Error::input("model", "no generated model in this slot"))
    }
}

impl<A: Shipped, B: Shipped, const NX: usize, const NU: usize> SizedModel<A, B, NX, NU> {
    /// The resolved model as this count's type: its generated code when it is shipped, else
    /// the interpreter (with the IR's native code when it was compiled).
    pub fn new(resolved: &ResolvedModel) -> Result<Self> {
        match &resolved.engine {
            Engine::Generated(name) if !A::NAME.is_empty() && name == A::NAME => {
                Ok(Self::First(A::build(&resolved.params)?))
            }
            Engine::Generated(name) if !B::NAME.is_empty() && name == B::NAME => {
                Ok(Self::Second(B::build(&resolved.params)?))
            }
            Engine::Generated(name) => Err(Error::Unsupported {
                model: name.clone(),
                reason: format!("no generated model of {NX} states has this name"),
            }),
            Engine::Interpreted | Engine::Jit => {
                Ok(Self::Interpreted(OutOfLine(interpreted(resolved)?)))
            }
        }
    }
}

/// The resolved model on the interpreter (or its IR's native code), with `NU` inputs, its own
/// first: the model of a state count without generated code, and [`SizedModel`]'s third arm.
pub(super) fn interpreted<const NX: usize, const NU: usize>(
    resolved: &ResolvedModel,
) -> Result<Interpreted<NX, NU>> {
    Ok(Interpreted::with_native(
        &resolved.ir,
        &resolved.params,
        resolved.native.clone(),
    )?)
}

/// `$call` on whichever model `$self` holds, bound to `$m`.
macro_rules! each {
    ($self:expr, $m:ident => $call:expr) => {
        match $self {
            SizedModel::First($m) => $call,
            SizedModel::Second($m) => $call,
            SizedModel::Interpreted($m) => $call,
        }
    };
}

/// `$call` on the model an [`OutOfLine`] wraps, bound to `$m`.
macro_rules! inner {
    ($self:expr, $m:ident => $call:expr) => {{
        let $m = &$self.0;
        $call
    }};
}

/// Every method of [`Model`], with attribute `$attr`, handing its arguments to the model
/// `$reach!` finds in `self`: the one body of both forwarding types below.
macro_rules! forward_model {
    (#[$attr:meta] $reach:ident) => {
        #[$attr]
        fn info(&self) -> ModelInfo {
            $reach!(self, m => m.info())
        }

        #[$attr]
        fn f(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [f64; NX]) {
            $reach!(self, m => m.f(x, u, out))
        }

        #[$attr]
        fn jac_x(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [[f64; NX]; NX]) {
            $reach!(self, m => m.jac_x(x, u, out))
        }

        #[$attr]
        fn jac_u(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [[f64; NU]; NX]) {
            $reach!(self, m => m.jac_u(x, u, out))
        }

        #[$attr]
        fn jac_x_colind(&self) -> &[usize] {
            $reach!(self, m => m.jac_x_colind())
        }

        #[$attr]
        fn jac_x_row(&self) -> &[usize] {
            $reach!(self, m => m.jac_x_row())
        }

        #[$attr]
        fn jac_x_sparse(&self, x: &[f64; NX], u: &[f64; NU], values: &mut [f64]) {
            $reach!(self, m => m.jac_x_sparse(x, u, values))
        }

        #[$attr]
        fn f_jw<const K: usize>(
            &self,
            x: &[f64; NX],
            u: &[f64; NU],
            w: &[[f64; NX]; K],
            f: &mut [f64; NX],
            out: &mut [[f64; NX]; K],
        ) {
            $reach!(self, m => m.f_jw(x, u, w, f, out))
        }

        #[$attr]
        fn f_jw_trace<const K: usize>(
            &self,
            x: &[f64; NX],
            u: &[f64; NU],
            w: &[[f64; NX]; K],
            f: &mut [f64; NX],
            out: &mut [[f64; NX]; K],
        ) -> f64 {
            $reach!(self, m => m.f_jw_trace(x, u, w, f, out))
        }

        #[$attr]
        fn f_jw_jac_u<const K: usize>(
            &self,
            x: &[f64; NX],
            u: &[f64; NU],
            w: &[[f64; NX]; K],
            f: &mut [f64; NX],
            out: &mut [[f64; NX]; K],
            jac_u: &mut [[f64; NU]; NX],
        ) {
            $reach!(self, m => m.f_jw_jac_u(x, u, w, f, out, jac_u))
        }

        #[$attr]
        fn f_jw_jac_u_lanes(
            &self,
            x: &[[f64; NX]; LANES],
            u: &[[f64; NU]; LANES],
            w: &[[f64; NX]; LANES],
            f: &mut [[f64; NX]; LANES],
            out: &mut [[f64; NX]; LANES],
            jac_u: &mut [[[f64; NU]; NX]; LANES],
        ) {
            $reach!(self, m => m.f_jw_jac_u_lanes(x, u, w, f, out, jac_u))
        }

        #[$attr]
        fn f_jw_jac_u_lane_arrays(
            &self,
            x: &[[f64; LANES]; NX],
            u: &[[f64; LANES]; NU],
            w: &[[f64; LANES]; NX],
            f: &mut [[f64; LANES]; NX],
            out: &mut [[f64; LANES]; NX],
            jac_u: &mut [[[f64; LANES]; NU]; NX],
        ) {
            $reach!(self, m => m.f_jw_jac_u_lane_arrays(x, u, w, f, out, jac_u))
        }


        #[$attr]
        fn f_jw_jac_u_lane_arrays_given(
            &self,
            x: &[[f64; LANES]; NX],
            u: &[[f64; LANES]; NU],
            w: &[[f64; LANES]; NX],
            f: &mut [[f64; LANES]; NX],
            out: &mut [[f64; LANES]; NX],
            jac_u: &mut [[[f64; LANES]; NU]; NX],
            given: (usize, &([f64; LANES], [f64; LANES])),
        ) {
            $reach!(self, m => m.f_jw_jac_u_lane_arrays_given(x, u, w, f, out, jac_u, given))
        }

        #[$attr]
        fn jw<const K: usize>(
            &self,
            x: &[f64; NX],
            u: &[f64; NU],
            w: &[[f64; NX]; K],
            out: &mut [[f64; NX]; K],
        ) {
            $reach!(self, m => m.jw(x, u, w, out))
        }
    };
}

impl<A, B, const NX: usize, const NU: usize> Model<NX, NU> for SizedModel<A, B, NX, NU>
where
    A: Model<NX, NU>,
    B: Model<NX, NU>,
{
    /// Compiled in when a shipped model's generated code is one of its arms.
    const COMPILED_IN: bool = A::COMPILED_IN || B::COMPILED_IN;

    forward_model!(
        #[inline]
        each
    );
}

/// A model whose every method is a call, never inlined: the interpreter's arm of
/// [`SizedModel`], so that its large generic defaults (the lanes forms' transposes) do not
/// crowd the generated models' calls out of the hot loops they are inlined into; the
/// interpreter's own cost dwarfs one call.
#[derive(Debug, Clone)]
pub struct OutOfLine<M>(pub M);

impl<M: Model<NX, NU>, const NX: usize, const NU: usize> Model<NX, NU> for OutOfLine<M> {
    const COMPILED_IN: bool = M::COMPILED_IN;

    forward_model!(
        #[inline(never)]
        inner
    );
}
