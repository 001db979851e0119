//! The IR interpreter: evaluates any function of a validated IR with the same operations in the
//! same order as the generated code, so results are bit-identical; it is both the reference the
//! generated code is tested against and the way to analyse a user's IR file without recompiling.

use std::cell::RefCell;
use std::sync::Arc;

use twv_model::{Mechanical, Model, ModelInfo};

use crate::error::{ModelError, WorkTooShort};
use crate::native::NativeCode;
use crate::params::check_values;
use crate::types::{Function, Instr, Ir, Output};

impl Function {
    /// Evaluate every instruction at (x, u, p) into `work[..n_values]`. Inputs outside the given
    /// slices read as NaN (never a panic); the outputs are then `work[output.values[e]]`.
    pub fn eval(
        &self,
        x: &[f64],
        u: &[f64],
        p: &[f64],
        work: &mut [f64],
    ) -> Result<(), WorkTooShort> {
        let (needed, given) = (self.n_values(), work.len());
        if given < needed {
            return Err(WorkTooShort { needed, given });
        }
        let args = [x, u, p];
        for (k, instr) in self.instructions.iter().enumerate() {
            work[k] = match *instr {
                Instr::Input { arg, index } => {
                    args[arg.number()].get(index).copied().unwrap_or(f64::NAN)
                }
                Instr::Const(c) => c,
                Instr::Unary(op, a) => op.apply(work[a]),
                Instr::Binary(op, a, b) => op.apply(work[a], work[b]),
            };
        }
        Ok(())
    }
}

/// What every interpreted model of one IR shares: the IR, its names as `'static` strings (leaked
/// once per IR, because [`ModelInfo`] holds `&'static str`) and the row-wise order of ∂f/∂x
/// that the sparse J·W product sums in.
#[derive(Debug)]
struct Program {
    ir: Ir,
    info: ModelInfo,
    /// Each row of ∂f/∂x as its stored entries' (column, value id in `f_jac_x`), columns
    /// increasing: the row form of J·W that every path computes (`twv_kernels::tangents`).
    jw_rows: Vec<Vec<(usize, usize)>>,
    work_len: usize,
    /// Native code for the functions (run-time compiled), or `None`: interpret them.
    native: Option<Arc<dyn NativeCode>>,
}

fn leak(s: &str) -> &'static str {
    Box::leak(s.to_string().into_boxed_str())
}

fn leak_names<'a>(names: impl Iterator<Item = &'a String>) -> &'static [&'static str] {
    Box::leak(
        names
            .map(|n| leak(n))
            .collect::<Vec<_>>()
            .into_boxed_slice(),
    )
}

impl Program {
    fn new(ir: &Ir, native: Option<Arc<dyn NativeCode>>) -> Self {
        let info = ModelInfo {
            name: leak(ir.model()),
            ir_hash: leak(ir.hash()),
            states: leak_names(ir.states().iter().map(|s| &s.name)),
            inputs: leak_names(ir.inputs().iter().map(|s| &s.name)),
            params: leak_names(ir.params().iter().map(|p| &p.name)),
        };
        let jw_rows = ir
            .output("f_jac_x", "jac_x")
            .map_or_else(Vec::new, Output::stored_row_values);
        let work_len = ir
            .functions()
            .values()
            .map(Function::n_values)
            .max()
            .unwrap_or(0);
        Program {
            ir: ir.clone(),
            info,
            jw_rows,
            work_len,
            native,
        }
    }
}

/// A model evaluated by interpreting its IR: implements [`Model`] (and [`Mechanical`] for
/// multibody models) with the same numbers as the generated code. Given native code compiled
/// from the IR ([`Interpreted::with_native`]), it runs that instead, with the same bits.
///
/// `NX` is the IR's number of states; `NU` may exceed its number of inputs: the extra inputs are
/// padding that the equations never read (their columns of ∂f/∂u are zero, and
/// [`ModelInfo::inputs`] names only the real ones), so one `NU` serves every input count.
///
/// Evaluations use one preallocated work vector behind a `RefCell`, so a value is `Send` but not
/// `Sync`: give each thread its own clone. No method allocates after construction.
#[derive(Debug, Clone)]
pub struct Interpreted<const NX: usize, const NU: usize> {
    program: Arc<Program>,
    params: Vec<f64>,
    work: RefCell<Vec<f64>>,
}

impl<const NX: usize, const NU: usize> Interpreted<NX, NU> {
    /// A model of `ir` with parameter values `params` (validated like a parameter file's).
    pub fn new(ir: &Ir, params: &[f64]) -> Result<Self, ModelError> {
        Self::with_native(ir, params, None)
    }

