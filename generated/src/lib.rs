//! Every shipped twv model, generated at compile time from `generated/ir/*.json` by the
//! `twv_model!` proc-macro (one emitter: twv-emit).
//!
//! - Runtime parameters: [`Vehicle8`], [`Vehicle7`], [`Segway7`], [`Lorenz`], [`HenonHeiles`]
//!   (`new(values)`, `with_defaults()`, consts `NX`, `NU`, `NP`, `NS`, `PARAMS`, `DEFAULTS`).
//! - Parameters folded as constants: the crate `twv-baked` beside this one (tests and bench).
//! - The IR text of each model ([`ir_json`], [`MODELS`]) so a binary can embed it, and of the
//!   shipped models that run on the interpreter ([`INTERPRETED`]: the Whipple bicycle).
//! - [`visit`]: dispatch a model name to its concrete type without trait objects.
//!
//! Without its default feature `std` the crate is `no_std` (the generated kernels need only
//! `core`): what firmware links (`twv-firmware`); `visit` and its error, which name models in
//! allocated text, come with `std`.
#![cfg_attr(not(feature = "std"), no_std)]

twv_macros::twv_model!(ir = "ir/vehicle8.json", name = Vehicle8);
twv_macros::twv_model!(ir = "ir/vehicle7.json", name = Vehicle7);
twv_macros::twv_model!(ir = "ir/segway7.json", name = Segway7);
twv_macros::twv_model!(ir = "ir/lorenz.json", name = Lorenz);
twv_macros::twv_model!(ir = "ir/henon_heiles.json", name = HenonHeiles);

/// (model name, IR file text) of every shipped model, in the order of docs/src/models.md.
pub const MODELS: [(&str, &str); 5] = [
    ("vehicle8", include_str!("../ir/vehicle8.json")),
    ("vehicle7", include_str!("../ir/vehicle7.json")),
    ("segway7", include_str!("../ir/segway7.json")),
    ("lorenz", include_str!("../ir/lorenz.json")),
    ("henon_heiles", include_str!("../ir/henon_heiles.json")),
];

/// (model name, IR file text) of the shipped models that run on the IR interpreter instead of
/// generated code: their Jacobians are too large to be worth compiling twice (the Whipple
/// bicycle's ∂f/∂x has 33k operations); the interpreter gives the generated code's bits.
pub const INTERPRETED: [(&str, &str); 1] = [("whipple", include_str!("../ir/whipple.json"))];

/// The IR text of a shipped model with generated code.
pub fn ir_json(name: &str) -> Option<&'static str> {
    MODELS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, text)| *text)
}

/// The IR text of any shipped model, with generated code or on the interpreter.
pub fn shipped_ir_json(name: &str) -> Option<&'static str> {
    MODELS
        .iter()
        .chain(&INTERPRETED)
        .find(|(n, _)| *n == name)
        .map(|(_, text)| *text)
}

/// What [`visit`] runs (the trait lives in twv-model so the IR interpreter's dispatch shares it).
pub use twv_model::ModelVisitor as Visitor;

/// A name that is not a shipped model, or parameter values of the wrong count.
#[cfg(feature = "std")]
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum VisitError {
    /// Not a shipped model; the known names are in [`MODELS`].
    UnknownModel(String),
    /// `params` has `given` values, the model has `expected`.
    ParamCount { expected: usize, given: usize },
}

#[cfg(feature = "std")]
impl core::fmt::Display for VisitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            VisitError::UnknownModel(name) => {
                let known: Vec<&str> = MODELS.iter().map(|(n, _)| *n).collect();
                write!(f, "unknown model `{name}` (known: {})", known.join(", "))
            }
            VisitError::ParamCount { expected, given } => {
                write!(
                    f,
                    "{given} parameter values given, the model has {expected}"
                )
            }
        }
    }
}

#[cfg(feature = "std")]
impl std::error::Error for VisitError {}

#[cfg(feature = "std")]
fn values<const NP: usize>(
    params: Option<&[f64]>,
    defaults: [f64; NP],
) -> Result<[f64; NP], VisitError> {
    match params {
        None => Ok(defaults),
        Some(p) => p.try_into().map_err(|_| VisitError::ParamCount {
            expected: NP,
            given: p.len(),
        }),
    }
}

/// The IR hashes of the models with generated code, with their names.
pub const GENERATED_HASHES: [(&str, &str); 5] = [
    (Vehicle8::NAME, Vehicle8::IR_HASH),
    (Vehicle7::NAME, Vehicle7::IR_HASH),
    (Segway7::NAME, Segway7::IR_HASH),
    (Lorenz::NAME, Lorenz::IR_HASH),
    (HenonHeiles::NAME, HenonHeiles::IR_HASH),
];

/// Whether an IR of this hash has generated code here (the same equations as a shipped model).
pub fn is_generated(ir_hash: &str) -> bool {
    GENERATED_HASHES.iter().any(|(_, h)| *h == ir_hash)
}

#[cfg(feature = "std")]
/// Run `visitor` on the runtime-parameter model called `name`, with `params` (IR order; validate
/// them first, e.g. with `twv_ir::load_params`) or the IR defaults.
pub fn visit<V: Visitor>(
    name: &str,
    params: Option<&[f64]>,
    visitor: V,
) -> Result<V::Output, VisitError> {
    Ok(match name {
        "vehicle8" => visitor.visit(Vehicle8::new(values(params, Vehicle8::DEFAULTS)?)),
        "vehicle7" => visitor.visit(Vehicle7::new(values(params, Vehicle7::DEFAULTS)?)),
        "segway7" => visitor.visit(Segway7::new(values(params, Segway7::DEFAULTS)?)),
        "lorenz" => visitor.visit(Lorenz::new(values(params, Lorenz::DEFAULTS)?)),
        "henon_heiles" => visitor.visit(HenonHeiles::new(values(params, HenonHeiles::DEFAULTS)?)),
        other => return Err(VisitError::UnknownModel(other.to_string())),
    })
}
