//! Everything `twv linear` prints about a pitch loop, in one call: closed-loop eigenvalues
//! (loop and hidden drift) and the margins on a grid placed around the loop's own frequencies.

use super::error::LinearError;
use super::margins::{loop_margins, GridOptions, Margins};
use super::pitch::{ClosedLoop, LoopOptions, PidGains, PitchLoop};

/// Closed-loop spectrum and margins of a pitch loop.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PitchAnalysis {
    /// Eigenvalues (delay-free) and the hidden modes.
    pub closed_loop: ClosedLoop,
    /// Gain, phase, delay and disk margins (delay included).
    pub margins: Margins,
}

/// The characteristic frequencies of the loop (plant poles, closed-loop poles, controller
/// zeros, 1/τ, 1/T), around which the frequency grid is laid.
pub fn loop_scales(
    lp: &PitchLoop,
    gains: &PidGains,
    opts: &LoopOptions,
    closed: &ClosedLoop,
) -> Result<Vec<f64>, LinearError> {
    let mut s: Vec<f64> = lp.plant().poles()?.iter().map(|p| p.norm()).collect();
    s.extend(closed.loop_eigenvalues.iter().map(|p| p.norm()));
    if gains.kd != 0.0 {
        s.push((gains.kp / gains.kd).abs());
        s.push((gains.ki / gains.kd).abs().sqrt());
    }
    for t in [opts.lag, opts.delay] {
        if t > 0.0 {
            s.push(1.0 / t);
        }
    }
    Ok(s)
}

/// Closed-loop eigenvalues and margins of the pitch loop with `gains`.
pub fn analyse_pitch(
    lp: &PitchLoop,
    gains: &PidGains,
    opts: &LoopOptions,
) -> Result<PitchAnalysis, LinearError> {
    let closed_loop = lp.closed_loop(gains, opts)?;
    let grid = GridOptions::around(&loop_scales(lp, gains, opts, &closed_loop)?);
    let l0 = |w: f64| lp.loop_delay_free(gains, opts.lag, w);
    let margins = loop_margins(&l0, opts.delay, closed_loop.stable, &grid);
    Ok(PitchAnalysis {
        closed_loop,
        margins,
    })
}