    /// A model of `ir` with parameter values `params` that runs `native`, code compiled from
    /// `ir` (checked by its hash), instead of interpreting (`None`: interpret).
    pub fn with_native(
        ir: &Ir,
        params: &[f64],
        native: Option<Arc<dyn NativeCode>>,
    ) -> Result<Self, ModelError> {
        let size = |what, found, expected| {
            if found == expected {
                Ok(())
            } else {
                Err(ModelError::Size {
                    file: ir.file().to_string(),
                    what,
                    found,
                    expected,
                })
            }
        };
        size("states", ir.nx(), NX)?;
        if ir.nu() > NU {
            size("inputs", ir.nu(), NU)?;
        }
        if let Some(code) = &native {
            if code.ir_hash() != ir.hash() {
                return Err(ModelError::NativeCode {
                    file: ir.file().to_string(),
                    compiled: code.ir_hash().to_string(),
                    ir: ir.hash().to_string(),
                });
            }
        }
        let program = Arc::new(Program::new(ir, native));
        Self::from_program(program, params)
    }

    /// A model of `ir` with every parameter at its IR default.
    pub fn with_defaults(ir: &Ir) -> Result<Self, ModelError> {
        Self::new(ir, &ir.defaults())
    }

    /// The same model with other parameter values (shares the IR and its names).
    pub fn with_params(&self, params: &[f64]) -> Result<Self, ModelError> {
        Self::from_program(self.program.clone(), params)
    }

    fn from_program(program: Arc<Program>, params: &[f64]) -> Result<Self, ModelError> {
        check_values(params, program.ir.file(), program.ir.params())?;
        let work = RefCell::new(vec![0.0; program.work_len]);
        Ok(Interpreted {
            program,
            params: params.to_vec(),
            work,
        })
    }

    /// The IR this model interprets.
    pub fn ir(&self) -> &Ir {
        &self.program.ir
    }

    /// Whether the functions run as native code rather than interpreted.
    pub fn is_native(&self) -> bool {
        self.program.native.is_some()
    }

    /// The parameter values, in IR order.
    pub fn params(&self) -> &[f64] {
        &self.params
    }

    /// Number of quasi-velocities (the `NS` of [`Mechanical`]), 0 for explicit models.
    pub fn ns(&self) -> usize {
        self.program.ir.ns()
    }

    /// Evaluate `function` at (x, u) and pass its outputs and values to `read`. Returns false
    /// (and does not call `read`) when the function does not exist; the work vector is always
    /// long enough and never borrowed twice, so nothing else can fail.
    fn run(
        &self,
        function: &str,
        x: &[f64],
        u: &[f64],
        read: impl FnOnce(&Function, &[f64]),
    ) -> bool {
        let Some(f) = self.program.ir.function(function) else {
            return false;
        };
        let Ok(mut work) = self.work.try_borrow_mut() else {
            return false;
        };
        let native = self.program.native.as_ref();
        let compiled = native.is_some_and(|n| n.eval(function, x, u, &self.params, &mut work));
        if !compiled && f.eval(x, u, &self.params, &mut work).is_err() {
            return false;
        }
        read(f, &work);
        true
    }

    /// Evaluate output `output` of `function` as a dense `rows`×`cols` matrix through `set(r, c, v)`
    /// after `clear()`; false if the function is missing or has another shape.
    fn dense(
        &self,
        (function, output): (&str, &str),
        (x, u): (&[f64], &[f64]),
        (rows, cols): (usize, usize),
        mut set: impl FnMut(usize, usize, f64),
    ) -> bool {
        let mut found = false;
        let ran = self.run(function, x, u, |f, w| {
            let Some(o) = f
                .output(output)
                .filter(|o| (o.rows, o.cols) == (rows, cols))
            else {
                return;
            };
            found = true;
            for r in 0..rows {
                for c in 0..cols {
                    set(r, c, 0.0);
                }
            }
            for (r, c, v) in o.entries() {
                set(r, c, w[v]);
            }
        });
        ran && found
    }

    fn vector<const R: usize>(&self, function: &str, x: &[f64], u: &[f64], out: &mut [f64; R]) {
        if self.native_dense(function, (x, u), (R, 1, 1), out) {
            return;
        }
        if !self.dense((function, function), (x, u), (R, 1), |r, _, v| out[r] = v) {
            out.fill(f64::NAN);
        }
    }

