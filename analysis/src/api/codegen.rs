//! The Rust the emitter produces for a model, formatted for people to read: `twv codegen`.

use twv_emit::{format_model, Options, Params};

use crate::error::Result;
use crate::model::ResolvedModel;

/// How to emit. Defaults: the model's name in CamelCase, parameters at run time.
#[derive(Debug, Clone, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CodegenSettings {
    /// Name of the emitted struct; `None`: the model name in CamelCase.
    pub name: Option<String>,
    /// Fold the resolved parameter values into the code as constants.
    pub baked: bool,
}

/// `vehicle_8` → `Vehicle8`.
pub fn camel(name: &str) -> String {
    name.split('_')
        .map(|w| {
            let mut c = w.chars();
            c.next()
                .map(|f| f.to_ascii_uppercase().to_string() + c.as_str())
                .unwrap_or_default()
        })
        .collect()
}

/// The generated Rust source of the model (prettyplease-formatted).
pub fn generate(model: &ResolvedModel, settings: &CodegenSettings) -> Result<String> {
    let params = if settings.baked {
        Params::Baked {
            values: model.params.clone(),
            source: model.params_origin.clone(),
        }
    } else {
        Params::Runtime
    };
    let name = settings.name.clone().unwrap_or_else(|| camel(model.name()));
    Ok(format_model(&model.ir, &Options { name, params })?)
}
