//! Classical and disk margins of a SISO loop L(jω) = L0(jω) e^{−jωT} from its frequency
//! response, for loops whose open loop may be unstable (the pitch loop is: the upright
//! pendulum has a pole at +λ).
//!
//! With an unstable open loop, "the phase at which |L| = 1" alone says nothing about
//! stability (the Nyquist criterion needs the encirclement count). So stability of the nominal
//! loop is an *input* (from closed-loop eigenvalues, see [`super::pitch::ClosedLoop`]) and the
//! margins are computed as distances to instability: the closed-loop poles can only cross the
//! imaginary axis at a frequency where k L(jω) e^{−jφ} = −1, so
//! - the gain margins are the critical gains 1/|L(jω)| at the phase crossovers (L(jω) real
//!   negative, DC included) nearest to 1 from above and from below;
//! - the phase margin is the smallest |∠L(jω_c) + 180°| over the gain crossovers |L(jω_c)| = 1;
//! - the delay the loop still tolerates is min over crossovers of (∠L + 180° mod 360°)/ω_c;
//! - with a delay T the loop is stable iff its delay-free part is and T is below the delay-free
//!   loop's delay margin (first crossing; a later return to stability at larger delays is not
//!   claimed, a conservative reading);
//! - the balanced disk margin is α = 1/sup_ω |S − ½| (see [`super::disk`]), 0 if unstable.
//!
//! Everything is evaluated on a log grid (refined where the phase turns fast, as it does with
//! a delay), crossings are bisected to machine precision and peaks refined by golden section,
//! so results are accurate to far better than 1e-6 relative. L is assumed strictly proper
//! (|L| → 0 as ω → ∞), as every physical loop is.

use nalgebra::Complex;

use super::disk::{balanced_sensitivity, DiskMargin};
use super::freq::{bisect_root, golden_max, log_grid};

/// The frequency range and density to evaluate on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridOptions {
    /// Lowest frequency (rad/s, > 0); ω = 0 is evaluated separately.
    pub w_min: f64,
    /// Highest frequency (rad/s).
    pub w_max: f64,
    /// Base density before refinement.
    pub points_per_decade: usize,
    /// Below this |L| the grid is not refined: there a delay spins the phase ever faster
    /// while nothing can happen (|S − ½| ≈ ½, no gain crossover); only phase crossovers with
    /// a critical gain above 1/`refine_floor` may go unresolved (reported as an infinite
    /// margin). 1e-4 (80 dB) by default; a stability-only check can use 0.1.
    pub refine_floor: f64,
}

impl GridOptions {
    /// Five decades either side of the loop's characteristic frequencies, 200 points a decade.
    pub fn around(scales: &[f64]) -> Self {
        let pos = scales.iter().copied().filter(|s| s.is_finite() && *s > 0.0);
        let lo = pos.clone().fold(f64::INFINITY, f64::min);
        let hi = pos.fold(0.0, f64::max);
        let (lo, hi) = if hi > 0.0 { (lo, hi) } else { (1.0, 1.0) };
        Self {
            w_min: lo * 1e-5,
            w_max: hi * 1e5,
            points_per_decade: 200,
            refine_floor: 1e-4,
        }
    }
}

/// Margins of a loop. Gain, phase and delay margins are meaningful only when `stable`; a loop
/// that its delay destabilises reports no phase crossover and the delay-free gain crossovers.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Margins {
    /// Nominal closed loop stable, delay included.
    pub stable: bool,
    /// Factor by which the loop gain may grow before instability (∞: any).
    pub gain_margin_upper: f64,
    /// Factor to which the loop gain may shrink before instability (0: any). For the pitch
    /// loop this is M_x g / Kp: below it the pendulum falls.
    pub gain_margin_lower: f64,
    /// Frequencies (rad/s) where L is real negative (0 = DC).
    pub phase_crossovers: Vec<f64>,
    /// Frequencies (rad/s) where |L| = 1.
    pub gain_crossovers: Vec<f64>,
    /// Smallest |∠L + 180°| over the gain crossovers, degrees (∞: no crossover).
    pub phase_margin_deg: f64,
    /// Gain crossover where the phase margin is attained (NaN: none).
    pub phase_margin_frequency: f64,
    /// Extra delay (s) the loop tolerates (∞: any).
    pub delay_margin: f64,
    /// Balanced disk margin.
    pub disk: DiskMargin,
    /// Peak sensitivity Ms = sup |S| (∞ if unstable).
    pub peak_sensitivity: f64,
}

