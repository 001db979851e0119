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
    // Gains so large that the loop's matrix spans more than a double holds (a Ki of 1e86) give
    // NaN poles: an input error, never poles and margins printed as NaN.
    if closed_loop
        .loop_eigenvalues
        .iter()
        .any(|e| !(e.re.is_finite() && e.im.is_finite()))
    {
        return Err(LinearError::NonFinite {
            what: "closed-loop poles (the gains are too large for double precision)",
        });
    }
    let grid = GridOptions::around(&loop_scales(lp, gains, opts, &closed_loop)?);
    let l0 = |w: f64| lp.loop_delay_free(gains, opts.lag, w);
    let margins = loop_margins(&l0, opts.delay, closed_loop.stable, &grid);
    Ok(PitchAnalysis {
        closed_loop,
        margins,
    })
}

/// The loop's return ratio L(jω) on a log grid: what a Bode and a Nyquist plot draw, with the
/// crossings the margins come from (to mark them). Frequencies where L has a pole on the axis
/// (ω = 0 with an integrator) are left out.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct LoopResponse {
    /// Frequencies [rad/s], increasing.
    pub w: Vec<f64>,
    /// Re L(jω).
    pub re: Vec<f64>,
    /// Im L(jω).
    pub im: Vec<f64>,
    /// 20 log10 |L(jω)| [dB].
    pub magnitude_db: Vec<f64>,
    /// ∠L(jω) [deg], unwrapped along the grid (continuous, starting in (−180°, 180°]).
    pub phase_deg: Vec<f64>,
    /// Where |L| = 1 [rad/s] (the phase margin is read there).
    pub gain_crossovers: Vec<f64>,
    /// Where L is real and negative [rad/s] (the gain margins are read there).
    pub phase_crossovers: Vec<f64>,
    /// The balanced disk margin's exclusion disk in the L plane (stable loops with α < 2).
    pub disk: Option<ExclusionDisk>,
}

/// The points L must avoid for the loop to stay stable under every gain and phase change of
/// the balanced disk of size α: {−1/f : f ∈ D(α, 0)}, the disk on the real axis between
/// −1/gain_low and −1/gain_high. It contains −1, and L(jω) touches it at the frequency where
/// the disk margin is attained.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ExclusionDisk {
    /// Centre (on the real axis).
    pub center: f64,
    /// Radius.
    pub radius: f64,
    /// Where L touches it [rad/s].
    pub frequency: f64,
}

impl ExclusionDisk {
    /// The disk of a stable loop's disk margin; `None` for an unstable loop or α ≥ 2 (then the
    /// region is a half-plane or more).
    pub fn of(margins: &Margins) -> Option<Self> {
        let d = &margins.disk;
        (margins.stable && d.alpha > 0.0 && d.alpha < 2.0).then(|| {
            let (far, near) = (-1.0 / d.gain_low, -1.0 / d.gain_high);
            Self {
                center: 0.5 * (far + near),
                radius: 0.5 * (near - far),
                frequency: d.frequency,
            }
        })
    }
}

/// L(jω) of `lp` at `points` log-spaced frequencies two decades either side of the loop's
/// characteristic frequencies ([`loop_scales`]), delay included.
pub fn loop_response(
    lp: &PitchLoop,
    gains: &PidGains,
    opts: &LoopOptions,
    analysis: &PitchAnalysis,
    points: usize,
) -> Result<LoopResponse, LinearError> {
    let scales = loop_scales(lp, gains, opts, &analysis.closed_loop)?;
    let wide = GridOptions::around(&scales);
    let (lo, hi) = (wide.w_min * 1e3, wide.w_max * 1e-3);
    let n = points.max(2);
    let mut r = LoopResponse {
        w: Vec::with_capacity(n),
        re: Vec::with_capacity(n),
        im: Vec::with_capacity(n),
        magnitude_db: Vec::with_capacity(n),
        phase_deg: Vec::with_capacity(n),
        gain_crossovers: analysis.margins.gain_crossovers.clone(),
        phase_crossovers: analysis.margins.phase_crossovers.clone(),
        disk: ExclusionDisk::of(&analysis.margins),
    };
    for k in 0..n {
        let w = lo * (hi / lo).powf(k as f64 / (n - 1) as f64);
        let Some(l) = lp.loop_response(gains, opts, w) else {
            continue;
        };
        let mut phase = l.arg().to_degrees();
        if let Some(&prev) = r.phase_deg.last() {
            phase += 360.0 * ((prev - phase) / 360.0).round();
        }
        r.w.push(w);
        r.re.push(l.re);
        r.im.push(l.im);
        r.magnitude_db.push(20.0 * l.norm().log10());
        r.phase_deg.push(phase);
    }
    Ok(r)
}
