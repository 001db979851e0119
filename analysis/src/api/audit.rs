//! The generated vehicle models against the independent hand model: `twv audit`.

use std::path::PathBuf;

use twv_ir::Ir;

use crate::audit::{audit, AuditReport, AuditSettings};
use crate::error::{Error, Result};
use crate::hand_file::{audit_hand_model, read_hand_file, HandAuditReport, HandAuditSettings};
use crate::hand_model::{HandSegway7, HandVehicle7, HandVehicle8, VehicleParams, PARAM_NAMES};
use crate::model::{Engine, ResolvedModel};

/// The vehicles the hand model covers.
pub const AUDITED: [&str; 3] = ["vehicle8", "vehicle7", "segway7"];

/// The most random samples an audit takes (each costs a few hand-model evaluations).
pub const MAX_SAMPLES: usize = 1_000_000;

impl AuditSettings {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<()> {
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(Error::input(
                "tolerance",
                format!("{} must be finite and > 0", self.tolerance),
            ));
        }
        if self.samples > MAX_SAMPLES {
            return Err(Error::input(
                "samples",
                format!("{} is more than {MAX_SAMPLES}", self.samples),
            ));
        }
        if !(self.input_scale.is_finite() && self.input_scale >= 0.0) {
            return Err(Error::input(
                "input_scale",
                format!("{} must be finite and ≥ 0", self.input_scale),
            ));
        }
        if self.simulations > 100 {
            return Err(Error::input(
                "simulations",
                format!("{} is more than 100", self.simulations),
            ));
        }
        Ok(())
    }
}

fn vehicle_params(ir: &Ir, values: &[f64]) -> Result<VehicleParams> {
    let mut array = [0.0; 16];
    for (slot, name) in array.iter_mut().zip(PARAM_NAMES) {
        let i = ir
            .params()
            .iter()
            .position(|p| p.name == name)
            .ok_or_else(|| Error::Unsupported {
                model: ir.model().to_string(),
                reason: format!("no parameter {name} for the hand model"),
            })?;
        *slot = values[i];
    }
    Ok(VehicleParams::from_array(array))
}

/// Parameter values in the IR's order from the hand model's struct.
fn reorder(ir: &Ir, p: &VehicleParams) -> [f64; 16] {
    let array = p.to_array();
    let mut out = [0.0; 16];
    for (slot, param) in out.iter_mut().zip(ir.params()) {
        if let Some(i) = PARAM_NAMES.iter().position(|n| *n == param.name) {
            *slot = array[i];
        }
    }
    out
}

/// Audits a shipped vehicle (generated code) against the hand model with its parameters.
pub fn audit_model(model: &ResolvedModel, settings: &AuditSettings) -> Result<AuditReport> {
    settings.validate()?;
    let name = match &model.engine {
        Engine::Generated(name) if AUDITED.contains(&name.as_str()) => name.as_str(),
        _ => {
            return Err(Error::Unsupported {
                model: model.name().to_string(),
                reason: format!(
                    "the hand model covers the shipped {} only",
                    AUDITED.join(", ")
                ),
            })
        }
    };
    let ir = &model.ir;
    let p = vehicle_params(ir, &model.params)?;
    let values = |q: &VehicleParams| reorder(ir, q);
    Ok(match name {
        "vehicle8" => audit(
            &p,
            |q| twv_generated::Vehicle8::new(values(q)),
            &HandVehicle8::new(p),
            false,
            settings,
        ),
        "vehicle7" => audit(
            &p,
            |q| twv_generated::Vehicle7::new(values(q)),
            &HandVehicle7::new(p),
            false,
            settings,
        ),
        _ => audit(
            &p,
            |q| twv_generated::Segway7::new(values(q)),
            &HandSegway7::new(p),
            true,
            settings,
        ),
    })
}

/// Where a user's hand model comes from.
#[derive(Debug, Clone, PartialEq)]
pub enum HandSource {
    /// A hand file (TOML, README "Your own hand model").
    File(PathBuf),
    /// Its text, with the name messages use for it.
    Text {
        /// The TOML document.
        text: String,
        /// Its name in messages and reports.
        origin: String,
    },
}

/// The largest hand file read (a hand model is a page of formulas, not megabytes).
pub const MAX_HAND_FILE_BYTES: u64 = 1 << 20;

impl HandSource {
    /// The text and its name.
    pub fn read(&self) -> Result<(String, String)> {
        match self {
            HandSource::Text { text, origin } => {
                if text.len() as u64 > MAX_HAND_FILE_BYTES {
                    return Err(Error::input(
                        "hand",
                        format!(
                            "{origin}: {} bytes is more than a hand file's {MAX_HAND_FILE_BYTES}",
                            text.len()
                        ),
                    ));
                }
                Ok((text.clone(), origin.clone()))
            }
            HandSource::File(path) => {
                let read_error = |reason: String| Error::Read {
                    path: path.clone(),
                    reason,
                };
                let size = std::fs::metadata(path)
                    .map_err(|e| read_error(e.to_string()))?
                    .len();
                if size > MAX_HAND_FILE_BYTES {
                    return Err(read_error(format!(
                        "{size} bytes is more than a hand file's {MAX_HAND_FILE_BYTES}"
                    )));
                }
                let text = std::fs::read_to_string(path).map_err(|e| read_error(e.to_string()))?;
                Ok((text, path.display().to_string()))
            }
        }
    }
}

/// Audits a user's hand model against the model's derivation (any shipped model or IR, its
/// parameters as resolved), term by term: see [`crate::hand_file`].
pub fn audit_hand(
    model: &ResolvedModel,
    hand: &HandSource,
    settings: &HandAuditSettings,
) -> Result<HandAuditReport> {
    let (text, origin) = hand.read()?;
    let hand = read_hand_file(&text, &origin, &model.ir)?;
    audit_hand_model(&model.ir, &model.params, &hand, settings)
}

/// The JSON job `audit_hand`: a hand file's text with the audit's settings (the Python package
/// reads the file and sends this).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HandAuditJob {
    /// The hand file's TOML text.
    pub hand: String,
    /// Its name in messages and the report. Default `hand file`.
    #[serde(default = "default_origin")]
    pub origin: String,
    /// Samples, seed, tolerance, parameter spread. Default [`HandAuditSettings::default`].
    #[serde(default)]
    pub audit: HandAuditSettings,
}

fn default_origin() -> String {
    "hand file".into()
}

impl HandAuditJob {
    /// Runs the job on `model`.
    pub fn run(self, model: &ResolvedModel) -> Result<HandAuditReport> {
        let source = HandSource::Text {
            text: self.hand,
            origin: self.origin,
        };
        audit_hand(model, &source, &self.audit)
    }
}
