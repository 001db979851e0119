//! `codegen`: the Rust the emitter produces for a model, formatted for people to audit.

use serde::Serialize;
use serde_json::json;

use super::options::{field, flag, is_none, Kind, Opt};
use super::{Job, JobOutput};
use crate::api::{generate, CodegenSettings};
use crate::error::Result;
use crate::model::ResolvedModel;
use crate::progress::Progress;

/// The generated code of a model.
pub struct Codegen;

/// The source of one model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GeneratedCode {
    /// Model name.
    pub model: String,
    /// The Rust source (prettyplease-formatted).
    pub source: String,
}

impl Job for Codegen {
    const NAME: &'static str = "codegen";
    const SUMMARY: &'static str =
        "Print the Rust code generated from a model's IR, for people to read and audit";
    const SERVED: bool = false;
    type Settings = CodegenSettings;
    type Output = GeneratedCode;

    fn options() -> Vec<Opt<CodegenSettings>> {
        vec![
            Opt::new(
                "name",
                Kind::Text,
                "",
                "Name of the emitted struct (none: the model name in CamelCase)",
                |s: &mut CodegenSettings, v| {
                    s.name = if is_none(v) {
                        None
                    } else {
                        Some(super::options::as_text("name", v)?.to_string())
                    };
                    Ok(())
                },
                |s| json!(s.name),
            ),
            flag(
                "baked",
                "Fold the parameter values into the code as constants",
                field(|s: &mut CodegenSettings| &mut s.baked),
            ),
        ]
    }

    fn validate(_s: &CodegenSettings) -> Result<()> {
        Ok(())
    }

    fn run(model: &ResolvedModel, s: &CodegenSettings, _p: &dyn Progress) -> Result<GeneratedCode> {
        Ok(GeneratedCode {
            model: model.name().to_string(),
            source: generate(model, s)?,
        })
    }
}

impl JobOutput for GeneratedCode {
    fn summary(&self) -> String {
        self.source.clone()
    }
}
