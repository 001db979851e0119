//! The model an exported library runs, behind sizes known only at run time: generated code for a
//! shipped model whose IR is the one built in (its hash decides), the IR interpreter otherwise.
//! Both give the same bits (the interpreter is the generated code's reference).

use twv_generated::{HenonHeiles, Lorenz, Segway7, Vehicle7, Vehicle8};
use twv_ir::{Bundle, Function, Ir};
use twv_model::Model;

/// ẋ = f(x, u; p) and its dense Jacobians, evaluated into caller-owned buffers: nothing here
/// allocates, so a simulation step of an FMU or a CasADi call does not either.
pub trait Plant: Send + Sync {
    /// Number of states.
    fn nx(&self) -> usize;
    /// Number of inputs.
    fn nu(&self) -> usize;
    /// Length of the `work` slice every evaluation needs.
    fn work_len(&self) -> usize;
    /// `out = f(x, u; p)`.
    fn f(&self, p: &[f64], x: &[f64], u: &[f64], out: &mut [f64], work: &mut [f64]);
    /// `out` = ∂f/∂x, row-major `nx × nx`.
    fn jac_x(&self, p: &[f64], x: &[f64], u: &[f64], out: &mut [f64], work: &mut [f64]);
    /// `out` = ∂f/∂u, row-major `nx × nu`.
    fn jac_u(&self, p: &[f64], x: &[f64], u: &[f64], out: &mut [f64], work: &mut [f64]);
    /// Which code runs: `generated` or `interpreter`.
    fn engine(&self) -> &'static str;
}

/// A loaded bundle: the validated IR, the values it was exported with, and the plant.
pub struct Loaded {
    /// The model IR (names, units, sparsity).
    pub ir: Ir,
    /// The exported parameter values.
    pub params: Vec<f64>,
    /// The RK4 step of a co-simulation step [s].
    pub rk4_step: f64,
    /// Whether the parameters are variables.
    pub tunable: bool,
    /// The equations.
    pub plant: Box<dyn Plant>,
}

impl Loaded {
    /// The plant of `bundle`.
    pub fn new(bundle: &Bundle) -> Result<Self, String> {
        let (ir, params) = bundle.model().map_err(|e| e.to_string())?;
        let plant = generated(&ir).unwrap_or_else(|| Box::new(Interpreted::new(&ir)));
        Ok(Loaded {
            ir,
            params,
            rk4_step: bundle.rk4_step,
            tunable: bundle.tunable,
            plant,
        })
    }
}

/// Generated code for `ir` when it is the IR a shipped model was generated from.
fn generated(ir: &Ir) -> Option<Box<dyn Plant>> {
    macro_rules! shipped {
        ($($ty:ident),*) => {
            $(if ir.hash() == $ty::IR_HASH {
                return Some(Box::new(Generated::<_, { $ty::NX }, { $ty::NU }, { $ty::NP }> {
                    make: $ty::new,
                }));
            })*
        };
    }
    shipped!(Vehicle8, Vehicle7, Segway7, Lorenz, HenonHeiles);
    None
}

/// A shipped model's generated code; `make` builds it from parameter values (a copy of them:
/// cheap enough per call, and it keeps tunable parameters free of any shared state).
struct Generated<M, const NX: usize, const NU: usize, const NP: usize> {
    make: fn([f64; NP]) -> M,
}

/// The first `N` entries of `v` (missing ones NaN: a caller's short slice gives NaN, not a panic).
fn array<const N: usize>(v: &[f64]) -> [f64; N] {
    core::array::from_fn(|i| v.get(i).copied().unwrap_or(f64::NAN))
}

impl<M: Model<NX, NU>, const NX: usize, const NU: usize, const NP: usize> Plant
    for Generated<M, NX, NU, NP>
{
    fn nx(&self) -> usize {
        NX
    }
    fn nu(&self) -> usize {
        NU
    }
    fn work_len(&self) -> usize {
        0
    }
    fn f(&self, p: &[f64], x: &[f64], u: &[f64], out: &mut [f64], _work: &mut [f64]) {
        let mut dx = [0.0; NX];
        (self.make)(array(p)).f(&array(x), &array(u), &mut dx);
        out.iter_mut().zip(dx).for_each(|(o, v)| *o = v);
    }
    fn jac_x(&self, p: &[f64], x: &[f64], u: &[f64], out: &mut [f64], _work: &mut [f64]) {
        let mut j = [[0.0; NX]; NX];
        (self.make)(array(p)).jac_x(&array(x), &array(u), &mut j);
        out.iter_mut()
            .zip(j.as_flattened())
            .for_each(|(o, v)| *o = *v);
    }
    fn jac_u(&self, p: &[f64], x: &[f64], u: &[f64], out: &mut [f64], _work: &mut [f64]) {
        let mut j = [[0.0; NU]; NX];
        (self.make)(array(p)).jac_u(&array(x), &array(u), &mut j);
        out.iter_mut()
            .zip(j.as_flattened())
            .for_each(|(o, v)| *o = *v);
    }
    fn engine(&self) -> &'static str {
        "generated"
    }
}

/// A model run by the IR interpreter (`twv_ir::Function::eval`) in the caller's work slice.
struct Interpreted {
    ir: Ir,
}

impl Interpreted {
    fn new(ir: &Ir) -> Self {
        Interpreted { ir: ir.clone() }
    }

    /// Function `name` (a validated IR has f, jac_x and jac_u) as a dense row-major matrix of
    /// `cols` columns in `out`; NaN when it cannot run (a short work slice).
    fn dense(
        &self,
        name: &str,
        cols: usize,
        (p, x, u): (&[f64], &[f64], &[f64]),
        out: &mut [f64],
        work: &mut [f64],
    ) {
        let Some(function) = self.ir.function(name) else {
            out.fill(f64::NAN);
            return;
        };
        if function.eval(x, u, p, work).is_err() {
            out.fill(f64::NAN);
            return;
        }
        out.fill(0.0);
        if let Some(o) = function.output(name) {
            for (r, c, v) in o.entries() {
                if let Some(slot) = out.get_mut(r * cols + c) {
                    *slot = work[v];
                }
            }
        }
    }
}

impl Plant for Interpreted {
    fn nx(&self) -> usize {
        self.ir.nx()
    }
    fn nu(&self) -> usize {
        self.ir.nu()
    }
    fn work_len(&self) -> usize {
        ["f", "jac_x", "jac_u"]
            .iter()
            .filter_map(|name| self.ir.function(name))
            .map(Function::n_values)
            .max()
            .unwrap_or(0)
    }
    fn f(&self, p: &[f64], x: &[f64], u: &[f64], out: &mut [f64], work: &mut [f64]) {
        self.dense("f", 1, (p, x, u), out, work);
    }
    fn jac_x(&self, p: &[f64], x: &[f64], u: &[f64], out: &mut [f64], work: &mut [f64]) {
        self.dense("jac_x", self.ir.nx(), (p, x, u), out, work);
    }
    fn jac_u(&self, p: &[f64], x: &[f64], u: &[f64], out: &mut [f64], work: &mut [f64]) {
        self.dense("jac_u", self.ir.nu(), (p, x, u), out, work);
    }
    fn engine(&self) -> &'static str {
        "interpreter"
    }
}