/// Computes the margins of L(jω) = l0(ω) e^{−jωT}. `l0` is the delay-free frequency response
/// (`None` at a pole on the axis), `delay_free_stable` says whether the delay-free closed loop
/// is stable (from its eigenvalues).
pub fn loop_margins(
    l0: &dyn Fn(f64) -> Option<Complex<f64>>,
    delay: f64,
    delay_free_stable: bool,
    grid: &GridOptions,
) -> Margins {
    if delay > 0.0 {
        // |L| and so the gain crossovers do not depend on the delay, and the delay-free loop's
        // delay margin says whether this one is stable. When it is not, no margin is defined and
        // the delayed L is not resolved: its phase spins at ωT, so resolving it would take work
        // growing with the delay without bound (a delay of hours is an input, not a loop).
        let free = loop_margins(l0, 0.0, delay_free_stable, grid);
        if !(free.stable && delay < free.delay_margin) {
            return Margins {
                stable: false,
                phase_crossovers: Vec::new(),
                gain_margin_upper: f64::INFINITY,
                gain_margin_lower: 0.0,
                delay_margin: (free.delay_margin - delay).max(0.0),
                disk: DiskMargin::from_alpha(0.0, free.disk.frequency),
                peak_sensitivity: f64::INFINITY,
                ..free
            };
        }
    }
    let l = |w: f64| l0(w).map(|v| v * Complex::from_polar(1.0, -w * delay));
    let pts = refined_grid(&l, grid);

    // Gain crossovers: sign changes of ln|L|.
    let log_mag = |w: f64| l(w).map_or(f64::INFINITY, |v| v.norm().ln());
    let gain_crossovers: Vec<f64> = pts
        .windows(2)
        .filter(|p| (p[0].1.norm() < 1.0) != (p[1].1.norm() < 1.0))
        .map(|p| bisect_root(log_mag, p[0].0, p[1].0))
        .collect();

    // Phase crossovers: L real negative. DC first (there L is real for a real system).
    let mut phase_crossovers = Vec::new();
    let mut critical = Vec::new();
    if let Some(l_dc) = l0(0.0) {
        if l_dc.re < 0.0 && l_dc.norm() > 0.0 {
            phase_crossovers.push(0.0);
            critical.push(1.0 / l_dc.norm());
        }
    }
    let im = |w: f64| l(w).map_or(f64::NAN, |v| v.im);
    for p in pts.windows(2) {
        let (a, b) = (p[0].1, p[1].1);
        if (a.im < 0.0) != (b.im < 0.0) && (a.re < 0.0 || b.re < 0.0) {
            let w = bisect_root(im, p[0].0, p[1].0);
            if let Some(v) = l(w) {
                if v.re < 0.0 {
                    phase_crossovers.push(w);
                    critical.push(1.0 / v.norm());
                }
            }
        }
    }
    let gain_margin_upper = critical
        .iter()
        .copied()
        .filter(|&k| k > 1.0)
        .fold(f64::INFINITY, f64::min);
    let gain_margin_lower = critical
        .iter()
        .copied()
        .filter(|&k| k < 1.0)
        .fold(0.0, f64::max);

    // Phase and delay margins at the gain crossovers.
    let mut phase_margin_deg = f64::INFINITY;
    let mut phase_margin_frequency = f64::NAN;
    let mut delay_margin_free = f64::INFINITY;
    let two_pi = 2.0 * std::f64::consts::PI;
    for &w in &gain_crossovers {
        if let (Some(v), Some(v0)) = (l(w), l0(w)) {
            let pm = (v.arg() + std::f64::consts::PI).rem_euclid(two_pi);
            let pm_signed = if pm > std::f64::consts::PI {
                pm - two_pi
            } else {
                pm
            };
            if pm_signed.abs().to_degrees() < phase_margin_deg {
                phase_margin_deg = pm_signed.abs().to_degrees();
                phase_margin_frequency = w;
            }
            let pm0 = (v0.arg() + std::f64::consts::PI).rem_euclid(two_pi);
            if w > 0.0 {
                delay_margin_free = delay_margin_free.min(pm0 / w);
            }
        }
    }
    let stable = delay_free_stable && (delay == 0.0 || delay < delay_margin_free);

    // Disk margin and peak sensitivity: grid maxima refined by golden section, plus the
    // limits at DC and at infinity (|S − ½| → ½, |S| → 1 for a strictly proper loop).
    let h = |w: f64| balanced_sensitivity(l(w));
    let sens = |w: f64| l(w).map_or(0.0, |v| 1.0 / (v + 1.0).norm());
    let (mut h_peak, mut h_freq) = (0.5, f64::INFINITY);
    let h_dc = balanced_sensitivity(l0(0.0));
    if h_dc > h_peak {
        (h_peak, h_freq) = (h_dc, 0.0);
    }
    let (w_h, v_h) = refine_peak(&pts, &h);
    if v_h > h_peak {
        (h_peak, h_freq) = (v_h, w_h);
    }
    let ms_dc = l0(0.0).map_or(0.0, |v| 1.0 / (v + 1.0).norm());
    let peak_sensitivity = refine_peak(&pts, &sens).1.max(ms_dc).max(1.0);

    let disk = if stable {
        DiskMargin::from_alpha(1.0 / h_peak, h_freq)
    } else {
        DiskMargin::from_alpha(0.0, h_freq)
    };
    Margins {
        stable,
        gain_margin_upper,
        gain_margin_lower,
        phase_crossovers,
        gain_crossovers,
        phase_margin_deg,
        phase_margin_frequency,
        delay_margin: (delay_margin_free - delay).max(0.0),
        disk,
        peak_sensitivity: if stable {
            peak_sensitivity
        } else {
            f64::INFINITY
        },
    }
}

