//! The seam for native code compiled from an IR at run time (the `twv-jit` crate): an
//! [`Interpreted`](crate::Interpreted) model given a [`NativeCode`] runs a function through it
//! instead of through [`Function::eval`](crate::Function::eval), and reads the outputs exactly
//! as before. The compiler lives outside this crate so that the IR, its validator and the
//! interpreter (the reference) do not carry a code generator.

use std::fmt::Debug;

/// Native code for the functions of one IR, with the interpreter's bits: the same operations
/// in the same order on the same values.
pub trait NativeCode: Send + Sync + Debug {
    /// The content hash of the IR the code was compiled from ([`Ir::hash`](crate::Ir::hash)).
    fn ir_hash(&self) -> &str;

    /// Evaluates `function` at (x, u, p), writing at least every value its outputs read into
    /// `work[value id]`. False, with `work` untouched, when there is no code for `function` or
    /// a slice is shorter than the function reads; the interpreter then runs instead.
    fn eval(&self, function: &str, x: &[f64], u: &[f64], p: &[f64], work: &mut [f64]) -> bool;

    /// Output `function` of function `function` (`f`, `jac_x`, `jac_u`, `M`, …) at (x, u, p),
    /// dense and row-major into `out`: with `shape` = (rows, cols, stride), entry (r, c) at
    /// `r·stride + c`, 0.0 where the output stores none; columns from cols up to the stride are
    /// left as they are. False, with `out` untouched, when there is no such code, the output is
    /// not rows × cols, or a slice does not fit.
    fn dense(
        &self,
        function: &str,
        xup: (&[f64], &[f64], &[f64]),
        shape: (usize, usize, usize),
        out: &mut [f64],
    ) -> bool;

    /// From function `f_jac_x` at (x, u, p): ẋ into `f` (dense), `out[k·nx..(k+1)·nx] =
    /// (∂f/∂x)·w[k·nx..]` for the `count` tangent vectors in `w` (the interpreter's J·W: column
    /// by column, structural zeros as 0.0), and returns tr(∂f/∂x) as the generated code sums it
    /// (0.0 plus the stored diagonal entries in order). `None`, with nothing written, when
    /// there is no such code or a slice does not fit.
    fn f_jw(
        &self,
        xup: (&[f64], &[f64], &[f64]),
        w: (&[f64], usize),
        f: &mut [f64],
        out: &mut [f64],
    ) -> Option<f64>;
}