    /// Output `function` as an R × C matrix whose first `cols` columns the IR holds (the rest,
    /// padding inputs, are zero).
    fn matrix<const R: usize, const C: usize>(
        &self,
        function: &str,
        (x, u): (&[f64], &[f64]),
        cols: usize,
        out: &mut [[f64; C]; R],
    ) {
        out.iter_mut().for_each(|row| row.fill(0.0));
        let shape = (R, cols, C);
        if cols <= C && self.native_dense(function, (x, u), shape, out.as_flattened_mut()) {
            return;
        }
        if cols > C
            || !self.dense((function, function), (x, u), (R, cols), |r, c, v| {
                out[r][c] = v
            })
        {
            out.iter_mut().for_each(|row| row.fill(f64::NAN));
        }
    }

    /// The native code's dense routine of `function`, if there is one (see
    /// [`NativeCode::dense`]).
    fn native_dense(
        &self,
        function: &str,
        (x, u): (&[f64], &[f64]),
        shape: (usize, usize, usize),
        out: &mut [f64],
    ) -> bool {
        let native = self.program.native.as_ref();
        native.is_some_and(|n| n.dense(function, (x, u, &self.params), shape, out))
    }

    fn jac_output(&self) -> Option<&Output> {
        self.program.ir.jac_x_sparsity()
    }
}

impl<const NX: usize, const NU: usize> Model<NX, NU> for Interpreted<NX, NU> {
    /// Every call evaluates the IR (interpreted or through its native code).
    const COMPILED_IN: bool = false;

    fn info(&self) -> ModelInfo {
        self.program.info
    }

    fn f(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [f64; NX]) {
        self.vector("f", x, u, out);
    }

    fn jac_x(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [[f64; NX]; NX]) {
        self.matrix("jac_x", (x, u), NX, out);
    }

    fn jac_u(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [[f64; NU]; NX]) {
        self.matrix("jac_u", (x, u), self.program.ir.nu(), out);
    }

    fn jac_x_colind(&self) -> &[usize] {
        self.jac_output().map_or(&[], |o| &o.colind)
    }

    fn jac_x_row(&self) -> &[usize] {
        self.jac_output().map_or(&[], |o| &o.row)
    }

    fn jac_x_sparse(&self, x: &[f64; NX], u: &[f64; NU], values: &mut [f64]) {
        let ran = self.run("jac_x", x, u, |f, w| {
            let ids = f.output("jac_x").map_or(&[][..], |o| &o.values);
            for (slot, &id) in values.iter_mut().zip(ids) {
                *slot = w[id];
            }
        });
        if !ran {
            values.fill(f64::NAN);
        }
    }

    fn f_jw<const K: usize>(
        &self,
        x: &[f64; NX],
        u: &[f64; NU],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        out: &mut [[f64; NX]; K],
    ) {
        // Without tangent vectors only f is needed: the IR's `f` gives the same bits as the `f`
        // of `f_jac_x` (every division goes through the same lowering) at a fraction of the
        // work (the bicycle: 5k operations instead of 33k).
        if K == 0 {
            return self.f(x, u, f);
        }
        self.f_jw_trace(x, u, w, f, out);
    }

    /// The trace as the generated code sums it: 0.0 plus the stored diagonal entries of
    /// `f_jac_x`'s ∂f/∂x in order, from the same evaluation as f and J·W.
    fn f_jw_trace<const K: usize>(
        &self,
        x: &[f64; NX],
        u: &[f64; NU],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        out: &mut [[f64; NX]; K],
    ) -> f64 {
        if let Some(native) = &self.program.native {
            let (wf, of) = (w.as_flattened(), out.as_flattened_mut());
            if let Some(trace) = native.f_jw((x, u, &self.params), (wf, K), f, of) {
                return trace;
            }
        }
        let p = &*self.program;
        let mut trace = f64::NAN;
        let ran = self.run("f_jac_x", x, u, |func, vals| {
            f.fill(0.0);
            if let Some(o) = func.output("f") {
                o.entries().for_each(|(r, _, v)| f[r] = vals[v]);
            }
            trace = func.output("jac_x").map_or(0.0, |o| {
                o.entries()
                    .filter(|(r, c, _)| r == c)
                    .fold(0.0, |sum, (_, _, v)| sum + vals[v])
            });
            for (wk, ok) in w.iter().zip(out.iter_mut()) {
                // The row form: each row's stored products summed left to right, 0.0 where a
                // row has none.
                ok.fill(0.0);
                for (slot, row) in ok.iter_mut().zip(&p.jw_rows) {
                    let mut terms = row.iter().map(|&(c, v)| vals[v] * wk[c]);
                    if let Some(first) = terms.next() {
                        *slot = terms.fold(first, |sum, term| sum + term);
                    }
                }
            }
        });
        if !ran {
            f.fill(f64::NAN);
            out.iter_mut().for_each(|row| row.fill(f64::NAN));
        }
        trace
    }
}

