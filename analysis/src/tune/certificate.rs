//! The independent check of tuned gains: closed-loop eigenvalues of the full linearised model
//! and margins recomputed on the dense, refined grid of [`crate::linear::margins`] — none of
//! the tuner's own grid or linearisation is trusted.

use super::spec::Spec;
use crate::linear::error::LinearError;
use crate::linear::pitch::{LoopOptions, PidGains, PitchLoop};
use crate::linear::report::{analyse_pitch, PitchAnalysis};

/// What was checked and what came out.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Certificate {
    /// The gains checked.
    pub gains: PidGains,
    /// The loop they were checked in (lag, delay).
    pub options: LoopOptions,
    /// Closed-loop eigenvalues (loop and hidden drift) and the dense-grid margins.
    pub analysis: PitchAnalysis,
    /// Loop stable (eigenvalues, delay included) and every requirement met.
    pub meets_spec: bool,
}

/// Checks `gains` against `spec`.
pub fn certify(
    lp: &PitchLoop,
    gains: &PidGains,
    options: &LoopOptions,
    spec: &Spec,
) -> Result<Certificate, LinearError> {
    let analysis = analyse_pitch(lp, gains, options)?;
    let meets_spec = analysis.closed_loop.stable
        && analysis.closed_loop.spectral_abscissa < 0.0
        && spec.met_by(&analysis.margins);
    Ok(Certificate {
        gains: *gains,
        options: *options,
        analysis,
        meets_spec,
    })
}
