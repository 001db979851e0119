//! The steer law reading the rates through a first-order filter: the closed loop as a vector
//! field on NA = NX + 2 states (the model's, then the filtered lean and steer rates r), with
//! its exact Jacobian:
//!
//! ```text
//! ẋ = f(x, u),  u_δ = sat(k_φ φ + k_δ δ + k_φ̇ r_φ̇ + k_δ̇ r_δ̇),  ṙ = ((φ̇, δ̇) − r)/τ
//! ```
//!
//! The linear counterpart is [`crate::linear::steer::steer_closed_loop`] with the same τ.

use twv_model::Model;

use super::{filter_state, SteerLaw};
use crate::control::ControlError;
use crate::integrate::VectorField;

/// The model closed by a steer law with a rate filter of time constant τ.
///
/// `NA` must be NX + 2: stable Rust cannot write the sum as a const argument, so `NA ≥ NX` is
/// checked at compile time and the equality by [`FilteredSteer::new`].
#[derive(Debug)]
pub struct FilteredSteer<'a, M, const NX: usize, const NU: usize, const NA: usize> {
    model: &'a M,
    law: SteerLaw<NX, NU>,
    tau: f64,
}

// By hand: a derive would require `M: Clone`, but only the reference is copied.
impl<M, const NX: usize, const NU: usize, const NA: usize> Clone
    for FilteredSteer<'_, M, NX, NU, NA>
{
    fn clone(&self) -> Self {
        *self
    }
}
impl<M, const NX: usize, const NU: usize, const NA: usize> Copy
    for FilteredSteer<'_, M, NX, NU, NA>
{
}

impl<'a, M, const NX: usize, const NU: usize, const NA: usize> FilteredSteer<'a, M, NX, NU, NA>
where
    M: Model<NX, NU>,
{
    /// `model` closed by `law`, its rates read through the law's filter 1/(τs + 1).
    pub fn new(model: &'a M, law: SteerLaw<NX, NU>) -> Result<Self, ControlError> {
        const { assert!(NA >= NX, "the augmented size NA must be ≥ NX") };
        if NA != NX + 2 {
            return Err(ControlError::AugmentedSize {
                na: NA,
                nx: NX,
                nz: 2,
            });
        }
        let tau = law.rate_filter().ok_or_else(|| {
            ControlError::InvalidRun("the steer law has no rate filter (steer_filter)".into())
        })?;
        if !(tau.is_finite() && tau > 0.0) {
            return Err(ControlError::InvalidSetting {
                what: "steer_filter",
                value: tau,
                why: "a time constant > 0 s",
            });
        }
        Ok(Self { model, law, tau })
    }

    /// The augmented initial state: `x0` and the filter at the rates of `x0` (a filter that
    /// has been running, so no start-up transient).
    pub fn initial_state(&self, x0: &[f64; NX]) -> [f64; NA] {
        let m = self.law.modes();
        core::array::from_fn(|i| match i.checked_sub(NX) {
            None => x0[i],
            Some(f) => x0[m[2 + f]],
        })
    }

    /// Names of the filter's two states, after the rates they carry ([`filter_state`]).
    pub fn filter_states(states: &[&str], law: &SteerLaw<NX, NU>) -> [String; 2] {
        let m = law.modes();
        [filter_state(states[m[2]]), filter_state(states[m[3]])]
    }

    /// The law's readings at the augmented state: φ, δ and the filtered rates.
    #[inline(always)]
    fn readings(&self, xa: &[f64; NA]) -> [f64; 4] {
        let m = self.law.modes();
        [xa[m[0]], xa[m[1]], xa[NX], xa[NX + 1]]
    }

    /// The model part of the augmented state, and the inputs the law applies there (with
    /// whether the torque is below its limit).
    #[inline(always)]
    fn split(&self, xa: &[f64; NA]) -> ([f64; NX], [f64; NU], bool) {
        let x = core::array::from_fn(|i| xa[i]);
        let (torque, active) = self.law.torque_of(self.readings(xa));
        (x, self.law.inputs(torque), active)
    }

    /// ṙ at the augmented state (or the filter rows of J w for a tangent vector).
    #[inline(always)]
    fn filter_rates(&self, v: &[f64; NA]) -> [f64; 2] {
        let m = self.law.modes();
        [
            (v[m[2]] - v[NX]) / self.tau,
            (v[m[3]] - v[NX + 1]) / self.tau,
        ]
    }

    /// Writes the model part `fx` and the filter part `fr` into `out`.
    #[inline(always)]
    fn join(out: &mut [f64; NA], fx: &[f64; NX], fr: [f64; 2]) {
        out[..NX].copy_from_slice(fx);
        out[NX..].copy_from_slice(&fr);
    }
}