/// The log grid with points inserted wherever L turns by more than 0.25 rad between
/// neighbours (so crossings are not skipped when a delay spins the phase).
fn refined_grid(
    l: &dyn Fn(f64) -> Option<Complex<f64>>,
    grid: &GridOptions,
) -> Vec<(f64, Complex<f64>)> {
    let base: Vec<(f64, Complex<f64>)> = log_grid(grid.w_min, grid.w_max, grid.points_per_decade)
        .into_iter()
        .filter_map(|w| l(w).map(|v| (w, v)))
        .collect();
    let mut out = Vec::with_capacity(base.len());
    for p in base.windows(2) {
        out.push(p[0]);
        let mut stack = vec![(p[0], p[1], 0u32)];
        let mut inner = Vec::new();
        while let Some((a, b, depth)) = stack.pop() {
            let turn = (b.1 / a.1).arg().abs();
            let visible = a.1.norm().max(b.1.norm()) >= grid.refine_floor;
            if turn > 0.25 && visible && depth < 24 {
                let w = (a.0 * b.0).sqrt();
                if let Some(v) = l(w) {
                    stack.push(((w, v), b, depth + 1));
                    stack.push((a, (w, v), depth + 1));
                    continue;
                }
            }
            inner.push(b);
        }
        out.extend(inner.into_iter().filter(|q| q.0 < p[1].0));
    }
    if let Some(last) = base.last() {
        out.push(*last);
    }
    out
}

/// The largest value of `f` on the grid, refined by golden section between the neighbours of
/// each of the five largest local maxima.
fn refine_peak(pts: &[(f64, Complex<f64>)], f: &dyn Fn(f64) -> f64) -> (f64, f64) {
    let vals: Vec<f64> = pts.iter().map(|p| f(p.0)).collect();
    let mut local: Vec<usize> = (0..vals.len())
        .filter(|&i| {
            (i == 0 || vals[i] >= vals[i - 1]) && (i + 1 == vals.len() || vals[i] >= vals[i + 1])
        })
        .collect();
    local.sort_by(|&a, &b| vals[b].total_cmp(&vals[a]));
    let mut best = (f64::NAN, f64::NEG_INFINITY);
    for &i in local.iter().take(5) {
        let a = pts[i.saturating_sub(1)].0;
        let b = pts[(i + 1).min(pts.len() - 1)].0;
        let cand = if a < b {
            golden_max(f, a, b, 1e-12)
        } else {
            (pts[i].0, vals[i])
        };
        let cand = if cand.1 >= vals[i] {
            cand
        } else {
            (pts[i].0, vals[i])
        };
        if cand.1 > best.1 {
            best = cand;
        }
    }
    best
}
