//! A model IR compiled to native code at run time, so that a user's model (`--ir FILE`) runs
//! at compiled speed without rebuilding twv.
//!
//! [`compile`] returns the native code of a validated [`Ir`], made with Cranelift as it is
//! used: each IR function, when first called, becomes a routine that stores the values its
//! outputs read where the interpreter's work vector has them; and the two hot paths get
//! routines of their own — `f` written as a dense ẋ, and `f_jac_x` as ẋ, J·W for any number of
//! tangent vectors and tr ∂f/∂x — so that a time step does not go through the interpreter's
//! read-out. The result plugs into [`twv_ir::Interpreted::with_native`].
//!
//! **The interpreter's bits.** Each instruction becomes one operation on the values before it,
//! in the IR's order. Addition, subtraction, multiplication, division, square root, negation,
//! absolute value and copysign are IEEE-754 operations that Cranelift emits as single
//! instructions (it never fuses a multiply and an add); `sq`, `twice` and `inv` are the
//! interpreter's `a·a`, `2·a` and `1/a`. Every other operation (the trigonometric functions
//! through twv's own `sin_cos`, `pow`, comparisons, …) calls [`UnaryOp::apply`] /
//! [`BinaryOp::apply`], the interpreter's own definition. J·W and the trace are summed in the
//! interpreter's order. `tests/tests/all/jit.rs` compares every operation and every shipped
//! model with the interpreter bit for bit.

mod emit;

use std::fmt;
use std::mem::ManuallyDrop;
use std::sync::{Arc, OnceLock};

use cranelift_codegen::ir::{types, AbiParam, InstBuilder, Signature};
use cranelift_codegen::settings::{self, Configurable};
use cranelift_frontend::{FunctionBuilder, FunctionBuilderContext};
use cranelift_jit::{JITBuilder, JITModule};
use cranelift_module::{default_libcall_names, FuncId, Linkage, Module};
use twv_ir::{BinaryOp, Function, Instr, Ir, NativeCode, UnaryOp};

/// Why an IR could not be compiled.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum JitError {
    /// The code generator does not support this machine. (A routine that cannot be compiled
    /// later, when first used, is left to the interpreter, which has the same bits.)
    #[error("{file}: the JIT does not support this CPU: {message}")]
    Host { file: String, message: String },
}

/// The native code of `ir` (see the crate documentation); an error if the code generator does
/// not support this CPU.
pub fn compile(ir: &Ir) -> Result<Arc<dyn NativeCode>, JitError> {
    Ok(Arc::new(JitCode::new(ir)?))
}

/// Functions above this many instructions (the bicycle's Jacobians: 18 000) are compiled with
/// Cranelift's single-pass register allocator: the default (backtracking) one took 2.9 s for
/// the bicycle against 0.06 s, while for vehicle-sized functions it is fast and its code better.
const SINGLE_PASS_ABOVE: usize = 4000;

/// (x, u, p, work): an IR function storing its output values in the work vector.
type Entry = unsafe extern "C" fn(*const f64, *const f64, *const f64, *mut f64);

/// (x, u, p, out, stride): an output written densely, row-major with that row stride.
type Dense = unsafe extern "C" fn(*const f64, *const f64, *const f64, *mut f64, usize);

/// (x, u, p, w, k, f, out) → tr ∂f/∂x: `f_jac_x` as ẋ, J·W and the trace (the Jacobian's
/// entries pass through an array on the routine's stack).
type FJw = unsafe extern "C" fn(
    *const f64,
    *const f64,
    *const f64,
    *const f64,
    usize,
    *mut f64,
    *mut f64,
) -> f64;

/// A compiled routine with the extent of what it reads: how many entries of x, u and p.
struct Routine<E> {
    entry: E,
    reads: [usize; 3],
}

impl<E> Routine<E> {
    fn reads_within(&self, x: &[f64], u: &[f64], p: &[f64]) -> bool {
        let [nx, nu, np] = self.reads;
        x.len() >= nx && u.len() >= nu && p.len() >= np
    }
}