/// The mechanical parts are evaluated with u = 0 except `Q` (as in the generated code). An `NS` other than the IR's number
/// of speeds, or an explicit model, gives NaN outputs (the trait has no error channel; check
/// [`Interpreted::ns`] first).
impl<const NX: usize, const NU: usize, const NS: usize> Mechanical<NX, NU, NS>
    for Interpreted<NX, NU>
{
    fn mass_matrix(&self, x: &[f64; NX], out: &mut [[f64; NS]; NS]) {
        self.matrix("M", (x, &[0.0; NU]), NS, out);
    }

    fn cp(&self, x: &[f64; NX], out: &mut [f64; NS]) {
        self.vector("Cp", x, &[0.0; NU], out);
    }

    fn gravity(&self, x: &[f64; NX], out: &mut [f64; NS]) {
        self.vector("F", x, &[0.0; NU], out);
    }

    fn input_forces(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [f64; NS]) {
        self.vector("Q", x, u, out);
    }

    fn energy(&self, x: &[f64; NX]) -> f64 {
        let mut out = [0.0; 1];
        self.vector("energy", x, &[0.0; NU], &mut out);
        out[0]
    }

    fn momentum(&self, x: &[f64; NX]) -> [f64; 3] {
        let mut out = [0.0; 3];
        self.vector("momentum", x, &[0.0; NU], &mut out);
        out
    }
}

/// An IR whose sizes [`visit_interpreted`] does not instantiate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{file}: {nx} states and {nu} inputs; the interpreter dispatch supports 1..={max_nx} states and 0..={max_nu} inputs")]
pub struct UnsupportedSize {
    pub file: String,
    pub nx: usize,
    pub nu: usize,
    pub max_nx: usize,
    pub max_nu: usize,
}

/// Why [`visit_interpreted`] could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum VisitError {
    #[error(transparent)]
    Size(#[from] UnsupportedSize),
    #[error(transparent)]
    Model(#[from] ModelError),
}

macro_rules! dispatch_sizes {
    ($ir:expr, $params:expr, $visitor:expr; $($nx:literal),*; $nus:tt) => {{
        let (ir, params, visitor) = ($ir, $params, $visitor);
        match ir.nx() {
            $($nx => dispatch_sizes!(@nu ir, params, visitor, $nx, $nus),)*
            _ => Err(unsupported(ir)),
        }
    }};
    (@nu $ir:ident, $params:ident, $visitor:ident, $nx:literal, [$($nu:literal),*]) => {
        match MAX_NU {
            $($nu => Ok($visitor.visit(Interpreted::<$nx, $nu>::with_native($ir, $params.0, $params.1)?)),)*
            _ => Err(unsupported($ir)),
        }
    };
}

/// The largest state count [`visit_interpreted`] dispatches.
pub const MAX_NX: usize = 12;
/// The input count every interpreted model is given (real inputs first, then padding).
pub const MAX_NU: usize = 4;

fn unsupported(ir: &Ir) -> VisitError {
    VisitError::Size(UnsupportedSize::of(ir))
}

impl UnsupportedSize {
    /// The error for `ir`, whose sizes are beyond [`MAX_NX`] states or [`MAX_NU`] inputs.
    pub fn of(ir: &Ir) -> Self {
        Self {
            file: ir.file().to_string(),
            nx: ir.nx(),
            nu: ir.nu(),
            max_nx: MAX_NX,
            max_nu: MAX_NU,
        }
    }
}

/// Run `visitor` on the interpreted model of `ir` with `params` (IR order) and optional
/// `native` code (see [`Interpreted::with_native`]), choosing the const
/// size `NX` from the IR at run time: how `--ir FILE` reaches code generic over [`Model`]. Each
/// state count instantiates the visitor once (1 to 12), always with `NU` = 4 inputs, the real
/// ones followed by padding (see [`Interpreted`]), so this costs the caller 12 instantiations.
pub fn visit_interpreted<V: twv_model::ModelVisitor>(
    ir: &Ir,
    params: &[f64],
    native: Option<Arc<dyn NativeCode>>,
    visitor: V,
) -> Result<V::Output, VisitError> {
    if ir.nu() > MAX_NU {
        return Err(unsupported(ir));
    }
    dispatch_sizes!(ir, (params, native), visitor; 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12; [4])
}
