//! `twv audit`: the generated vehicle models against the independent hand model.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use twv_ir::Ir;

use super::model::ModelArgs;
use crate::audit::{audit, AuditReport, AuditSettings};
use crate::hand_model::{HandSegway7, HandVehicle7, HandVehicle8, VehicleParams};

/// Audit the derived (generated) model term by term against the hand model, plus physical checks.
#[derive(Args, Debug)]
pub struct AuditArgs {
    /// vehicle8, vehicle7, segway7 or all
    #[arg(long, value_name = "NAME", default_value = "all")]
    pub model: String,
    /// Parameter file (TOML) [default: each model's defaults]
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
    /// Random samples (states and inputs) besides the upright and hanging rest states
    #[arg(long, value_name = "N", default_value_t = 200)]
    pub samples: usize,
    /// Seed of the samples
    #[arg(long, value_name = "S", default_value_t = 2016)]
    pub seed: u64,
    /// Largest accepted normwise relative error of a term
    #[arg(long, value_name = "REL", default_value_t = 1e-11)]
    pub tolerance: f64,
    /// Print JSON instead of the table
    #[arg(long)]
    pub json: bool,
}

const VEHICLES: [&str; 3] = ["vehicle8", "vehicle7", "segway7"];

fn vehicle_params(ir: &Ir, values: &[f64]) -> Result<VehicleParams> {
    let by_name = |n: &str| {
        ir.params()
            .iter()
            .position(|p| p.name == n)
            .map(|i| values[i])
    };
    let mut array = [0.0; 16];
    for (slot, name) in array.iter_mut().zip(crate::hand_model::PARAM_NAMES) {
        *slot =
            by_name(name).ok_or_else(|| anyhow::anyhow!("{}: no parameter {name}", ir.file()))?;
    }
    Ok(VehicleParams::from_array(array))
}

/// Audit one vehicle model with the parameters of `args`.
pub fn audit_model(
    name: &str,
    params: Option<&PathBuf>,
    settings: &AuditSettings,
) -> Result<AuditReport> {
    let loaded = ModelArgs {
        model: Some(name.to_string()),
        ir: None,
        params: params.cloned(),
    }
    .load()?;
    let p = vehicle_params(&loaded.ir, &loaded.params)?;
    let values = |p: &VehicleParams| -> [f64; 16] { reorder(&loaded.ir, p) };
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
        "segway7" => audit(
            &p,
            |q| twv_generated::Segway7::new(values(q)),
            &HandSegway7::new(p),
            true,
            settings,
        ),
        other => bail!("--model {other}: the audit covers vehicle8, vehicle7, segway7 or all"),
    })
}

/// Parameter values in the IR's order from the hand model's struct.
fn reorder(ir: &Ir, p: &VehicleParams) -> [f64; 16] {
    let array = p.to_array();
    let mut out = [0.0; 16];
    for (slot, param) in out.iter_mut().zip(ir.params()) {
        if let Some(i) = crate::hand_model::PARAM_NAMES
            .iter()
            .position(|n| *n == param.name)
        {
            *slot = array[i];
        }
    }
    out
}

pub fn run(args: &AuditArgs) -> Result<()> {
    if args.tolerance.is_nan() || args.tolerance <= 0.0 {
        bail!("--tolerance must be positive, got {}", args.tolerance);
    }
    let settings = AuditSettings {
        samples: args.samples,
        seed: args.seed,
        tolerance: args.tolerance,
        ..Default::default()
    };
    let names: Vec<&str> = if args.model == "all" {
        VEHICLES.to_vec()
    } else {
        vec![args.model.as_str()]
    };
    let reports = names
        .iter()
        .map(|n| audit_model(n, args.params.as_ref(), &settings))
        .collect::<Result<Vec<_>>>()?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&reports)?);
    } else {
        for r in &reports {
            print!("{}", r.table());
        }
    }
    let failed: Vec<&str> = reports
        .iter()
        .filter(|r| !r.passed)
        .map(|r| r.model.as_str())
        .collect();
    if !failed.is_empty() {
        bail!("audit failed for {}", failed.join(", "));
    }
    Ok(())
}
