//! `evaluate`: ẋ = f(x, u) and, if asked, ∂f/∂x and ∂f/∂u at one point.

use super::options::{field, flag, optional_vector, vector, Opt};
use super::{Job, JobOutput};
use crate::api::{evaluate, EvalResult, EvalSettings};
use crate::error::{Error, Result};
use crate::model::ResolvedModel;
use crate::progress::Progress;

/// One evaluation of the model's functions.
pub struct Evaluate;

impl Job for Evaluate {
    const NAME: &'static str = "evaluate";
    const ALIASES: &'static [&'static str] = &["eval"];
    const SUMMARY: &'static str =
        "Evaluate ẋ = f(x, u) (and its Jacobians) at one state; JSON on stdout";
    type Settings = EvalSettings;
    type Output = EvalResult;

    fn options() -> Vec<Opt<EvalSettings>> {
        vec![
            vector(
                "x",
                "SI, rad",
                "State, in the model's state order",
                field(|s: &mut EvalSettings| &mut s.x),
            )
            .required(),
            optional_vector(
                "u",
                "N, N m",
                "Input, in the model's input order (none: zeros)",
                field(|s: &mut EvalSettings| &mut s.u),
            ),
            flag(
                "jacobians",
                "Also give jac_x = ∂f/∂x and jac_u = ∂f/∂u (one row per state)",
                field(|s: &mut EvalSettings| &mut s.jacobians),
            )
            .aliases(&["jac"]),
        ]
    }

    fn validate(_s: &EvalSettings) -> Result<()> {
        Ok(())
    }

    fn run(model: &ResolvedModel, s: &EvalSettings, _p: &dyn Progress) -> Result<EvalResult> {
        if s.x.is_empty() {
            return Err(Error::input("x", "evaluate needs the state"));
        }
        evaluate(model, s)
    }
}

impl JobOutput for EvalResult {
    /// The values as compact JSON, one line (what `twv evaluate` has always printed).
    fn summary(&self) -> String {
        serde_json::to_string(self).unwrap_or_default() + "\n"
    }
}
