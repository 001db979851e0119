//! The runtime of twv's exported models: one shared library that `twv export` copies into an
//! FMI 2.0 FMU (`binaries/linux64/<id>.so`, the model in `resources/bundle.json`) or writes as
//! a CasADi external function (`lib<id>.so`, the model appended to the file). It runs the
//! generated kernels of a shipped model whose IR it was built with, the IR interpreter for any
//! other model (the same bits), and steps co-simulation with twv's RK4 (`twv-step`).
//!
//! - [`plant`]: the model behind run-time sizes.
//! - `fmi2`: the FMI 2.0 C functions (model exchange and co-simulation).
//! - `casadi`: CasADi's external-function API (`f`, `jac_f`).
//! - [`bundle_source`]: where the library finds its model.

pub mod bundle_source;
mod casadi;
mod fmi2;
pub mod plant;
