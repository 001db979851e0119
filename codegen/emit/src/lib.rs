//! The one emitter: a validated model IR ([`twv_ir::Ir`]) to Rust tokens implementing
//! [`twv_model::Model`] (and `Mechanical` for multibody models). Both the `twv_model!` proc-macro
//! and `twv codegen` (through [`format_model`]) use it, so there is one code path from IR to Rust.
//!
//! Emitted code: one `let` per IR instruction (SSA, in IR order, so the operations and their
//! order are CasADi's and the interpreter's), fixed-size arrays, no heap, no panics, only the
//! structural non-zeros of ∂f/∂x, and J·W by the columns that have entries. Every kernel is
//! built for the x86-64 baseline and for AVX-512, picked at run time (`twv_kernels::isa`). It
//! depends on `twv_model` only.

mod body;
mod model;

use proc_macro2::TokenStream;
use thiserror::Error;
use twv_ir::{check_values, Ir, ParamError};

pub use model::op_counts;

/// Where the emitted model takes its parameter values from.
#[derive(Debug, Clone, PartialEq)]
pub enum Params {
    /// A field `[f64; NP]` set at run time (`new(values)`, `with_defaults()`).
    Runtime,
    /// Folded as constants: `values` in IR order, read from `source` (shown in the header).
    Baked { values: Vec<f64>, source: String },
}

/// What to emit.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Name of the emitted struct (a Rust identifier, e.g. `Vehicle8`).
    pub name: String,
    /// Runtime or baked parameters.
    pub params: Params,
}

/// Why a model could not be emitted.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum EmitError {
    #[error("`{0}` is not a valid Rust identifier for the model struct")]
    Name(String),
    #[error(transparent)]
    Params(#[from] ParamError),
    #[error("{file}: {message}")]
    Ir { file: String, message: String },
    #[error("emitted code does not parse (a bug in twv-emit): {0}")]
    Format(String),
}

/// The model of `ir` as Rust tokens.
pub fn emit_model(ir: &Ir, options: &Options) -> Result<TokenStream, EmitError> {
    let name: syn::Ident =
        syn::parse_str(&options.name).map_err(|_| EmitError::Name(options.name.clone()))?;
    if let Params::Baked { values, source } = &options.params {
        check_values(values, source, ir.params())?;
    }
    model::emit(ir, &name, &options.params)
}

/// The model of `ir` as formatted Rust source (prettyplease), for people to read and audit.
pub fn format_model(ir: &Ir, options: &Options) -> Result<String, EmitError> {
    let tokens = emit_model(ir, options)?;
    let file: syn::File = syn::parse2(tokens).map_err(|e| EmitError::Format(e.to_string()))?;
    Ok(prettyplease::unparse(&file))
}
