//! `twv audit`: the derived (generated) model against the independent hand model, term by term,
//! plus physical checks on the derived model alone.
//!
//! An energy test cannot catch a dropped gyroscopic pair (it does no work); comparing every
//! entry of M, Cp, F, Q, f and ∂f/∂x at random large-angle, fast-spin states does.

pub(crate) mod compare;
mod physics;
pub(crate) mod report;
mod sampling;
mod simulation;

pub use compare::{compare, EntryError, QuantityError};
pub use physics::{upright_lambda_squared, PhysicsCheck};
pub use report::AuditReport;
pub use sampling::{sample_vectors, samples, Sample};

use twv_model::Mechanical;

use crate::hand_model::VehicleParams;

/// Settings of an audit, defaults beside each field.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AuditSettings {
    /// Random samples (after the upright and hanging rest states). Default 200.
    pub samples: usize,
    /// Seed of the sample generator. Default 2016.
    pub seed: u64,
    /// Largest accepted normwise relative error of any term. Default 1e-11.
    pub tolerance: f64,
    /// Half-range of the random inputs (N or N m). Default 200.
    pub input_scale: f64,
    /// Random states simulated for the energy checks (20 s free, 2 s forced). Default 4.
    pub simulations: usize,
}

impl Default for AuditSettings {
    fn default() -> Self {
        Self {
            samples: 200,
            seed: 2016,
            tolerance: 1e-11,
            input_scale: 200.0,
            simulations: 4,
        }
    }
}

/// Audit `make(params)` against `reference`: term by term and physically.
///
/// `make` builds the audited model from parameters (the `a`-independence check rebuilds it with
/// another base height); `rolling_wheels` selects the translational mass of the λ formula.
pub fn audit<const NX: usize, const NU: usize, const NS: usize, A, R>(
    params: &VehicleParams,
    make: impl Fn(&VehicleParams) -> A,
    reference: &R,
    rolling_wheels: bool,
    settings: &AuditSettings,
) -> AuditReport
where
    A: Mechanical<NX, NU, NS>,
    R: Mechanical<NX, NU, NS>,
{
    let audited = make(params);
    let info = reference.info();
    let pts = samples::<NX, NU>(
        info.states,
        settings.input_scale,
        settings.samples + 2,
        settings.seed,
    );
    let quantities = compare(&audited, reference, &pts);
    let lambda_squared = upright_lambda_squared(params, rolling_wheels);
    let mut checks = Vec::new();
    checks.extend(physics::equilibrium_eigenvalues(&audited, lambda_squared));
    checks.push(physics::gyroscopic_no_work(&audited, &pts));
    checks.push(physics::energy_balance(&audited, &pts));
    checks.push(physics::height_independence(
        |a| make(&VehicleParams { a, ..*params }),
        &pts,
    ));
    checks.extend(physics::symmetry(&audited, &pts));
    checks.extend(simulation::energy_checks(
        &audited,
        &pts,
        settings.simulations,
    ));
    AuditReport::new(info.name, settings, quantities, checks, &pts)
}