impl<M, const NX: usize, const NU: usize, const NA: usize> VectorField<NA>
    for FilteredSteer<'_, M, NX, NU, NA>
where
    M: Model<NX, NU>,
{
    const COMPILED_IN: bool = M::COMPILED_IN;

    #[inline(always)]
    fn eval<const K: usize>(
        &self,
        _t: f64,
        xa: &[f64; NA],
        w: &[[f64; NA]; K],
        f: &mut [f64; NA],
        jw: &mut [[f64; NA]; K],
    ) {
        let (x, u, active) = self.split(xa);
        let mut fx = [0.0; NX];
        if K == 0 {
            self.model.f(&x, &u, &mut fx);
            Self::join(f, &fx, self.filter_rates(xa));
            return;
        }
        let wx: [[f64; NX]; K] = core::array::from_fn(|k| core::array::from_fn(|i| w[k][i]));
        let mut jwx = [[0.0; NX]; K];
        let mut b = [[0.0; NU]; NX];
        self.model
            .f_jw_jac_u(&x, &u, &wx, &mut fx, &mut jwx, &mut b);
        let input = self.law.input_index();
        let gains = self.law.gain_row();
        for ((wk, jk), out) in w.iter().zip(&mut jwx).zip(jw.iter_mut()) {
            if active {
                // du = K · (the readings' tangent), then out += (∂f/∂u_δ) du.
                let du: f64 = self
                    .readings(wk)
                    .iter()
                    .zip(gains)
                    .map(|(r, k)| r * k)
                    .sum();
                for (o, brow) in jk.iter_mut().zip(&b) {
                    *o += brow[input] * du;
                }
            }
            Self::join(out, jk, self.filter_rates(wk));
        }
        Self::join(f, &fx, self.filter_rates(xa));
    }

    #[inline(always)]
    fn rhs(&self, _t: f64, xa: &[f64; NA], f: &mut [f64; NA]) {
        let (x, u, _) = self.split(xa);
        let mut fx = [0.0; NX];
        self.model.f(&x, &u, &mut fx);
        Self::join(f, &fx, self.filter_rates(xa));
    }

    /// tr J = tr ∂f/∂x + (∂f/∂u_δ)·(k_φ e_φ + k_δ e_δ) on the diagonal (the rates' gains act
    /// on the filter's states, off it) − 2/τ.
    fn trace_jacobian(&self, _t: f64, xa: &[f64; NA]) -> f64 {
        let (x, u, active) = self.split(xa);
        let mut j = [[0.0; NX]; NX];
        self.model.jac_x(&x, &u, &mut j);
        let mut tr: f64 = (0..NX).map(|i| j[i][i]).sum();
        if active {
            let mut b = [[0.0; NU]; NX];
            self.model.jac_u(&x, &u, &mut b);
            let (m, k, input) = (
                self.law.modes(),
                self.law.gain_row(),
                self.law.input_index(),
            );
            tr += b[m[0]][input] * k[0] + b[m[1]][input] * k[1];
        }
        tr - 2.0 / self.tau
    }
}
