//! Resolving the model a job runs on — a shipped model by name or a model IR, with parameter
//! values from its defaults, a file, or text — and the one place that hands it, with its sizes
//! as constants, to the generic code ([`dispatch`], [`dispatch_control`]).

mod dispatch;
mod sized;
mod vector;

use std::path::{Path, PathBuf};
use std::sync::Arc;

pub use dispatch::{
    dispatch, dispatch_control, dispatch_steer_filtered, dispatch_steered, ControlTask, ModelTask,
};
pub use vector::{check_vector, input_vector, state_vector};

use twv_ir::{Ir, NativeCode, SteadyMotion};

use crate::error::{Error, Result};

/// Where a model's equations come from.
#[derive(Debug, Clone, PartialEq)]
pub enum ModelSource {
    /// A shipped model (`vehicle8`, `vehicle7`, `segway7`, `lorenz`, `henon_heiles`): generated
    /// code.
    Shipped(String),
    /// A model IR file (`twv-ir/1`): the interpreter, bit-identical to generated code.
    IrFile(PathBuf),
    /// A model IR already in memory (derived in the same session): the interpreter.
    Ir(Box<Ir>),
}

impl Default for ModelSource {
    /// The study's model, vehicle8.
    fn default() -> Self {
        ModelSource::Shipped("vehicle8".into())
    }
}

/// Where the parameter values come from.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum ParamSource {
    /// The defaults recorded in the model IR.
    #[default]
    Defaults,
    /// A TOML parameter file (SI units).
    File(PathBuf),
    /// TOML text, with the name messages use for it (a front end's embedded vehicle file).
    Text {
        /// The TOML document.
        text: String,
        /// Its name in messages and reports.
        origin: String,
    },
}

/// A compiler of an IR to native code with the interpreter's bits (`twv_jit::compile`). A front
/// end that links one passes it in [`IrRuntime::Compiled`]; this library does not depend on a
/// code generator, so that it builds the same with or without.
#[derive(Clone, Copy)]
pub struct Compiler {
    /// Its name in messages (compilers are equal when their names are).
    pub name: &'static str,
    /// Compiles an IR, or says why it cannot.
    pub compile: fn(&Ir) -> std::result::Result<Arc<dyn NativeCode>, String>,
}

impl PartialEq for Compiler {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

impl Eq for Compiler {}

impl std::fmt::Debug for Compiler {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Compiler({})", self.name)
    }
}

/// How a model without generated code (an IR file, an IR in memory, the bicycle) runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum IrRuntime {
    /// The IR interpreter: the reference.
    #[default]
    Interpreter,
    /// Compiled to native code by this compiler when the model is resolved (milliseconds), with
    /// the interpreter's bits.
    Compiled(Compiler),
}

/// A model and its parameters: what every job starts from.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ModelSpec {
    /// The equations. Default vehicle8.
    pub model: ModelSource,
    /// The parameter values. Default the IR's.
    pub params: ParamSource,
    /// How a model without generated code runs. Default the interpreter.
    pub runtime: IrRuntime,
}

/// How a resolved model is evaluated.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Engine {
    /// Generated code of the shipped model of this name.
    Generated(String),
    /// The IR interpreter.
    Interpreted,
    /// The IR compiled to native code at run time ([`ResolvedModel::native`]).
    Jit,
}

/// A resolved model: its IR (names, metadata), how it runs, and validated parameter values.
#[derive(Debug, Clone)]
pub struct ResolvedModel {
    /// How it is evaluated.
    pub engine: Engine,
    /// Where the IR came from (`generated/ir/<name>.json` for a shipped model, the file name,
    /// or the IR's own file label).
    pub origin: String,
    /// The model IR.
    pub ir: Ir,
    /// Parameter values in IR order.
    pub params: Vec<f64>,
    /// Where the values came from (a file, or a description of the defaults).
    pub params_origin: String,
    /// One standard deviation of each value (IR order), from the parameter file's
    /// `[uncertainty]` table; 0 where the file gives none (and for the IR's defaults). What
    /// `twv uncertainty` draws from.
    pub uncertainty: Vec<f64>,
    /// The native code of [`Engine::Jit`].
    pub native: Option<Arc<dyn NativeCode>>,
    /// The text of the IR, when it came from a file or is shipped (what an export carries);
    /// `None` for an IR built in memory.
    pub ir_text: Option<Arc<str>>,
}

/// The default parameter source of a shipped vehicle: `paper` (the text of vehicles/paper.toml)
/// for vehicle8 and vehicle7, `segway` (vehicles/segway.toml) for segway7, `None` for the other
/// models (their IR defaults). Front ends embed the two files themselves, so that editing one
/// rebuilds only the front end, not this library.
pub fn vehicle_defaults(model: &str, paper: &str, segway: &str) -> Option<ParamSource> {
    let (text, file) = match model {
        "vehicle8" | "vehicle7" => (paper, "vehicles/paper.toml"),
        "segway7" => (segway, "vehicles/segway.toml"),
        _ => return None,
    };
    Some(ParamSource::Text {
        text: text.to_string(),
        origin: format!("{file} (embedded)"),
    })
}

