//! Settings of a Lyapunov-spectrum run, with defaults, validation and the study's preset.

use serde::{Deserialize, Serialize};

use super::SettingsError;
use crate::integrate::{DopriOptions, MAX_STEPS};

/// Which integrator carries the variational system.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum IntegratorChoice {
    /// Fixed-step RK4 with step `h` (s) (the study's integrator).
    Rk4 {
        /// Step size (s).
        h: f64,
    },
    /// Adaptive Dormand–Prince 5(4).
    Dopri(DopriOptions),
}

impl Default for IntegratorChoice {
    /// RK4 with h = 10⁻³ s, the study's setting.
    fn default() -> Self {
        IntegratorChoice::Rk4 { h: 1e-3 }
    }
}

/// The initial tangent basis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum InitialBasis {
    /// The first `K` unit vectors (reproducible; what most papers use).
    #[default]
    Identity,
    /// A random orthonormal basis (Gaussian vectors, orthonormalised) from a seeded ChaCha8
    /// stream: avoids a basis accidentally aligned with an invariant subspace.
    Random {
        /// Seed of the stream.
        seed: u64,
    },
}

/// Everything a run needs besides the vector field, the initial state and `K`. Defaults are
/// beside each field; [`LyapunovSettings::preset_paper`] is the study's setting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LyapunovSettings {
    /// Re-orthonormalisation (sampling) interval T (s). Default 0.1, the study's.
    pub t_sample: f64,
    /// Number of intervals averaged over (the study's K). Default 100, so T·K = 10 s.
    pub iterations: usize,
    /// Time discarded before averaging (s). The tangent basis is evolved and re-orthonormalised
    /// during it too, so the average starts from an aligned basis. Default 0.
    pub transient: f64,
    /// The integrator. Default RK4 with h = 10⁻³ s.
    pub integrator: IntegratorChoice,
    /// The initial tangent basis. Default identity.
    pub basis: InitialBasis,
    /// Integrate ⟨tr ∂f/∂x⟩ along the trajectory (costs one Jacobian per stage) for the
    /// Σλ = ⟨tr J⟩ check. Default true.
    pub trace_check: bool,
    /// Number of batches for the batch-means standard error. Default 10.
    pub batches: usize,
    /// z-score for calling an exponent significantly positive or negative. Default 3.
    pub significance: f64,
    /// Absolute floor [1/s]: an exponent with |λ| at or below it is never called positive or
    /// negative. `None` (default): ln(K²)/T for K intervals over the horizon T (at least 1/T),
    /// the finite-time exponent of a direction that grows only like t² (see
    /// [`SignRule::from_settings`](super::SignRule::from_settings)).
    pub zero_floor: Option<f64>,
    /// An exponent that is not significantly signed counts as zero when its error bar z·σ is
    /// at most max(floor, `convergence_tol` · max|λ|), and makes the run "not converged"
    /// otherwise. Default 0.05.
    pub convergence_tol: f64,
    /// Record running estimates at every re-orthonormalisation. Default true.
    pub record_running: bool,
}

impl Default for LyapunovSettings {
    fn default() -> Self {
        Self {
            t_sample: 0.1,
            iterations: 100,
            transient: 0.0,
            integrator: IntegratorChoice::default(),
            basis: InitialBasis::Identity,
            trace_check: true,
            batches: 10,
            significance: 3.0,
            zero_floor: None,
            convergence_tol: 0.05,
            record_running: true,
        }
    }
}

impl LyapunovSettings {
    /// The study's setting: T = 0.1 s, K = 100 iterations, RK4 with h = 10⁻³ s, no transient,
    /// identity basis.
    pub fn preset_paper() -> Self {
        Self {
            t_sample: 0.1,
            iterations: 100,
            transient: 0.0,
            integrator: IntegratorChoice::Rk4 { h: 1e-3 },
            basis: InitialBasis::Identity,
            ..Self::default()
        }
    }

    /// The averaging horizon T·K (s).
    pub fn horizon(&self) -> f64 {
        self.t_sample * self.iterations as f64
    }

    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), SettingsError> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.t_sample) {
            return Err(SettingsError::SampleInterval(self.t_sample));
        }
        if self.iterations == 0 {
            return Err(SettingsError::NoIterations);
        }
        if self.iterations as u64 > MAX_STEPS {
            return Err(SettingsError::TooManySteps {
                steps: self.iterations as f64,
                max: MAX_STEPS,
            });
        }
        if !(self.transient.is_finite() && self.transient >= 0.0) {
            return Err(SettingsError::Transient(self.transient));
        }
        match &self.integrator {
            IntegratorChoice::Rk4 { h } => {
                if !pos(*h) || *h > self.t_sample {
                    return Err(SettingsError::StepSize {
                        h: *h,
                        t_sample: self.t_sample,
                    });
                }
                let steps = (self.transient + self.horizon()) / h;
                if steps > MAX_STEPS as f64 {
                    return Err(SettingsError::TooManySteps {
                        steps,
                        max: MAX_STEPS,
                    });
                }
            }
            IntegratorChoice::Dopri(o) => o.validate().map_err(SettingsError::Dopri)?,
        }
        if self.batches < 2 {
            return Err(SettingsError::Batches {
                batches: self.batches,
            });
        }
        if !pos(self.significance) {
            return Err(SettingsError::Significance(self.significance));
        }
        if let Some(floor) = self.zero_floor {
            if !(floor.is_finite() && floor >= 0.0) {
                return Err(SettingsError::ZeroFloor(floor));
            }
        }
        if !pos(self.convergence_tol) {
            return Err(SettingsError::ConvergenceTol(self.convergence_tol));
        }
        Ok(())
    }
}
