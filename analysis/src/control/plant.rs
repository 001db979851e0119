//! How the controller sees a model: which states it measures and which input directions its
//! pitch force F and yaw torque T act along, found from the model's state and input names so any
//! model with the docs/src/conventions.md names works (a generated one or an `--ir` file).

use serde::Serialize;
use twv_model::ModelInfo;

use super::error::ControlError;

/// Indices of the measured states in the model's state vector.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Measured {
    /// Pitch angle Φ (`phi`).
    pub phi: usize,
    /// Pitch rate Φ̇ (`w_y`).
    pub w_y: usize,
    /// Forward velocity (`v_x`), if the model has it.
    pub v_x: Option<usize>,
    /// Yaw rate (`w_z`), if the model has it.
    pub w_z: Option<usize>,
}

/// The input vector the controller's force F and yaw torque T produce: u = F·force + T·yaw.
///
/// - Inputs (F1, T2) (vehicle8, vehicle7): force = e_F1, yaw = e_T2.
/// - Inputs (tau_L, tau_R) (segway7): Q_vx = (τ_L + τ_R)/R and Q_wz = c (τ_R − τ_L)/(2R), so
///   F is realised by equal torques τ_L = τ_R = F R/2 and T by τ_R − τ_L = 2 R T/c:
///   force = (R/2, R/2), yaw = (−R/c, R/c). The motor's reaction −(τ_L + τ_R) = −F R acts on
///   the pendulum, which helps: it pitches it back against the lean, so the PD threshold on Kp
///   is lower than M_x g for segway7.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct InputMap<const NU: usize> {
    /// ∂u/∂F.
    #[serde(serialize_with = "ser_array")]
    pub force: [f64; NU],
    /// ∂u/∂T, or `None` when the model has no yaw input.
    #[serde(serialize_with = "ser_opt_array")]
    pub yaw: Option<[f64; NU]>,
}

fn ser_array<S: serde::Serializer, const N: usize>(a: &[f64; N], s: S) -> Result<S::Ok, S::Error> {
    a.as_slice().serialize(s)
}

fn ser_opt_array<S: serde::Serializer, const N: usize>(
    a: &Option<[f64; N]>,
    s: S,
) -> Result<S::Ok, S::Error> {
    a.as_ref().map(|a| a.as_slice()).serialize(s)
}

/// The states a pitch loop measures: the pitch angle Φ and the pitch rate w_y (a model without
/// them has no pitch to control).
pub const PITCH_STATES: [&str; 2] = ["phi", "w_y"];

/// A model as the controller sees it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Plant<const NU: usize> {
    /// Measured states.
    pub measured: Measured,
    /// Input directions.
    pub inputs: InputMap<NU>,
}

impl<const NU: usize> Plant<NU> {
    /// From the model's names; `param` looks up a parameter value by IR name (needed for the
    /// wheel-torque map: `R`, `c`). A `dyn` closure: one copy per input count, not one per
    /// caller and model (112 copies had been 4 % of the analysis crate's LLVM IR).
    pub fn from_info(
        info: &ModelInfo,
        param: &dyn Fn(&str) -> Option<f64>,
    ) -> Result<Self, ControlError> {
        let model = info.name.to_string();
        let find = |name: &str| info.states.iter().position(|s| *s == name);
        let need = |name: &'static str| {
            find(name).ok_or_else(|| ControlError::MissingState {
                model: model.clone(),
                state: name,
                states: info.states.join(", "),
            })
        };
        let [phi, w_y] = PITCH_STATES;
        let measured = Measured {
            phi: need(phi)?,
            w_y: need(w_y)?,
            v_x: find("v_x"),
            w_z: find("w_z"),
        };
        let input = |name: &str| info.inputs.iter().position(|s| *s == name);
        let unit = |i: usize| {
            let mut e = [0.0; NU];
            e[i] = 1.0;
            e
        };
        let inputs = if let Some(f1) = input("F1") {
            InputMap {
                force: unit(f1),
                yaw: input("T2").map(unit),
            }
        } else if let (Some(l), Some(r)) = (input("tau_L"), input("tau_R")) {
            let positive = |name: &'static str| match param(name) {
                Some(v) if v.is_finite() && v > 0.0 => Ok(v),
                Some(v) => Err(ControlError::MissingParam {
                    model: model.clone(),
                    param: name,
                    why: format!("= {v} must be finite and > 0"),
                }),
                None => Err(ControlError::MissingParam {
                    model: model.clone(),
                    param: name,
                    why: "is not a parameter of the model".into(),
                }),
            };
            let (radius, track) = (positive("R")?, positive("c")?);
            let mut force = [0.0; NU];
            let mut yaw = [0.0; NU];
            force[l] = radius / 2.0;
            force[r] = radius / 2.0;
            yaw[l] = -radius / track;
            yaw[r] = radius / track;
            InputMap {
                force,
                yaw: Some(yaw),
            }
        } else {
            return Err(ControlError::UnrecognisedInputs {
                model,
                inputs: info.inputs.join(", "),
            });
        };
        Ok(Self { measured, inputs })
    }
}
