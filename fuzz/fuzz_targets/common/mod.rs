//! What the fuzz targets share: the model they read against, resolved once per process.

use std::sync::OnceLock;

use twv_analysis::model::{ModelSpec, ResolvedModel};

/// The study's vehicle with its default parameters.
pub fn vehicle8() -> &'static ResolvedModel {
    static MODEL: OnceLock<ResolvedModel> = OnceLock::new();
    MODEL.get_or_init(|| ModelSpec::shipped("vehicle8").resolve().expect("vehicle8"))
}
