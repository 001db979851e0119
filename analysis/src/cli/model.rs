//! `--model NAME | --ir FILE [--params FILE]`: resolving the model a command runs on.
//!
//! A shipped model runs as generated code (its concrete type, monomorphised); an IR file runs on
//! the interpreter, whose sizes are const generics too, chosen from the file at run time.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use twv_ir::Ir;
use twv_model::{Model, ModelVisitor};

/// Which model to run and with which parameters.
#[derive(Args, Debug, Clone, Default)]
pub struct ModelArgs {
    /// Shipped model: vehicle8, vehicle7, segway7, lorenz or henon_heiles [default: vehicle8]
    #[arg(long, value_name = "NAME", conflicts_with = "ir")]
    pub model: Option<String>,
    /// A model IR file (twv-ir/1) to evaluate with the interpreter, without recompiling
    #[arg(long, value_name = "FILE")]
    pub ir: Option<PathBuf>,
    /// Parameter file (TOML, SI units) [default: the model's defaults; for the vehicles the
    /// values of vehicles/paper.toml, for segway7 vehicles/segway.toml, embedded in the binary]
    #[arg(long, value_name = "FILE")]
    pub params: Option<PathBuf>,
}

/// Where the model's equations come from.
#[derive(Debug, Clone)]
pub enum Source {
    /// A shipped model: generated code.
    Shipped(String),
    /// An IR file: the interpreter.
    File(PathBuf),
}

/// A resolved model: its IR (for names and metadata) and validated parameter values.
#[derive(Debug, Clone)]
pub struct LoadedModel {
    pub source: Source,
    pub ir: Ir,
    pub params: Vec<f64>,
    /// The parameter file, or a description of the defaults used.
    pub params_origin: String,
}

impl LoadedModel {
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
}

impl ModelArgs {
    /// A shipped model by default.
    pub fn with_default(mut self, name: &str) -> Self {
        if self.model.is_none() && self.ir.is_none() {
            self.model = Some(name.to_string());
        }
        self
    }

    /// Read the IR and the parameter file (everything validated, errors name file and field).
    pub fn load(&self) -> Result<LoadedModel> {
        let (source, ir) = match (&self.model, &self.ir) {
            (_, Some(path)) => (Source::File(path.clone()), twv_ir::load_ir(path)?),
            (name, None) => {
                let name = name.as_deref().unwrap_or("vehicle8");
                let Some(text) = twv_generated::ir_json(name) else {
                    let known: Vec<&str> = twv_generated::MODELS.iter().map(|(n, _)| *n).collect();
                    bail!("unknown model `{name}` (shipped: {})", known.join(", "));
                };
                let file = format!("generated/ir/{name}.json");
                (
                    Source::Shipped(name.to_string()),
                    twv_ir::parse_ir(text, &file)?,
                )
            }
        };
        let (params, params_origin) = match &self.params {
            Some(path) => (ir.load_params(path)?, path.display().to_string()),
            None => {
                let defaults = ir.params().iter().map(|p| p.default).collect::<Vec<_>>();
                (defaults, format!("defaults of {}", ir.model()))
            }
        };
        Ok(LoadedModel {
            source,
            ir,
            params,
            params_origin,
        })
    }
}

/// Work to do with a model whose sizes are known only once it is resolved.
pub trait ModelTask {
    type Output;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        loaded: &LoadedModel,
    ) -> Result<Self::Output>;
}

struct Visit<'a, T> {
    task: T,
    loaded: &'a LoadedModel,
}

impl<T: ModelTask> ModelVisitor for Visit<'_, T> {
    type Output = Result<T::Output>;
    fn visit<const NX: usize, const NU: usize, M: Model<NX, NU>>(self, model: M) -> Self::Output {
        self.task.run(&model, self.loaded)
    }
}

/// Run `task` on the resolved model: generated code for a shipped model, the interpreter (sizes
/// chosen at run time, 1 to 10 states and 0 to 2 inputs) for an IR file.
pub fn dispatch<T: ModelTask>(loaded: &LoadedModel, task: T) -> Result<T::Output> {
    let visitor = Visit { task, loaded };
    match &loaded.source {
        Source::Shipped(name) => twv_generated::visit(name, Some(&loaded.params), visitor)?,
        Source::File(_) => twv_ir::visit_interpreted(&loaded.ir, &loaded.params, visitor)?,
    }
}

/// Parse a comma-separated vector of `n` finite numbers for option `--{option}`.
pub fn parse_vector(option: &str, text: &str, names: &[&str]) -> Result<Vec<f64>> {
    let values: Vec<f64> = if text.trim().is_empty() {
        Vec::new()
    } else {
        text.split(',')
            .map(|s| {
                s.trim()
                    .parse::<f64>()
                    .with_context(|| format!("--{option}: `{}` is not a number", s.trim()))
            })
            .collect::<Result<_>>()?
    };
    if values.len() != names.len() {
        bail!(
            "--{option} has {} values, the model has {} ({})",
            values.len(),
            names.len(),
            names.join(", ")
        );
    }
    if let Some((i, v)) = values.iter().enumerate().find(|(_, v)| !v.is_finite()) {
        bail!("--{option}: {} = {v} is not finite", names[i]);
    }
    Ok(values)
}

/// Copy a checked vector into a fixed-size array (lengths were checked by `parse_vector`).
pub fn to_array<const N: usize>(v: &[f64]) -> [f64; N] {
    let mut out = [0.0; N];
    out.iter_mut().zip(v).for_each(|(o, x)| *o = *x);
    out
}
