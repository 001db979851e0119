//! A resolved model for Python: f, ∂f/∂x, ∂f/∂u and J·v on a batch of states, looped in Rust
//! with the GIL released (one dispatch per batch, no per-state Python overhead).

use std::path::PathBuf;

use numpy::{PyArray1, PyArrayMethods, PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use twv_analysis::api::{evaluate_batch, Batch, Quantity};
use twv_analysis::model::{
    vehicle_defaults, Compiler, Engine, IrRuntime, ModelSource, ModelSpec, ParamSource,
    ResolvedModel,
};

use crate::errors::{to_py, InputError};
use crate::{PAPER_TOML, SEGWAY_TOML};

/// A model and its parameter values, resolved and validated as the CLI resolves `--model`,
/// `--ir` and `--params`.
#[pyclass(frozen, module = "twv._native")]
pub struct Model {
    resolved: ResolvedModel,
}

impl Model {
    /// The resolved model the API functions take.
    pub fn resolved(&self) -> &ResolvedModel {
        &self.resolved
    }
}

/// The contiguous numbers of `array` (C order), named `name` in errors, with every entry
/// finite.
fn numbers<'a>(name: &str, array: &'a PyReadonlyArray2<'_, f64>) -> PyResult<&'a [f64]> {
    let values = array
        .as_slice()
        .map_err(|_| InputError::new_err(format!("{name}: must be a C-contiguous array")))?;
    let cols = array.shape()[1].max(1);
    if let Some(i) = values.iter().position(|v| !v.is_finite()) {
        return Err(InputError::new_err(format!(
            "{name}[{}, {}] = {} is not finite",
            i / cols,
            i % cols,
            values[i]
        )));
    }
    Ok(values)
}

impl Model {
    /// Evaluates `what` on the rows of `x` (and `u`, `v`) into an array of shape `shape(n)`.
    fn batch<'py>(
        &self,
        py: Python<'py>,
        what: Quantity,
        x: PyReadonlyArray2<'py, f64>,
        u: Option<PyReadonlyArray2<'py, f64>>,
        v: Option<PyReadonlyArray2<'py, f64>>,
        shape: impl Fn(usize) -> Vec<usize>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (nx, nu) = (self.resolved.ir.nx(), self.resolved.ir.nu());
        let n = x.shape()[0];
        let check = |name: &str, a: &PyReadonlyArray2<'_, f64>, width: usize| {
            let s = a.shape();
            if s[0] != n || s[1] != width {
                return Err(InputError::new_err(format!(
                    "{name}: shape ({}, {}), want ({n}, {width})",
                    s[0], s[1]
                )));
            }
            Ok(())
        };
        check("x", &x, nx)?;
        let xs = numbers("x", &x)?;
        let us = match &u {
            Some(u) => {
                check("u", u, nu)?;
                numbers("u", u)?
            }
            None => &[],
        };
        let vs = match &v {
            Some(v) => {
                check("v", v, nx)?;
                numbers("v", v)?
            }
            None => &[],
        };
        let mut out = vec![0.0; n * what.width(nx, nu)];
        let resolved = &self.resolved;
        py.detach(|| {
            let batch = Batch {
                x: xs,
                u: us,
                v: vs,
            };
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                evaluate_batch(resolved, what, batch, &mut out)
            }))
        })
        .map_err(crate::errors::panicked)?
        .map_err(to_py)?;
        let array = PyArray1::from_vec(py, out);
        Ok(array.reshape(shape(n))?.into_any())
    }
}

