//! A CasADi external function: the export runtime with the model appended to its file, one
//! library that `casadi.external("f", "lib<id>.so")` loads as a differentiable `Function`
//! (`f(x, u) -> xdot` and `jac_f`, the Jacobians by CasADi's naming rule).

use twv_ir::Bundle;

/// The library file name of an export with identifier `id`.
pub fn file_name(id: &str) -> String {
    format!("lib{id}.so")
}

/// The library's bytes.
pub fn library(bundle: &Bundle, runtime: &[u8]) -> Vec<u8> {
    bundle.append_to(runtime)
}