/// The model a front end runs when none is named: the study's vehicle.
pub const DEFAULT_MODEL: &str = "vehicle8";

/// The names of the shipped models.
pub fn shipped_models() -> Vec<&'static str> {
    twv_generated::MODELS
        .iter()
        .chain(&twv_generated::INTERPRETED)
        .map(|(n, _)| *n)
        .collect()
}

impl ModelSpec {
    /// A shipped model with its IR defaults.
    pub fn shipped(name: &str) -> Self {
        Self {
            model: ModelSource::Shipped(name.to_string()),
            params: ParamSource::Defaults,
            runtime: IrRuntime::default(),
        }
    }

    /// This spec with other parameter values.
    pub fn with_params(mut self, params: ParamSource) -> Self {
        self.params = params;
        self
    }

    /// Reads and validates the IR and the parameters; errors name the file and the field.
    pub fn resolve(&self) -> Result<ResolvedModel> {
        let (engine, origin, ir, ir_text) = match &self.model {
            ModelSource::Shipped(name) => {
                let file = format!("generated/ir/{name}.json");
                let interpreted = twv_generated::INTERPRETED.iter().find(|(n, _)| n == name);
                match (twv_generated::ir_json(name), interpreted) {
                    (Some(text), _) => {
                        let ir = twv_ir::parse_ir(text, &file)?;
                        (
                            Engine::Generated(name.clone()),
                            file,
                            ir,
                            Some(Arc::from(text)),
                        )
                    }
                    (None, Some((_, text))) => (
                        Engine::Interpreted,
                        file.clone(),
                        twv_ir::parse_ir(text, &file)?,
                        Some(Arc::from(*text)),
                    ),
                    (None, None) => {
                        return Err(Error::UnknownModel {
                            name: name.clone(),
                            known: shipped_models().join(", "),
                        })
                    }
                }
            }
            ModelSource::IrFile(path) => {
                let file = path.display().to_string();
                let text = std::fs::read_to_string(path).map_err(|e| twv_ir::IrError {
                    file: file.clone(),
                    problem: twv_ir::Problem::Io(e.to_string()),
                })?;
                let ir = twv_ir::parse_ir(&text, &file)?;
                (Engine::Interpreted, file, ir, Some(Arc::from(text)))
            }
            ModelSource::Ir(ir) => (
                Engine::Interpreted,
                ir.file().to_string(),
                (**ir).clone(),
                None,
            ),
        };
        let (params, params_origin, uncertainty) = match &self.params {
            ParamSource::Defaults => (
                ir.params().iter().map(|p| p.default).collect(),
                format!("defaults of {}", ir.model()),
                vec![0.0; ir.params().len()],
            ),
            ParamSource::File(path) => {
                let file = path.display().to_string();
                let text = std::fs::read_to_string(path).map_err(|e| twv_ir::ParamError {
                    file: file.clone(),
                    problem: twv_ir::ParamProblem::Io(e.to_string()),
                })?;
                let values = twv_ir::parse_params(&text, &file, ir.params())?;
                let stds = twv_ir::parse_uncertainty(&text, &file, ir.params())?;
                (values, file, stds)
            }
            ParamSource::Text { text, origin } => (
                twv_ir::parse_params(text, origin, ir.params())?,
                origin.clone(),
                twv_ir::parse_uncertainty(text, origin, ir.params())?,
            ),
        };
        let (engine, native) = match (engine, self.runtime) {
            (Engine::Interpreted, IrRuntime::Compiled(compiler)) => {
                let code = (compiler.compile)(&ir).map_err(|reason| Error::Unsupported {
                    model: ir.model().to_string(),
                    reason,
                })?;
                (Engine::Jit, Some(code))
            }
            (engine, _) => (engine, None),
        };
        Ok(ResolvedModel {
            engine,
            origin,
            ir,
            params,
            params_origin,
            uncertainty,
            native,
            ir_text,
        })
    }
}

impl ResolvedModel {
    /// The model's name.
    pub fn name(&self) -> &str {
        self.ir.model()
    }

    /// Parameter value by IR name (e.g. `m2`, `I2_yy`).
    pub fn param(&self, name: &str) -> Option<f64> {
        self.ir
            .params()
            .iter()
            .position(|p| p.name == name)
            .map(|i| self.params[i])
    }

    /// State names in order.
    pub fn states(&self) -> Vec<&str> {
        self.ir.states().iter().map(|s| s.name.as_str()).collect()
    }

    /// Input names in order.
    pub fn inputs(&self) -> Vec<&str> {
        self.ir.inputs().iter().map(|s| s.name.as_str()).collect()
    }

    /// The unit of a state, input or parameter by name (SI, from the IR).
    pub fn unit_of(&self, name: &str) -> Option<&str> {
        let ir = &self.ir;
        ir.states()
            .iter()
            .chain(ir.inputs())
            .find(|s| s.name == name)
            .map(|s| s.unit.as_str())
            .or_else(|| {
                ir.params()
                    .iter()
                    .find(|p| p.name == name)
                    .map(|p| p.unit.as_str())
            })
    }

