//! The one dispatch point: a resolved model handed to generic code with its sizes as constants.
//!
//! A shipped model runs as its generated type; an IR file on the interpreter, whose state count
//! is chosen from the file (1 to 12; inputs are padded to 4, see `twv_ir::Interpreted`), so each
//! job is instantiated once per shipped model and once per state count.
//!
//! A closed loop with NZ controller states is a `VectorField<NA>` with NA = NX + NZ, which
//! stable Rust cannot spell for a generic NX; [`dispatch_control`] resolves the model with NX as
//! a literal and matches NZ ∈ 0..=3 to `{NX + NZ}`: four instantiations per model that has a
//! pitch to control (vehicle8, vehicle7, segway7; IR files with 8, 7 or 4 states).
//! [`dispatch_steer_filtered`] does the same for a steer law's rate filter (NZ = 2).

use twv_generated::{Segway7, Vehicle7, Vehicle8};
use twv_ir::{Interpreted, MAX_NU};
use twv_model::{Model, ModelVisitor};

use super::{Engine, ResolvedModel};
use crate::error::{Error, Result};

/// Work to do with a model whose sizes are known only once it is resolved.
pub trait ModelTask {
    /// What the work returns.
    type Output;
    /// Do it with the concrete model.
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<Self::Output>;
}

struct Visit<'a, T> {
    task: T,
    resolved: &'a ResolvedModel,
}

impl<T: ModelTask> ModelVisitor for Visit<'_, T> {
    type Output = Result<T::Output>;
    fn visit<const NX: usize, const NU: usize, M: Model<NX, NU>>(self, model: M) -> Self::Output {
        self.task.run(&model, self.resolved)
    }
}

/// Runs `task` on the resolved model: generated code for a shipped model, the interpreter or
/// the IR's native code otherwise.
pub fn dispatch<T: ModelTask>(resolved: &ResolvedModel, task: T) -> Result<T::Output> {
    let visitor = Visit { task, resolved };
    match &resolved.engine {
        Engine::Generated(name) => twv_generated::visit(name, Some(&resolved.params), visitor)
            .map_err(|e| Error::Unsupported {
                model: name.clone(),
                reason: e.to_string(),
            })?,
        Engine::Interpreted | Engine::Jit => {
            let native = resolved.native.clone();
            twv_ir::visit_interpreted(&resolved.ir, &resolved.params, native, visitor).map_err(
                |e| match e {
                    twv_ir::VisitError::Size(s) => Error::Size(s),
                    twv_ir::VisitError::Model(m) => Error::Model(m),
                },
            )?
        }
    }
}

/// Work on a closed loop whose augmented size NA is known only once the controller is.
pub trait ControlTask {
    /// What the work returns.
    type Output;
    /// Do it with the concrete model and NA = NX + controller states.
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        model: &M,
        resolved: &ResolvedModel,
    ) -> Result<Self::Output>;
}

/// Runs `task` on the resolved model with NA = NX + `nz` (see the module documentation).
pub fn dispatch_control<T: ControlTask>(
    resolved: &ResolvedModel,
    nz: usize,
    task: T,
) -> Result<T::Output> {
    macro_rules! with_na {
        ($model:expr, $nx:literal, $nu:expr) => {{
            let model = $model;
            match nz {
                0 => task.run::<$nx, $nu, $nx, _>(&model, resolved),
                1 => task.run::<$nx, $nu, { $nx + 1 }, _>(&model, resolved),
                2 => task.run::<$nx, $nu, { $nx + 2 }, _>(&model, resolved),
                3 => task.run::<$nx, $nu, { $nx + 3 }, _>(&model, resolved),
                _ => Err(Error::input(
                    "controller",
                    format!("{nz} controller states: at most 3 are supported"),
                )),
            }
        }};
    }
    let params = &resolved.params;
    let values = |n: usize| -> Result<Vec<f64>> {
        if params.len() != n {
            return Err(Error::input(
                "params",
                format!("{} parameter values for a model with {n}", params.len()),
            ));
        }
        Ok(params.clone())
    };
    let no_pitch = |model: &str| Error::Unsupported {
        model: model.to_string(),
        reason: "no pitch to control: the control jobs run vehicle8, vehicle7, segway7, or an IR \
                 model with 8, 7 or 4 states (phi, w_y among them) and 1 or 2 inputs (F1[, T2] \
                 or tau_L, tau_R); for an uncontrolled run use `twv ride`"
            .to_string(),
    };
    match &resolved.engine {
        Engine::Generated(name) => match name.as_str() {
            "vehicle8" => with_na!(Vehicle8::new(fixed(values(Vehicle8::NP)?)), 8, 2),
            "vehicle7" => with_na!(Vehicle7::new(fixed(values(Vehicle7::NP)?)), 7, 2),
            "segway7" => with_na!(Segway7::new(fixed(values(Segway7::NP)?)), 7, 2),
            other => Err(no_pitch(other)),
        },
        Engine::Interpreted | Engine::Jit => {
            let ir = &resolved.ir;
            let native = resolved.native.clone();
            // Interpreted models take MAX_NU inputs, their own first (see `twv_ir::Interpreted`).
            match (ir.nx(), ir.nu()) {
                (8, 1 | 2) => with_na!(
                    Interpreted::<8, MAX_NU>::with_native(ir, params, native)?,
                    8,
                    MAX_NU
                ),
                (7, 1 | 2) => with_na!(
                    Interpreted::<7, MAX_NU>::with_native(ir, params, native)?,
                    7,
                    MAX_NU
                ),
                (4, 1 | 2) => with_na!(
                    Interpreted::<4, MAX_NU>::with_native(ir, params, native)?,
                    4,
                    MAX_NU
                ),
                _ => Err(no_pitch(&resolved.origin)),
            }
        }
    }
}

/// Runs `task` on the resolved model with NA = NX + 2: a steer law with a rate filter
/// ([`crate::control::steer::FilteredSteer`]). Only a model with a steer input has one, and
/// none is generated, so only an IR's state counts resolve: 9, the Whipple bicycle's (its
/// measured variants included). Another count is one more literal in the match below.
pub fn dispatch_steer_filtered<T: ControlTask>(
    resolved: &ResolvedModel,
    task: T,
) -> Result<T::Output> {
    crate::control::steer::steer_input(resolved.name(), &resolved.inputs())?;
    let ir = &resolved.ir;
    let native = resolved.native.clone();
    match (&resolved.engine, ir.nx()) {
        (Engine::Interpreted | Engine::Jit, 9) => {
            let model = Interpreted::<9, MAX_NU>::with_native(ir, &resolved.params, native)?;
            task.run::<9, MAX_NU, 11, _>(&model, resolved)
        }
        (_, nx) => Err(Error::Unsupported {
            model: resolved.name().to_string(),
            reason: format!(
                "a steer law with a rate filter runs on models of 9 states (the Whipple \
                 bicycle's form); this one has {nx}: steer it without steer_filter"
            ),
        }),
    }
}

/// A parameter vector of checked length as an array.
fn fixed<const N: usize>(v: Vec<f64>) -> [f64; N] {
    let mut out = [0.0; N];
    out.iter_mut().zip(&v).for_each(|(o, x)| *o = *x);
    out
}
