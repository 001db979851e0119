//! The generated vehicle models against the independent hand model: `twv audit`.

use twv_ir::Ir;

use crate::audit::{audit, AuditReport, AuditSettings};
use crate::error::{Error, Result};
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