/// A routine and the module that owns its executable memory (freed on drop).
struct Compiled<E> {
    routine: Routine<E>,
    module: ManuallyDrop<JITModule>,
}

impl<E> Drop for Compiled<E> {
    fn drop(&mut self) {
        // SAFETY: the routine that points into this memory is dropped with it; none escapes
        // (the `NativeCode` methods only call it).
        unsafe { ManuallyDrop::take(&mut self.module).free_memory() };
    }
}

// SAFETY: after `finalize_definitions` a module is never mutated again; the code it owns is
// read-only executable memory whose routine keeps no state (it reads its arguments and writes
// only the caller's slices), so calling it from several threads is sound.
unsafe impl<E> Send for Compiled<E> {}
// SAFETY: as above.
unsafe impl<E> Sync for Compiled<E> {}

/// A routine compiled on its first use; `None` when the IR has no such function or it could
/// not be compiled (the interpreter, with the same bits, then runs instead).
type Lazy<E> = OnceLock<Option<Compiled<E>>>;

/// One IR function's routines.
struct FunctionCode {
    name: String,
    /// Its value count: the work vector its work routine writes into.
    n_values: usize,
    /// The (rows, cols) of its output of its own name (`f`, `jac_x`, `M`, …), if it has one.
    shape: Option<(usize, usize)>,
    /// Storing what its outputs read in the work vector.
    work: Lazy<Entry>,
    /// Writing its output of its own name densely.
    dense: Lazy<Dense>,
}

/// The native code of one IR: [`NativeCode`] for [`twv_ir::Interpreted::with_native`].
///
/// Each routine is compiled when it is first called, in a module of its own, so that a run
/// pays only for what it uses (a ride of the bicycle compiles its `f`, 5 000 instructions, not
/// its 80 000).
pub struct JitCode {
    ir: Ir,
    functions: Vec<FunctionCode>,
    /// The indices of `f`, `jac_x` and `jac_u`, looked up at every step.
    hot: [Option<usize>; 3],
    /// `f_jac_x` as ẋ, J·W (a loop over any number of tangent vectors) and the trace.
    f_jw: Lazy<FJw>,
    /// The same with J·W written out for exactly k tangent vectors (index k ≤
    /// [`MAX_UNROLLED`]), for functions of at most [`SINGLE_PASS_ABOVE`] instructions.
    f_jw_unrolled: [Lazy<FJw>; MAX_UNROLLED + 1],
    /// Whether `f_jac_x` is small enough to be written out per count.
    unroll: bool,
}

/// The largest number of tangent vectors J·W is written out for (one routine per count, made
/// on first use): the loop's bookkeeping and the re-reading of the Jacobian's entries for
/// every vector are gone, which is what small models (Lorenz: 3 × 3) spend most on.
const MAX_UNROLLED: usize = 16;

impl fmt::Debug for JitCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let names: Vec<&str> = self.functions.iter().map(|c| c.name.as_str()).collect();
        f.debug_struct("JitCode")
            .field("ir_hash", &self.ir.hash())
            .field("functions", &names)
            .finish()
    }
}

/// The interpreter's unary operation number `op` (its index in [`UnaryOp::ALL`]).
extern "C" fn twv_unary(op: u32, a: f64) -> f64 {
    UnaryOp::ALL
        .get(op as usize)
        .map_or(f64::NAN, |o| o.apply(a))
}

/// The interpreter's binary operation number `op` (its index in [`BinaryOp::ALL`]).
extern "C" fn twv_binary(op: u32, a: f64, b: f64) -> f64 {
    BinaryOp::ALL
        .get(op as usize)
        .map_or(f64::NAN, |o| o.apply(a, b))
}

/// `twv_kernels::trig::sin_cos_pair(a, b)` into `out[0..4]` as (sin a, cos a, sin b, cos b).
///
/// # Safety
/// `out` must be valid for writing 4 doubles.
unsafe extern "C" fn twv_sin_cos_pair(a: f64, b: f64, out: *mut f64) {
    let ((sa, ca), (sb, cb)) = twv_kernels::trig::sin_cos_pair(a, b);
    // SAFETY: the caller's; the routines pass a 32-byte stack slot of their own.
    unsafe { core::ptr::copy_nonoverlapping([sa, ca, sb, cb].as_ptr(), out, 4) };
}

