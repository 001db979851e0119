//! A model for other people's tools: an FMI 2.0 FMU (model exchange and co-simulation in one
//! archive, [`fmu`]) or a CasADi external function ([`casadi`]). Both are the export runtime
//! (the shared library of the crate `twv-export`, built beside `twv`) with the model: an FMU
//! carries it in `resources/bundle.json`, a CasADi library at the end of its file.

pub mod casadi;
pub mod fmu;
mod xml;

use std::path::PathBuf;

use serde::{Deserialize, Serialize};
use twv_ir::Bundle;

use crate::error::{Error, Result};
use crate::model::ResolvedModel;

/// The file name of the export runtime.
pub const RUNTIME_FILE: &str = "libtwv_export.so";

/// The environment variable that names the export runtime when it is not beside the program.
pub const RUNTIME_VARIABLE: &str = "TWV_EXPORT_RUNTIME";

/// What to export.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ExportFormat {
    /// An FMI 2.0 FMU, model exchange and co-simulation.
    #[default]
    Fmu,
    /// A CasADi external function (`f` and `jac_f`).
    Casadi,
}

impl ExportFormat {
    /// Its name in settings.
    pub fn name(self) -> &'static str {
        match self {
            ExportFormat::Fmu => "fmu",
            ExportFormat::Casadi => "casadi",
        }
    }
}

/// How to export. Defaults: an FMU with the parameters fixed at the model's values, RK4 steps
/// of at most 1 ms in co-simulation, the identifier `twv_<model>`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ExportSettings {
    /// FMU or CasADi library.
    pub format: ExportFormat,
    /// Parameters as tunable FMU variables (causality parameter) instead of fixed at the
    /// exported values. FMUs only: the IR has no ∂f/∂p that a CasADi input `p` would need.
    pub tunable: bool,
    /// The largest RK4 step of one co-simulation step (`fmi2DoStep`) [s].
    pub rk4_step: f64,
    /// The stop time of the FMU's default experiment [s].
    pub stop_time: f64,
    /// The model identifier (file names, FMI `modelIdentifier`); `None`: `twv_<model>`.
    pub name: Option<String>,
}

impl Default for ExportSettings {
    fn default() -> Self {
        Self {
            format: ExportFormat::Fmu,
            tunable: false,
            rk4_step: 1e-3,
            stop_time: 10.0,
            name: None,
        }
    }
}

impl ExportSettings {
    /// Checks every setting; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        if !(self.rk4_step.is_finite() && self.rk4_step > 0.0 && self.rk4_step <= 1e3) {
            return Err(Error::input(
                "rk4_step",
                format!("{}: not a step size in (0, 1000] s", self.rk4_step),
            ));
        }
        if !(self.stop_time.is_finite() && self.stop_time > 0.0) {
            return Err(Error::input(
                "stop_time",
                format!("{}: not a time > 0", self.stop_time),
            ));
        }
        if self.tunable && self.format == ExportFormat::Casadi {
            return Err(Error::input(
                "tunable",
                "a CasADi export has its parameters fixed (the IR has no ∂f/∂p for a `p` input); \
                 export other values with --params FILE",
            ));
        }
        if let Some(name) = &self.name {
            check_identifier(name)?;
        }
        Ok(())
    }
}

/// An identifier is a C identifier of at most 64 characters: it names files and symbols.
fn check_identifier(name: &str) -> Result<()> {
    let mut chars = name.chars();
    let first_ok = chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_');
    if !first_ok || name.len() > 64 || !chars.all(|c| c.is_ascii_alphanumeric() || c == '_') {
        return Err(Error::input(
            "name",
            format!(
                "{name:?} is not an identifier (letters, digits and _, not starting with a digit, \
                 at most 64)"
            ),
        ));
    }
    Ok(())
}

/// The model identifier of an export: the settings' name or `twv_<model>` (characters that are
/// not letters, digits or `_` become `_`).
pub fn identifier(model: &ResolvedModel, settings: &ExportSettings) -> String {
    settings.name.clone().unwrap_or_else(|| {
        let clean: String = model
            .name()
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        format!("twv_{clean}")
    })
}

/// The model and its values as the runtime reads them.
pub fn bundle(model: &ResolvedModel, settings: &ExportSettings) -> Result<Bundle> {
    let text = model.ir_text.as_deref().ok_or_else(|| {
        Error::input(
            "model",
            format!(
                "{}: an IR built in memory cannot be exported; write it to a file and pass --ir",
                model.origin
            ),
        )
    })?;
    Bundle::new(
        text,
        model.params.clone(),
        &model.params_origin,
        settings.rk4_step,
        settings.tunable,
    )
    .map_err(|e| Error::input("model", e.to_string()))
}

/// Where the export runtime is: `$TWV_EXPORT_RUNTIME`, or beside the running program (and its
/// parent folder, where a test binary's `deps/` sits below it).
pub fn runtime_path() -> Result<PathBuf> {
    if let Some(path) = std::env::var_os(RUNTIME_VARIABLE) {
        let path = PathBuf::from(path);
        return if path.is_file() {
            Ok(path)
        } else {
            Err(Error::input(
                RUNTIME_VARIABLE,
                format!("{} is not a file", path.display()),
            ))
        };
    }
    let exe = std::env::current_exe().ok();
    let dirs: Vec<PathBuf> = exe
        .iter()
        .filter_map(|e| e.parent())
        .flat_map(|d| [Some(d.to_path_buf()), d.parent().map(PathBuf::from)])
        .flatten()
        .collect();
    dirs.iter()
        .map(|d| d.join(RUNTIME_FILE))
        .find(|p| p.is_file())
        .ok_or_else(|| {
            Error::input(
                "runtime",
                format!(
                    "the export runtime {RUNTIME_FILE} is not beside {} (build it with `cargo \
                     build --release -p twv-export`, or name it in ${RUNTIME_VARIABLE})",
                    exe.map_or("this program".into(), |e| e.display().to_string())
                ),
            )
        })
}

/// The bytes of the export runtime, refusing what is not a 64-bit Linux shared library.
pub fn runtime() -> Result<Vec<u8>> {
    if !cfg!(all(target_os = "linux", target_pointer_width = "64")) {
        return Err(Error::input(
            "format",
            "exports are built for 64-bit Linux (binaries/linux64); this twv runs elsewhere",
        ));
    }
    let path = runtime_path()?;
    let bytes = std::fs::read(&path)
        .map_err(|e| Error::input("runtime", format!("cannot read {}: {e}", path.display())))?;
    if !bytes.starts_with(b"\x7fELF\x02") {
        return Err(Error::input(
            "runtime",
            format!("{} is not a 64-bit ELF shared library", path.display()),
        ));
    }
    Ok(bytes)
}
