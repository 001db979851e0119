//! Lyapunov spectra by the method of Benettin, Galgani, Giorgilli & Strelcyn (1980) with
//! Householder QR re-orthonormalisation, and the diagnostics that say how far to trust them.
//!
//! The state and `K` tangent vectors are integrated together ([`crate::integrate`]); every
//! `t_sample` seconds the tangent basis is re-orthonormalised (W = QR, R with a positive
//! diagonal) and log R_kk accumulated. λ_k is the time average of those logs. `K = N` gives the
//! full spectrum, `K < N` the `K` largest exponents.
//!
//! Diagnostics (in [`LyapunovResult`]): running estimates at every re-orthonormalisation (CSV),
//! a standard error per exponent by batch means, Σλ beside the time average of tr(∂f/∂x) along
//! the same trajectory (they must agree for the full spectrum), the Kaplan–Yorke dimension, and a
//! [`Classification`] that never calls a finite-time estimate more than it is.
//!
//! ```no_run
//! # use twv_analysis::integrate::OpenLoop;
//! # use twv_analysis::lyapunov::{lyapunov_spectrum, LyapunovSettings};
//! # fn demo<M: twv_model::Model<8, 2>>(model: &M, x0: [f64; 8]) -> Result<(), Box<dyn std::error::Error>> {
//! let field = OpenLoop::new(model, [0.0, 0.0]);
//! let result = lyapunov_spectrum::<_, 8, 8>(&field, &x0, &LyapunovSettings::preset_paper())?;
//! println!("{}", serde_json::to_string(&result)?);
//! # Ok(()) }
//! ```

mod basis;
mod benettin;
mod classify;
mod error;
mod intervals;
mod qr;
mod result;
mod settings;
mod stats;

pub use basis::initial_basis;
pub use benettin::{
    lyapunov_spectrum, lyapunov_spectrum_observed, lyapunov_spectrum_with, Batches,
    MAX_RUNNING_ROWS,
};
pub use classify::{
    classify, verdict, Classification, ExponentSign, SignDecision, SignRule, SignTest,
};
pub use error::{LyapunovError, SettingsError};
pub(crate) use intervals::IntervalEnds;
pub use qr::orthonormalize;
pub use result::{LyapunovResult, RunDetails, RunningEstimates};
pub use settings::{InitialBasis, IntegratorChoice, LyapunovSettings};
pub use stats::{batch_means_stderr, kaplan_yorke, stderr_of_batch_means};