/// How many entries of x, u and p `function` reads.
fn reads(function: &Function) -> [usize; 3] {
    let mut n = [0; 3];
    for instr in function.instructions() {
        if let Instr::Input { arg, index } = *instr {
            n[arg.number()] = n[arg.number()].max(index + 1);
        }
    }
    n
}

/// What a routine does with the values of its IR function.
#[derive(Clone, Copy)]
enum Shape<'a> {
    /// Store the values the outputs read at their ids in the work vector.
    Work,
    /// Store this output densely, row-major, with a row stride given at run time.
    Dense(&'a twv_ir::Output),
    /// ẋ, J·W over these rows (`Output::stored_rows`), the trace of this Jacobian.
    FJw {
        f: &'a twv_ir::Output,
        jac: &'a twv_ir::Output,
        rows: &'a [Vec<(usize, usize)>],
        /// `Some(k)`: J·W written out for exactly k tangent vectors; `None`: a loop.
        unrolled: Option<usize>,
    },
}

/// One module (one register allocator) for one routine.
struct Builder {
    module: JITModule,
    unary: FuncId,
    binary: FuncId,
    sin_cos_pair: FuncId,
}

impl Builder {
    fn new(ir: &Ir, single_pass: bool) -> Result<Self, JitError> {
        let host = |message: String| JitError::Host {
            file: ir.file().to_string(),
            message,
        };
        let mut flags = settings::builder();
        let allocator = if single_pass {
            "single_pass"
        } else {
            "backtracking"
        };
        // No verifier: the routines come from a validated IR through the code below and the
        // tests compare their results with the interpreter's bit for bit (it took a third of
        // the compile time).
        for (name, value) in [
            ("opt_level", "speed"),
            ("is_pic", "false"),
            ("regalloc_algorithm", allocator),
            ("enable_verifier", "false"),
        ] {
            flags
                .set(name, value)
                .map_err(|e| host(format!("setting {name}={value}: {e}")))?;
        }
        let isa = cranelift_native::builder()
            .map_err(|e| host(e.to_string()))?
            .finish(settings::Flags::new(flags))
            .map_err(|e| host(e.to_string()))?;
        let mut jit = JITBuilder::with_isa(isa, default_libcall_names());
        jit.symbol("twv_unary", twv_unary as *const u8);
        jit.symbol("twv_binary", twv_binary as *const u8);
        jit.symbol("twv_sin_cos_pair", twv_sin_cos_pair as *const u8);
        let mut module = JITModule::new(jit);
        let helper = |module: &mut JITModule, name: &str, operands: usize| {
            let mut sig = module.make_signature();
            sig.params.push(AbiParam::new(types::I32));
            sig.params
                .extend(std::iter::repeat_n(AbiParam::new(types::F64), operands));
            sig.returns.push(AbiParam::new(types::F64));
            module
                .declare_function(name, Linkage::Import, &sig)
                .map_err(|e| host(format!("{name}: {e}")))
        };
        let unary = helper(&mut module, "twv_unary", 1)?;
        let binary = helper(&mut module, "twv_binary", 2)?;
        let mut sig = module.make_signature();
        let pointer = module.target_config().pointer_type();
        sig.params.extend([
            AbiParam::new(types::F64),
            AbiParam::new(types::F64),
            AbiParam::new(pointer),
        ]);
        let sin_cos_pair = module
            .declare_function("twv_sin_cos_pair", Linkage::Import, &sig)
            .map_err(|e| host(format!("twv_sin_cos_pair: {e}")))?;
        Ok(Self {
            module,
            unary,
            binary,
            sin_cos_pair,
        })
    }