    /// The units of the columns of a time series: time, the model's variables, and `extra`
    /// (name, unit) for the rest.
    pub fn column_units(&self, columns: &[String], extra: &[(&str, &str)]) -> Vec<String> {
        columns
            .iter()
            .map(|c| {
                let known = extra.iter().find(|(n, _)| n == c).map(|(_, u)| *u);
                match (c.as_str(), known) {
                    ("t", _) => "s",
                    (_, Some(u)) => u,
                    (name, None) => self.unit_of(name).unwrap_or(""),
                }
                .to_string()
            })
            .collect()
    }

    /// The steady motion its IR describes (the bicycle's straight running: its speed state and
    /// the lean-and-steer modes studied about it), if any.
    pub fn steady_motion(&self) -> Option<&SteadyMotion> {
        self.ir.mechanics().and_then(|m| m.steady_motion.as_ref())
    }

    /// Index of a state by name.
    pub fn state_index(&self, name: &str) -> Option<usize> {
        self.ir.states().iter().position(|s| s.name == name)
    }

    /// A state at rest with only `name` set to `value` (e.g. a tilt of Φ).
    pub fn rest_with(&self, name: &str, value: f64) -> Result<Vec<f64>> {
        let i = self.state_index(name).ok_or_else(|| Error::Unsupported {
            model: self.name().to_string(),
            reason: format!("no state `{name}` (states: {})", self.states().join(", ")),
        })?;
        let mut x = vec![0.0; self.ir.nx()];
        x[i] = value;
        Ok(x)
    }

    /// This model with some parameters set, each by its TOML key (`m2`, or `I2` with all its
    /// components) or by its IR name (`I2_yy`, one component): both vocabularies, so the values
    /// of [`Self::param_values`] round-trip. Checked like a parameter file's values; errors name
    /// the parameter. `origin` describes where the values came from, for messages and reports.
    pub fn with_overrides(&self, overrides: &[(String, Vec<f64>)], origin: &str) -> Result<Self> {
        let params = self.ir.params();
        let mut values = self.params.clone();
        let mut set = vec![false; params.len()];
        for (key, given) in overrides {
            let mut slots: Vec<usize> = (0..params.len())
                .filter(|&i| params[i].key == *key)
                .collect();
            if slots.is_empty() {
                slots = (0..params.len())
                    .filter(|&i| params[i].name == *key)
                    .collect();
            }
            if slots.is_empty() {
                let mut known: Vec<&str> = params.iter().map(|p| p.key.as_str()).collect();
                known.dedup();
                let names: Vec<&str> = params
                    .iter()
                    .filter(|p| p.index.is_some())
                    .map(|p| p.name.as_str())
                    .collect();
                return Err(Error::input(
                    "params",
                    format!(
                        "unknown parameter `{key}` (file keys: {}; components: {})",
                        known.join(", "),
                        names.join(", ")
                    ),
                ));
            }
            if given.len() != slots.len() {
                return Err(Error::input(
                    "params",
                    format!(
                        "`{key}` has {} component(s), {} given",
                        slots.len(),
                        given.len()
                    ),
                ));
            }
            for (&i, &v) in slots.iter().zip(given) {
                if std::mem::replace(&mut set[i], true) {
                    return Err(Error::input(
                        "params",
                        format!(
                            "`{}` is given twice (as {key} and by another name)",
                            params[i].name
                        ),
                    ));
                }
                values[i] = v;
            }
        }
        let label = format!("{origin} (over {})", self.params_origin);
        twv_ir::check_values(&values, &label, params)?;
        Ok(Self {
            params: values,
            params_origin: label,
            ..self.clone()
        })
    }

    /// This model with parameters set by their IR names (`m2`, `I2_xx`: one value each) or
    /// TOML keys of one component: see [`Self::with_overrides`].
    pub fn with_param_values(&self, values: &[(String, f64)], origin: &str) -> Result<Self> {
        let overrides: Vec<(String, Vec<f64>)> =
            values.iter().map(|(k, v)| (k.clone(), vec![*v])).collect();
        self.with_overrides(&overrides, origin)
    }

    /// Every parameter by its IR name (`m2`, `I2_yy`) with its value: what
    /// [`Self::with_overrides`] takes back.
    pub fn param_values(&self) -> Vec<(String, f64)> {
        self.ir
            .params()
            .iter()
            .zip(&self.params)
            .map(|(p, v)| (p.name.clone(), *v))
            .collect()
    }

    /// Whether the model runs on generated code.
    pub fn is_shipped(&self) -> bool {
        matches!(self.engine, Engine::Generated(_))
    }

    /// Where the IR came from, as recorded in sweep configs: `shipped` or the file.
    pub fn source_label(&self) -> String {
        match &self.engine {
            Engine::Generated(_) => "shipped".to_string(),
            Engine::Interpreted | Engine::Jit => self.origin.clone(),
        }
    }

    /// The IR file path, for a model read from an IR file.
    pub fn ir_path(&self) -> Option<&Path> {
        (!self.is_shipped()).then(|| Path::new(&self.origin))
    }
}
