//! Typed errors of Lyapunov runs.

use crate::integrate::IntegrateError;

/// A setting that cannot give a meaningful run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingsError {
    /// T must be finite and positive.
    #[error("sampling interval t_sample = {0} must be finite and > 0")]
    SampleInterval(f64),
    /// At least one interval is needed.
    #[error("iterations must be ≥ 1")]
    NoIterations,
    /// The transient must be finite and non-negative.
    #[error("transient = {0} must be finite and ≥ 0")]
    Transient(f64),
    /// The RK4 step must be positive and fit in one interval.
    #[error("RK4 step h = {h} must be finite, > 0 and ≤ t_sample = {t_sample}")]
    StepSize {
        /// Step size.
        h: f64,
        /// Sampling interval.
        t_sample: f64,
    },
    /// Bad adaptive-integrator options.
    #[error("dopri options: {0}")]
    Dopri(IntegrateError),
    /// Batch means need at least two batches.
    #[error("batches = {batches} must be ≥ 2")]
    Batches {
        /// Batches requested.
        batches: usize,
    },
    /// The z-score must be positive.
    #[error("significance = {0} must be finite and > 0")]
    Significance(f64),
    /// The zero floor must be finite and non-negative.
    #[error("zero_floor = {0} must be finite and ≥ 0 [1/s]")]
    ZeroFloor(f64),
    /// The run would take more fixed steps than any run may.
    #[error("the run needs {steps:.3e} RK4 steps ((transient + t_sample · iterations) / h); at most {max:e} are allowed: raise h or shorten the run")]
    TooManySteps {
        /// Steps the settings ask for.
        steps: f64,
        /// The limit.
        max: u64,
    },
    /// The convergence tolerance must be positive.
    #[error("convergence_tol = {0} must be finite and > 0")]
    ConvergenceTol(f64),
}

/// Why a spectrum could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LyapunovError {
    /// Invalid settings.
    #[error("invalid Lyapunov settings")]
    Settings(#[from] SettingsError),
    /// The integration failed (blow-up, step-size underflow).
    #[error("integration failed")]
    Integrate(#[from] IntegrateError),
    /// K must be between 1 and N.
    #[error("{k} exponents requested for a {n}-dimensional system: need 1 ≤ k ≤ n")]
    ExponentCount {
        /// Requested number of exponents.
        k: usize,
        /// State dimension.
        n: usize,
    },
    /// The caller cancelled the run.
    #[error("interrupted")]
    Interrupted,
    /// A tangent vector collapsed (R_kk = 0 or non-finite): the basis lost rank, e.g. through
    /// underflow over a too long interval at a strongly contracting direction.
    #[error("tangent basis degenerate at t = {t}: R[{index}][{index}] = {r}; shorten t_sample")]
    Degenerate {
        /// Time of the re-orthonormalisation.
        t: f64,
        /// Index of the collapsed vector.
        index: usize,
        /// Its R_kk.
        r: f64,
    },
}