    fn signature(&self, shape: Shape<'_>) -> Signature {
        let pointer = AbiParam::new(self.module.target_config().pointer_type());
        let mut sig = self.module.make_signature();
        match shape {
            Shape::Work => sig.params.extend([pointer; 4]),
            Shape::Dense(_) => {
                sig.params.extend([pointer; 4]);
                sig.params.push(AbiParam::new(types::I64));
            }
            Shape::FJw { .. } => {
                // (x, u, p, w, k, f, out) → trace
                sig.params.extend([pointer; 4]);
                sig.params.push(AbiParam::new(types::I64));
                sig.params.extend([pointer; 2]);
                sig.returns.push(AbiParam::new(types::F64));
            }
        }
        sig
    }

    /// Compiles `function` (of `nx` states) in `shape`: the module, to be kept as long as the
    /// routine is used, and the routine's id in it. `None` if Cranelift refuses it.
    fn compile(
        mut self,
        function: &Function,
        shape: Shape<'_>,
        nx: usize,
    ) -> Option<(JITModule, FuncId)> {
        // Offsets into the slices are 32-bit immediates.
        if function.n_values() > i32::MAX as usize / 8 {
            return None;
        }
        let mut ctx = self.module.make_context();
        ctx.func.signature = self.signature(shape);
        let mut builder_ctx = FunctionBuilderContext::new();
        let mut b = FunctionBuilder::new(&mut ctx.func, &mut builder_ctx);
        let block = b.create_block();
        b.append_block_params_for_function_params(block);
        b.switch_to_block(block);
        b.seal_block(block);
        let params = b.block_params(block).to_vec();
        let helpers = emit::Helpers {
            unary: self.module.declare_func_in_func(self.unary, b.func),
            binary: self.module.declare_func_in_func(self.binary, b.func),
            sin_cos_pair: self.module.declare_func_in_func(self.sin_cos_pair, b.func),
            pointer: self.module.target_config().pointer_type(),
        };
        let args = [params[0], params[1], params[2]];
        let mut sinks: emit::Sinks = vec![Vec::new(); function.n_values()];
        match shape {
            Shape::Work => {
                emit::work_sinks(&mut sinks, function, params[3]);
                emit::values(&mut b, &helpers, function, args, &sinks);
                b.ins().return_(&[]);
            }
            Shape::Dense(output) => {
                let rows = emit::row_pointers(&mut b, params[3], params[4], output.rows);
                emit::dense_sinks(&mut b, &mut sinks, output, &rows);
                emit::values(&mut b, &helpers, function, args, &sinks);
                b.ins().return_(&[]);
            }
            Shape::FJw {
                f,
                jac,
                rows: jw_rows,
                unrolled,
            } => {
                let [w, count, f_out, out] = [3, 4, 5, 6].map(|i| params[i]);
                let one = b.ins().iconst(types::I64, 1);
                let rows = emit::row_pointers(&mut b, f_out, one, f.rows);
                emit::dense_sinks(&mut b, &mut sinks, f, &rows);
                let trace = match unrolled {
                    // A small function: the Jacobian's entries stay values.
                    Some(k) => {
                        let values = emit::values(&mut b, &helpers, function, args, &sinks);
                        let entries: Vec<_> = jac.values.iter().map(|&v| values[v]).collect();
                        emit::jw_unrolled(&mut b, &entries, jw_rows, nx, (w, k, out));
                        emit::trace(&mut b, &entries, jac)
                    }
                    // Any size: they go to a stack array as soon as they exist, and the loop
                    // reads them back.
                    None => {
                        let array = emit::entry_sinks(&mut b, &mut sinks, jac, helpers.pointer);
                        emit::values(&mut b, &helpers, function, args, &sinks);
                        // Only the diagonal is read back for the trace.
                        let unused = b.ins().f64const(0.0);
                        let entries: Vec<_> = (jac.entries().enumerate())
                            .map(|(e, (r, c, _))| {
                                if r == c {
                                    emit::load(&mut b, array, e)
                                } else {
                                    unused
                                }
                            })
                            .collect();
                        let trace = emit::trace(&mut b, &entries, jac);
                        emit::jw_loop(&mut b, array, jw_rows, nx, (w, count, out));
                        trace
                    }
                };
                b.ins().return_(&[trace]);
            }
        }
        b.finalize(self.module.target_config());
        let id = self
            .module
            .declare_function("twv_routine", Linkage::Local, &ctx.func.signature)
            .ok()?;
        self.module.define_function(id, &mut ctx).ok()?;
        self.module.finalize_definitions().ok()?;
        Some((self.module, id))
    }
}

