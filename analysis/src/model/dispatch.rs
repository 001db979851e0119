//! The one dispatch point: a resolved model handed to generic code with its sizes as constants.
//!
//! Each state count has one model type ([`super::sized`]): the shipped models of that count
//! (generated code, their inputs padded to 4) and any IR of that count (the interpreter or its
//! native code, inputs padded to 4, see `twv_ir::Interpreted`) are variants of one enum. So each
//! job is instantiated once per state count (1 to 12), whichever models ship.
//!
//! A closed loop with NZ controller states is a `VectorField<NA>` with NA = NX + NZ, which
//! stable Rust cannot spell for a generic NX; [`dispatch_control`] resolves the model with NX as
//! a literal and matches NZ ∈ 0..=3 to `{NX + NZ}`: four instantiations per state count that
//! has a pitch to control (8: vehicle8; 7: vehicle7, segway7; IR files with 8, 7 or 4 states),
//! all with 2 inputs there.
//! [`dispatch_steer_filtered`] does the same for a steer law's rate filter (NZ = 2).

use twv_ir::{Interpreted, UnsupportedSize, MAX_NU};
use twv_model::Model;

use super::sized::{interpreted, Control7, Control8, Model3, Model4, Model7, Model8};
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

/// Runs `task` on the resolved model: generated code for a shipped model, the interpreter or
/// the IR's native code otherwise, as its state count's one model type.
pub fn dispatch<T: ModelTask>(resolved: &ResolvedModel, task: T) -> Result<T::Output> {
    let ir = &resolved.ir;
    let unsupported = || Error::Size(UnsupportedSize::of(ir));
    if ir.nu() > MAX_NU {
        return Err(unsupported());
    }
    macro_rules! by_size {
        ($($nx:literal),*) => {
            match ir.nx() {
                3 => task.run(&Model3::new(resolved)?, resolved),
                4 => task.run(&Model4::new(resolved)?, resolved),
                7 => task.run(&Model7::new(resolved)?, resolved),
                8 => task.run(&Model8::new(resolved)?, resolved),
                $($nx => task.run(&interpreted::<$nx, MAX_NU>(resolved)?, resolved),)*
                _ => Err(unsupported()),
            }
        };
    }
    by_size!(1, 2, 5, 6, 9, 10, 11, 12)
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
    let no_pitch = |model: &str| Error::Unsupported {
        model: model.to_string(),
        reason: "no pitch to control: the control jobs run vehicle8, vehicle7, segway7, or an IR \
                 model with 8, 7 or 4 states (phi, w_y among them) and 1 or 2 inputs (F1[, T2] \
                 or tau_L, tau_R); for an uncontrolled run use `twv ride`"
            .to_string(),
    };
    let ir = &resolved.ir;
    match &resolved.engine {
        Engine::Generated(name)
            if !["vehicle8", "vehicle7", "segway7"].contains(&name.as_str()) =>
        {
            return Err(no_pitch(name))
        }
        Engine::Interpreted | Engine::Jit if !matches!(ir.nu(), 1 | 2) => {
            return Err(no_pitch(&resolved.origin))
        }
        _ => {}
    }
    // Two inputs, an IR's own first (see `twv_ir::Interpreted`): the shipped vehicles' count,
    // so their generated code runs unpadded in the hot loops (see `super::sized`).
    match ir.nx() {
        8 => with_na!(Control8::new(resolved)?, 8, 2),
        7 => with_na!(Control7::new(resolved)?, 7, 2),
        4 => with_na!(interpreted::<4, 2>(resolved)?, 4, 2),
        _ => Err(no_pitch(&resolved.origin)),
    }
}

/// The one state count the steered jobs are compiled for: the Whipple bicycle's (its measured
/// variants included). Only a model with a steer input has a steer law, none is generated, and
/// every IR with one has this count, so the law's code is compiled for it alone rather than for
/// all twelve.
const STEERED_NX: usize = 9;

/// Runs `task`, a steer law's work, on the resolved model (of [`STEERED_NX`] states).
pub fn dispatch_steered<T: ModelTask>(resolved: &ResolvedModel, task: T) -> Result<T::Output> {
    task.run(&steered_model(resolved)?, resolved)
}

/// Runs `task` on the resolved model with NA = NX + 2: a steer law with a rate filter
/// ([`crate::control::steer::FilteredSteer`]), on a model of [`STEERED_NX`] states.
pub fn dispatch_steer_filtered<T: ControlTask>(
    resolved: &ResolvedModel,
    task: T,
) -> Result<T::Output> {
    const NA: usize = STEERED_NX + 2;
    task.run::<STEERED_NX, MAX_NU, NA, _>(&steered_model(resolved)?, resolved)
}

/// The resolved model as the steered jobs' model type, if a steer law can run on it: it has a
/// steer input and [`STEERED_NX`] states.
fn steered_model(resolved: &ResolvedModel) -> Result<Interpreted<STEERED_NX, MAX_NU>> {
    crate::control::steer::steer_input(resolved.name(), &resolved.inputs())?;
    match (&resolved.engine, resolved.ir.nx()) {
        (Engine::Interpreted | Engine::Jit, STEERED_NX) => interpreted(resolved),
        (_, nx) => Err(Error::Unsupported {
            model: resolved.name().to_string(),
            reason: format!(
                "a steer law runs on models of {STEERED_NX} states (the Whipple bicycle's \
                 form); this one has {nx}"
            ),
        }),
    }
}
