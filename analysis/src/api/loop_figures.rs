//! The pitch loop's Bode and Nyquist figures from its frequency response, with the crossings
//! the margins are read at marked: what `twv linear --out` writes and the live page draws.

use crate::linear::LoopResponse;
use crate::plot::{Curve, Figure, Grid, LineChart};

/// |L| beyond which the Nyquist figure does not draw the curve: the margins live near −1,
/// and an integrator's L(j0⁺) is unbounded.
pub const NYQUIST_CLIP: f64 = 5.0;

const PANEL: (u32, u32) = (900, 380);

fn vertical(name: String, x: f64, ys: &[f64]) -> Curve {
    let (lo, hi) = ys
        .iter()
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    Curve {
        name,
        points: vec![(x, lo), (x, hi)],
    }
}

fn horizontal(name: &str, y: f64, w: &[f64]) -> Curve {
    Curve {
        name: name.into(),
        points: vec![(w[0], y), (w[w.len() - 1], y)],
    }
}

/// The odd multiple of 180° nearest the phase at the first phase crossover (or the phase's
/// mean): the line the phase margin is measured from.
fn critical_phase(r: &LoopResponse) -> f64 {
    let at = r.phase_crossovers.iter().copied().find(|w| *w > 0.0);
    let reference = match at.and_then(|w| r.w.iter().position(|&x| x >= w)) {
        Some(i) => r.phase_deg[i],
        None => r.phase_deg.iter().sum::<f64>() / r.phase_deg.len() as f64,
    };
    180.0 * (2.0 * ((reference - 180.0) / 360.0).round() + 1.0)
}

/// Magnitude and phase against ω (log), the gain crossovers and phase crossovers as vertical
/// lines; `None` if the response is empty.
pub fn bode(title: &str, r: &LoopResponse) -> Option<Figure> {
    if r.w.len() < 2 {
        return None;
    }
    let points = |ys: &[f64]| r.w.iter().copied().zip(ys.iter().copied()).collect();
    let mut magnitude = vec![
        Curve {
            name: "|L(jω)| [dB]".into(),
            points: points(&r.magnitude_db),
        },
        horizontal("0 dB", 0.0, &r.w),
    ];
    let critical = critical_phase(r);
    let mut phase = vec![
        Curve {
            name: "∠L(jω) [°]".into(),
            points: points(&r.phase_deg),
        },
        horizontal(&format!("{critical:.0}°"), critical, &r.w),
    ];
    for &w in &r.gain_crossovers {
        magnitude.push(vertical(
            format!("|L| = 1 at {w:.3} rad/s"),
            w,
            &r.magnitude_db,
        ));
        phase.push(vertical(
            format!("|L| = 1 at {w:.3} rad/s"),
            w,
            &r.phase_deg,
        ));
    }
    for &w in r.phase_crossovers.iter().filter(|w| **w > 0.0) {
        magnitude.push(vertical(
            format!("∠L = 180° at {w:.3} rad/s"),
            w,
            &r.magnitude_db,
        ));
    }
    let panel = |name: &str, y: &str, curves| {
        let mut chart = LineChart::new(name, "ω [rad/s]", y, PANEL, curves);
        chart.log_x = true;
        chart
    };
    Some(Figure::Grid(Grid {
        panels: vec![
            panel(&format!("{title}: Bode magnitude"), "|L| [dB]", magnitude),
            panel(&format!("{title}: Bode phase"), "∠L [°]", phase),
        ],
        columns: 1,
    }))
}

/// The circle of `radius` about (`center`, 0), 180 segments.
fn circle(center: f64, radius: f64) -> Vec<(f64, f64)> {
    (0..=180)
        .map(|k| {
            let t = k as f64 * std::f64::consts::TAU / 180.0;
            (center + radius * t.cos(), radius * t.sin())
        })
        .collect()
}

/// Im L against Re L for ω > 0 and its mirror image (ω < 0), the unit circle, the critical
/// point −1 and the disk margin's exclusion disk, within |L| ≤ [`NYQUIST_CLIP`]; `None` if no point is that close.
pub fn nyquist(title: &str, r: &LoopResponse) -> Option<Figure> {
    let near: Vec<(f64, f64)> =
        r.re.iter()
            .zip(&r.im)
            .filter(|(a, b)| a.hypot(**b) <= NYQUIST_CLIP)
            .map(|(a, b)| (*a, *b))
            .collect();
    if near.len() < 2 {
        return None;
    }
    let mut curves = vec![
        Curve {
            name: "L(jω), ω > 0".into(),
            points: near.clone(),
        },
        Curve {
            name: "L(jω), ω < 0".into(),
            points: near.iter().map(|(a, b)| (*a, -b)).collect(),
        },
        Curve {
            name: "|L| = 1".into(),
            points: circle(0.0, 1.0),
        },
        Curve {
            name: "−1".into(),
            points: vec![
                (-1.08, 0.0),
                (-0.92, 0.0),
                (-1.0, 0.0),
                (-1.0, 0.08),
                (-1.0, -0.08),
            ],
        },
    ];
    if let Some(d) = &r.disk {
        curves.push(Curve {
            name: "disk margin".into(),
            points: circle(d.center, d.radius),
        });
    }
    Some(Figure::Line(LineChart::new(
        &format!("{title}: Nyquist (|L| ≤ {NYQUIST_CLIP})"),
        "Re L",
        "Im L",
        (760, 640),
        curves,
    )))
}