impl JitCode {
    /// The native code of `ir`, compiled as it is used. Fails at once if the code generator
    /// does not support this CPU.
    pub fn new(ir: &Ir) -> Result<Self, JitError> {
        Builder::new(ir, false)?;
        Ok(JitCode {
            ir: ir.clone(),
            functions: ir
                .functions()
                .iter()
                .map(|(name, function)| FunctionCode {
                    name: name.clone(),
                    n_values: function.n_values(),
                    shape: function.output(name).map(|o| (o.rows, o.cols)),
                    work: OnceLock::new(),
                    dense: OnceLock::new(),
                })
                .collect(),
            hot: ["f", "jac_x", "jac_u"].map(|name| ir.functions().keys().position(|n| n == name)),
            f_jw: OnceLock::new(),
            f_jw_unrolled: std::array::from_fn(|_| OnceLock::new()),
            unroll: ir
                .function("f_jac_x")
                .is_some_and(|f| f.n_values() <= SINGLE_PASS_ABOVE),
        })
    }

    /// Compiles function `name` in `shape` into a module of its own; `convert` turns its
    /// address into the routine's type.
    fn compile<E>(
        &self,
        name: &str,
        shape: Shape<'_>,
        convert: unsafe fn(*const u8) -> E,
    ) -> Option<Compiled<E>> {
        let function = self.ir.function(name)?;
        let builder = Builder::new(&self.ir, function.n_values() > SINGLE_PASS_ABOVE).ok()?;
        let (module, id) = builder.compile(function, shape, self.ir.nx())?;
        // SAFETY: the address is the routine just defined with the signature of `E`, the
        // platform's C calling convention (`make_signature`'s default); `convert` only casts.
        let entry = unsafe { convert(module.get_finalized_function(id)) };
        Some(Compiled {
            routine: Routine {
                entry,
                reads: reads(function),
            },
            module: ManuallyDrop::new(module),
        })
    }

    /// The index of function `name`: the hot three without comparing strings of unknown length.
    fn index(&self, name: &str) -> Option<usize> {
        match name {
            "f" => self.hot[0],
            "jac_x" => self.hot[1],
            "jac_u" => self.hot[2],
            _ => self.functions.iter().position(|c| c.name == name),
        }
    }

    /// Whether output `o` of the IR is a column of ẋ's length.
    fn is_state_column(&self, o: &twv_ir::Output) -> bool {
        (o.rows, o.cols) == (self.ir.nx(), 1)
    }

    fn work_routine<'c>(&self, code: &'c FunctionCode) -> Option<&'c Routine<Entry>> {
        let compiled = code
            .work
            .get_or_init(|| self.compile(&code.name, Shape::Work, as_entry));
        compiled.as_ref().map(|c| &c.routine)
    }

    fn dense_routine<'c>(&self, code: &'c FunctionCode) -> Option<&'c Routine<Dense>> {
        let compiled = code.dense.get_or_init(|| {
            let output = self.ir.output(&code.name, &code.name)?;
            self.compile(&code.name, Shape::Dense(output), as_dense)
        });
        compiled.as_ref().map(|c| &c.routine)
    }

    /// The `f_jac_x` routine for `count` tangent vectors: written out for that count where
    /// [`MAX_UNROLLED`] allows and the function is small, else the loop.
    fn f_jw_routine(&self, count: usize) -> Option<&Routine<FJw>> {
        let unrolled = self
            .f_jw_unrolled
            .get(count)
            .filter(|_| self.unroll)
            .and_then(|lazy| lazy.get_or_init(|| self.compile_f_jw(Some(count))).as_ref());
        let compiled = match unrolled {
            Some(c) => Some(c),
            None => self.f_jw.get_or_init(|| self.compile_f_jw(None)).as_ref(),
        };
        compiled.map(|c| &c.routine)
    }

    fn compile_f_jw(&self, unrolled: Option<usize>) -> Option<Compiled<FJw>> {
        let f = self
            .ir
            .output("f_jac_x", "f")
            .filter(|f| self.is_state_column(f))?;
        let jac = self.ir.output("f_jac_x", "jac_x")?;
        let rows = jac.stored_rows();
        let shape = Shape::FJw {
            f,
            jac,
            rows: &rows,
            unrolled,
        };
        self.compile("f_jac_x", shape, as_f_jw)
    }
}