#[pymethods]
impl Model {
    /// A shipped model by `name` (default vehicle8), or a model IR from `ir_file` or the text
    /// `ir_json` (bit-identical to generated code); parameters from `params_file` or the TOML
    /// text `params_toml` (default: the vehicle file a shipped vehicle comes with, else the
    /// IR's defaults), then `overrides` (TOML key → its values). A model without generated code
    /// runs as `runtime`: "jit" (compiled to native code when loaded) or "interpreter".
    #[new]
    #[pyo3(signature = (name = None, *, ir_file = None, ir_json = None, params_file = None,
                        params_toml = None, overrides = None, runtime = "jit"))]
    fn new(
        name: Option<String>,
        ir_file: Option<PathBuf>,
        ir_json: Option<String>,
        params_file: Option<PathBuf>,
        params_toml: Option<String>,
        overrides: Option<Vec<(String, Vec<f64>)>>,
        runtime: &str,
    ) -> PyResult<Self> {
        let runtime = match runtime {
            "jit" => IrRuntime::Compiled(Compiler {
                name: "cranelift",
                compile: |ir| twv_jit::compile(ir).map_err(|e| e.to_string()),
            }),
            "interpreter" => IrRuntime::Interpreter,
            other => {
                return Err(InputError::new_err(format!(
                    "runtime: {other:?} is not one of \"jit\", \"interpreter\""
                )))
            }
        };
        let given = [name.is_some(), ir_file.is_some(), ir_json.is_some()];
        if given.iter().filter(|g| **g).count() > 1 {
            return Err(InputError::new_err(
                "model: give one of name, ir_file and ir_json",
            ));
        }
        if params_file.is_some() && params_toml.is_some() {
            return Err(InputError::new_err(
                "params: give params_file or params_toml, not both",
            ));
        }
        let (model, shipped) = match (ir_file, ir_json) {
            (Some(path), _) => (ModelSource::IrFile(path), None),
            (None, Some(text)) => {
                let ir =
                    twv_ir::parse_ir(&text, "the IR given as text").map_err(|e| to_py(e.into()))?;
                (ModelSource::Ir(Box::new(ir)), None)
            }
            (None, None) => {
                let name = name.unwrap_or_else(|| "vehicle8".into());
                (ModelSource::Shipped(name.clone()), Some(name))
            }
        };
        let params = match (params_file, params_toml, shipped) {
            (Some(path), _, _) => ParamSource::File(path),
            (None, Some(text), _) => ParamSource::Text {
                text,
                origin: "the parameters given as TOML text".into(),
            },
            (None, None, Some(name)) => {
                vehicle_defaults(&name, PAPER_TOML, SEGWAY_TOML).unwrap_or_default()
            }
            (None, None, None) => ParamSource::Defaults,
        };
        let spec = ModelSpec {
            model,
            params,
            runtime,
        };
        let mut resolved = spec.resolve().map_err(to_py)?;
        if let Some(o) = overrides.filter(|o| !o.is_empty()) {
            resolved = resolved.with_overrides(&o, "overrides").map_err(to_py)?;
        }
        Ok(Self { resolved })
    }

    /// The model's name.
    #[getter]
    fn name(&self) -> &str {
        self.resolved.name()
    }

    /// State names, in order.
    #[getter]
    fn states(&self) -> Vec<String> {
        self.resolved
            .states()
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Input names, in order.
    #[getter]
    fn inputs(&self) -> Vec<String> {
        self.resolved
            .inputs()
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// `generated` (a shipped model's compiled kernels) or `interpreted` (an IR).
    #[getter]
    fn engine(&self) -> &'static str {
        match self.resolved.engine {
            Engine::Generated(_) => "generated",
            Engine::Jit => "jit",
            Engine::Interpreted => "interpreted",
        }
    }

    /// Where the parameter values came from.
    #[getter]
    fn params_origin(&self) -> &str {
        &self.resolved.params_origin
    }

    /// Parameters as (name, TOML key, component index or None, unit, value), in IR order.
    #[getter]
    fn params(&self) -> Vec<(String, String, Option<usize>, String, f64)> {
        self.resolved
            .ir
            .params()
            .iter()
            .zip(&self.resolved.params)
            .map(|(p, v)| (p.name.clone(), p.key.clone(), p.index, p.unit.clone(), *v))
            .collect()
    }

    /// State units, in order (SI).
    #[getter]
    fn state_units(&self) -> Vec<String> {
        self.resolved
            .ir
            .states()
            .iter()
            .map(|s| s.unit.clone())
            .collect()
    }

    /// Input units, in order (SI).
    #[getter]
    fn input_units(&self) -> Vec<String> {
        self.resolved
            .ir
            .inputs()
            .iter()
            .map(|s| s.unit.clone())
            .collect()
    }

    /// ẋ = f(x, u) for each row: shape (n, nx).
    #[pyo3(signature = (x, u = None))]
    fn f<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
        u: Option<PyReadonlyArray2<'py, f64>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let nx = self.resolved.ir.nx();
        self.batch(py, Quantity::F, x, u, None, |n| vec![n, nx])
    }

    /// ∂f/∂x for each row: shape (n, nx, nx), `[k, i, j] = ∂f_i/∂x_j`.
    #[pyo3(signature = (x, u = None))]
    fn jac_x<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
        u: Option<PyReadonlyArray2<'py, f64>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let nx = self.resolved.ir.nx();
        self.batch(py, Quantity::JacX, x, u, None, |n| vec![n, nx, nx])
    }

    /// ∂f/∂u for each row: shape (n, nx, nu).
    #[pyo3(signature = (x, u = None))]
    fn jac_u<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
        u: Option<PyReadonlyArray2<'py, f64>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let (nx, nu) = (self.resolved.ir.nx(), self.resolved.ir.nu());
        self.batch(py, Quantity::JacU, x, u, None, |n| vec![n, nx, nu])
    }

    /// (∂f/∂x)·v for each row of x and v: shape (n, nx).
    #[pyo3(signature = (x, v, u = None))]
    fn jw<'py>(
        &self,
        py: Python<'py>,
        x: PyReadonlyArray2<'py, f64>,
        v: PyReadonlyArray2<'py, f64>,
        u: Option<PyReadonlyArray2<'py, f64>>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let nx = self.resolved.ir.nx();
        self.batch(py, Quantity::Jw, x, u, Some(v), |n| vec![n, nx])
    }
}
