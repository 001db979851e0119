//! The steer-torque law of a two-wheeler with a steer input (the bicycle), on the nonlinear
//! model: T_δ = sat(k_φ φ + k_δ δ + k_φ̇ φ̇ + k_δ̇ δ̇), every other input held at its given value;
//! with a rate filter the rates are read through 1/(τs + 1), two states of the law's own
//! ([`FilteredSteer`]).
//! The linear analysis and the tuning of the same law are [`crate::linear::steer`] and
//! [`crate::tune::steer`].

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::integrate::FeedbackLaw;
use crate::linear::steer::{SteerGains, STEER_INPUT};

mod filtered;
pub use filtered::FilteredSteer;

/// The law's settings. Default: no gains (no steering), no torque limit, no rate filter.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SteerSettings {
    /// The gains on lean, steer, lean rate and steer rate.
    pub gains: SteerGains,
    /// The torque limit |T_δ| ≤ T_max [N m]; `None`: unlimited.
    pub saturation: Option<f64>,
    /// Time constant τ [s] of a first-order filter on the lean and steer rates the law reads
    /// (a rate sensor's or a rider's lag); `None`: the rates are read directly.
    pub rate_filter: Option<f64>,
}

impl SteerSettings {
    /// The law with `gains` and nothing else: no limit, no filter.
    pub fn gains(gains: SteerGains) -> Self {
        Self {
            gains,
            ..Self::default()
        }
    }