/// # Safety
/// `address` must be a routine with the signature of [`Entry`].
unsafe fn as_entry(address: *const u8) -> Entry {
    // SAFETY: the caller's.
    unsafe { std::mem::transmute::<*const u8, Entry>(address) }
}

/// # Safety
/// `address` must be a routine with the signature of [`Dense`].
unsafe fn as_dense(address: *const u8) -> Dense {
    // SAFETY: the caller's.
    unsafe { std::mem::transmute::<*const u8, Dense>(address) }
}

/// # Safety
/// `address` must be a routine with the signature of [`FJw`].
unsafe fn as_f_jw(address: *const u8) -> FJw {
    // SAFETY: the caller's.
    unsafe { std::mem::transmute::<*const u8, FJw>(address) }
}

impl NativeCode for JitCode {
    fn ir_hash(&self) -> &str {
        self.ir.hash()
    }

    fn eval(&self, function: &str, x: &[f64], u: &[f64], p: &[f64], work: &mut [f64]) -> bool {
        let Some(code) = self.index(function).map(|i| &self.functions[i]) else {
            return false;
        };
        let Some(routine) = self.work_routine(code) else {
            return false;
        };
        if !routine.reads_within(x, u, p) || work.len() < code.n_values {
            return false;
        }
        // SAFETY: the routine reads x, u, p within `reads` and writes work[..n_values] (the
        // offsets it was compiled with), all within the slices, checked just above.
        unsafe { (routine.entry)(x.as_ptr(), u.as_ptr(), p.as_ptr(), work.as_mut_ptr()) };
        true
    }

    fn dense(
        &self,
        function: &str,
        (x, u, p): (&[f64], &[f64], &[f64]),
        (rows, cols, stride): (usize, usize, usize),
        out: &mut [f64],
    ) -> bool {
        let Some(code) = self.index(function).map(|i| &self.functions[i]) else {
            return false;
        };
        let fits = code.shape == Some((rows, cols)) && cols <= stride && out.len() == rows * stride;
        let Some(routine) = self.dense_routine(code).filter(|_| fits) else {
            return false;
        };
        if !routine.reads_within(x, u, p) {
            return false;
        }
        // SAFETY: reads within the checked extents; writes out[r·stride + c] for r < rows and
        // c < cols ≤ stride, within `out` (rows·stride long).
        unsafe { (routine.entry)(x.as_ptr(), u.as_ptr(), p.as_ptr(), out.as_mut_ptr(), stride) };
        true
    }

    fn f_jw(
        &self,
        (x, u, p): (&[f64], &[f64], &[f64]),
        (w, count): (&[f64], usize),
        f: &mut [f64],
        out: &mut [f64],
    ) -> Option<f64> {
        let routine = self.f_jw_routine(count)?;
        let nx = self.ir.nx();
        let fits = w.len() == count * nx && out.len() == w.len() && f.len() >= nx;
        if !routine.reads_within(x, u, p) || !fits {
            return None;
        }
        // SAFETY: reads x, u, p within the checked extents and w[..count·nx]; writes f[..nx]
        // and out[..count·nx], all within the slices.
        let trace = unsafe {
            (routine.entry)(
                x.as_ptr(),
                u.as_ptr(),
                p.as_ptr(),
                w.as_ptr(),
                count,
                f.as_mut_ptr(),
                out.as_mut_ptr(),
            )
        };
        Some(trace)
    }
}
