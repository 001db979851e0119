//! A user's own hand model — a short TOML file of closed-form formulas in the model's own state,
//! input and parameter names — audited term by term against the derivation (`twv audit --hand`).
//!
//! - [`file`]: the format (README "Your own hand model") and its one-line errors;
//! - [`parse`] and [`expr`]: one formula, evaluated for values and exact derivatives;
//! - [`normal`] and [`from_ir`]: canonical forms, so a disagreement prints as the missing term;
//! - [`audit`]: the comparison and its report; `linear`: the same for the equations
//!   linearised about a steady motion (the bicycle benchmark's M, C1, K0, K2).
//!
//! The built-in hand model of the shipped vehicles ([`crate::hand_model`]) is Rust code; this is
//! the same audit for a model the user derived, of any shipped or IR vehicle.

pub mod audit;
pub mod expr;
pub mod file;
mod from_ir;
mod linear;
pub mod normal;
pub mod parse;

pub use audit::{audit_hand_model, Disagreement, HandAuditReport, HandAuditSettings};
pub use file::{model_named_in, read_hand_file, HandFileError, HandForm, HandModel};