    /// Checks the gains and the limit; the error names the field.
    pub fn validate(&self) -> Result<()> {
        for (name, k) in SteerGains::NAMES.iter().zip(self.gains.row()) {
            if !k.is_finite() {
                return Err(Error::input(*name, format!("{k} is not finite")));
            }
        }
        if let Some(t) = self.saturation {
            if !(t.is_finite() && t > 0.0) {
                return Err(Error::input(
                    "steer_saturation",
                    format!("{t}: a torque limit must be finite and > 0 N m"),
                ));
            }
        }
        if let Some(t) = self.rate_filter {
            if !(t.is_finite() && t > 0.0 && t <= MAX_RATE_FILTER) {
                return Err(Error::input(
                    "steer_filter",
                    format!(
                        "{t}: a rate filter's time constant must be in (0, {MAX_RATE_FILTER}] s"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Controller states the law adds to the model's: the two filtered rates, or none.
    pub fn n_states(&self) -> usize {
        if self.rate_filter.is_some() {
            2
        } else {
            0
        }
    }
}

/// The longest rate filter [s]: a lag of a minute is no longer a rate the law reads.
pub const MAX_RATE_FILTER: f64 = 60.0;

/// What a rate filter state's name adds to the rate's: the filtered lean rate of `w_phi` is
/// `w_phi_f`.
const FILTERED: &str = "_f";

/// The name of the filter state that carries `rate` through the law's rate filter.
pub fn filter_state(rate: &str) -> String {
    format!("{rate}{FILTERED}")
}

/// The rate that the filter state `name` carries (`None`: not a filter state's name).
pub fn filtered_rate(name: &str) -> Option<&str> {
    name.strip_suffix(FILTERED)
}

/// The index of the steer torque among `inputs` of `model`, or why it has none.
pub fn steer_input(model: &str, inputs: &[&str]) -> Result<usize> {
    inputs
        .iter()
        .position(|n| *n == STEER_INPUT)
        .ok_or_else(|| Error::Unsupported {
            model: model.to_string(),
            reason: format!(
                "no steer input to control: a steer controller needs an input named \
                 {STEER_INPUT} (inputs: {})",
                inputs.join(", ")
            ),
        })
}

/// The law on a model: where it reads (the four lean-and-steer states) and acts (`T_delta`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteerLaw<const NX: usize, const NU: usize> {
    /// Indices of φ, δ, φ̇, δ̇ in the state.
    modes: [usize; 4],
    /// Index of the steer torque in the input.
    input: usize,
    gains: [f64; 4],
    saturation: Option<f64>,
    /// τ of the rates' filter [s]: read by [`FilteredSteer`], the field that has its states.
    rate_filter: Option<f64>,
    /// The other inputs, held.
    base: [f64; NU],
}

impl<const NX: usize, const NU: usize> SteerLaw<NX, NU> {
    /// The law on a model with states `states` and inputs `inputs`, steering with `settings`
    /// on top of the constant inputs `base` (its steer-torque entry must be 0). `modes` names
    /// the lean, steer, lean-rate and steer-rate states (the IR's steady-motion modes).
    pub fn new(
        model: &str,
        states: &[&str],
        inputs: &[&str],
        modes: &[String],
        settings: &SteerSettings,
        base: [f64; NU],
    ) -> Result<Self> {
        settings.validate()?;
        let unsupported = |reason: String| Error::Unsupported {
            model: model.to_string(),
            reason,
        };
        let input = steer_input(model, inputs)?;
        if modes.len() != 4 {
            return Err(unsupported(format!(
                "a steer controller needs the four lean-and-steer modes (lean, steer, their \
                 rates) of the IR's steady motion; it names {}",
                modes.len()
            )));
        }
        let mut idx = [0; 4];
        for (slot, name) in idx.iter_mut().zip(modes) {
            *slot = states.iter().position(|n| n == name).ok_or_else(|| {
                unsupported(format!("steady-motion mode `{name}` is not a state"))
            })?;
        }
        if base[input] != 0.0 {
            return Err(Error::input(
                "u",
                format!(
                    "{STEER_INPUT} = {} is given and steered: leave it 0 when a steer \
                     controller is on",
                    base[input]
                ),
            ));
        }
        Ok(Self {
            modes: idx,
            input,
            gains: settings.gains.row(),
            saturation: settings.saturation,
            rate_filter: settings.rate_filter,
            base,
        })
    }

    /// The law on the resolved model `resolved` (states and inputs as its generated or
    /// interpreted type names them), on the lean-and-steer modes its IR's steady motion names.
    pub fn for_model(
        resolved: &crate::model::ResolvedModel,
        states: &[&str],
        inputs: &[&str],
        settings: &SteerSettings,
        base: [f64; NU],
    ) -> Result<Self> {
        let modes = resolved
            .steady_motion()
            .map_or_else(Vec::new, |m| m.modes.clone());
        Self::new(resolved.name(), states, inputs, &modes, settings, base)
    }

    /// The law's readings at `x`: φ, δ, φ̇, δ̇.
    fn readings(&self, x: &[f64; NX]) -> [f64; 4] {
        self.modes.map(|i| x[i])
    }

    /// The applied torque [N m] for the readings `r` (φ, δ and the rates as the law reads
    /// them), and whether it is below the limit (the law's derivative is then K, else 0).
    pub(crate) fn torque_of(&self, r: [f64; 4]) -> (f64, bool) {
        let c: f64 = r.iter().zip(self.gains).map(|(v, k)| k * v).sum();
        match self.saturation {
            Some(t) if c.abs() > t => (c.clamp(-t, t), false),
            _ => (c, true),
        }
    }

    /// The applied steer torque at `x` [N m].
    pub fn torque(&self, x: &[f64; NX]) -> f64 {
        self.torque_of(self.readings(x)).0
    }

    /// The inputs with the steer torque `torque`, the others held.
    pub(crate) fn inputs(&self, torque: f64) -> [f64; NU] {
        let mut u = self.base;
        u[self.input] = torque;
        u
    }

    /// Indices of φ, δ, φ̇, δ̇ in the state.
    pub(crate) fn modes(&self) -> [usize; 4] {
        self.modes
    }

    /// Index of the steer torque in the input.
    pub(crate) fn input_index(&self) -> usize {
        self.input
    }

    /// τ of the rates' filter [s], if the law has one.
    pub(crate) fn rate_filter(&self) -> Option<f64> {
        self.rate_filter
    }

    /// The gains over (φ, δ, φ̇, δ̇).
    pub(crate) fn gain_row(&self) -> [f64; 4] {
        self.gains
    }
}

impl<const NX: usize, const NU: usize> FeedbackLaw<NX, NU> for SteerLaw<NX, NU> {
    #[inline]
    fn input(&self, _t: f64, x: &[f64; NX]) -> [f64; NU] {
        self.inputs(self.torque(x))
    }

    fn jacobian(&self, _t: f64, x: &[f64; NX], out: &mut [[f64; NX]; NU]) {
        for row in out.iter_mut() {
            row.fill(0.0);
        }
        if self.torque_of(self.readings(x)).1 {
            for (&i, k) in self.modes.iter().zip(self.gains) {
                out[self.input][i] = k;
            }
        }
    }
}
