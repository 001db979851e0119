//! The twv model IR, format `twv-ir/1` (generated/ir/README.md is the specification).
//!
//! - [`load_ir`] / [`parse_ir`]: read and validate a file into an [`Ir`]; every problem is an
//!   [`IrError`] naming the file and the problem, never a panic.
//! - [`load_params`] / [`parse_params`]: a TOML parameter file into values in the IR's order,
//!   validated by each parameter's kind ([`ParamError`]).
//! - [`Function::eval`] and [`Interpreted`]: the interpreter, bit-identical to the generated code.
//! - [`Bundle`]: an IR with its parameter values, as an exported library carries it.

mod bundle;
mod consistency;
mod error;
mod hash;
mod infix;
mod interp;
mod lower;
mod native;
pub mod ops;
mod params;
mod types;
mod unique_keys;
mod validate;

pub use bundle::{
    Bundle, BundleError, ValueReferences, Variable, BUNDLE_FORMAT, FMU_RESOURCE, MAX_BUNDLE_BYTES,
    TRAILER_MAGIC,
};
pub use error::{
    InstrProblem, IrError, ModelError, OutputProblem, ParamError, ParamProblem, Problem,
    WorkTooShort,
};
pub use hash::{content_hash, rehash, sha256_hex, sha256_hex_bytes, HASH_PLACEHOLDER};
pub use infix::{formulas, Formulas};
pub use interp::{visit_interpreted, Interpreted, UnsupportedSize, VisitError, MAX_NU, MAX_NX};
pub use native::NativeCode;
pub use ops::{BinaryOp, UnaryOp};
pub use params::{check_values, load_params, parse_params, parse_uncertainty, UNCERTAINTY};
pub use types::{
    Arg, Function, Golden, Instr, Ir, Kind, Mechanics, Output, Param, ParamKind, Signal,
    SteadyMotion, FORMAT,
};
pub use validate::{load_ir, parse_ir, MECHANICAL_FUNCTIONS, REQUIRED_FUNCTIONS};

impl Ir {
    /// Read the parameter file at `path` for this model.
    pub fn load_params(&self, path: impl AsRef<std::path::Path>) -> Result<Vec<f64>, ParamError> {
        load_params(path, &self.params)
    }
}
