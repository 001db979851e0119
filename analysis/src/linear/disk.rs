//! Balanced (symmetric) disk margins, after P. Seiler, A. Packard and P. Gahinet, "An
//! introduction to disk margins", IEEE Control Systems Magazine 40(5):78–95, 2020.
//!
//! The loop gain is perturbed by a factor f in the disk D(α, σ) = {(1 + (1−σ)/2 δ) /
//! (1 − (1+σ)/2 δ) : |δ| ≤ α}. With a stable nominal loop, the largest α for which every such
//! f keeps it stable is α_max = 1/‖S + (σ − 1)/2‖∞, S = 1/(1 + L). For the balanced disk
//! (σ = 0): α_max = 1/‖S − ½‖∞ = 2/‖S − T‖∞, since S − ½ = ½ (S − T) with T = L/(1 + L).
//! That disk covers the gain factors [(2 − α)/(2 + α), (2 + α)/(2 − α)] (the disk gain margin)
//! and phase changes of ±2 atan(α/2) (the disk phase margin).

use nalgebra::Complex;

/// The balanced disk margin and what it guarantees.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DiskMargin {
    /// α_max = 1/‖S − ½‖∞ (0 for an unstable loop).
    pub alpha: f64,
    /// Smallest tolerated gain factor (2 − α)/(2 + α) (0 when α ≥ 2).
    pub gain_low: f64,
    /// Largest tolerated gain factor (2 + α)/(2 − α) (∞ when α ≥ 2).
    pub gain_high: f64,
    /// Tolerated phase change 2 atan(α/2), degrees.
    pub phase_deg: f64,
    /// Frequency (rad/s) where |S − ½| peaks (0 for a peak at DC, ∞ for one at infinity).
    pub frequency: f64,
}

impl DiskMargin {
    /// The margins that the disk of size `alpha` guarantees.
    pub fn from_alpha(alpha: f64, frequency: f64) -> Self {
        let alpha = alpha.max(0.0);
        let (gain_low, gain_high) = if alpha >= 2.0 {
            (0.0, f64::INFINITY)
        } else {
            ((2.0 - alpha) / (2.0 + alpha), (2.0 + alpha) / (2.0 - alpha))
        };
        Self {
            alpha,
            gain_low,
            gain_high,
            phase_deg: 2.0 * (alpha / 2.0).atan().to_degrees(),
            frequency,
        }
    }
}

/// α of the balanced disk whose phase margin is `deg` degrees: α = 2 tan(deg/2).
pub fn alpha_from_phase_deg(deg: f64) -> f64 {
    2.0 * (deg.to_radians() / 2.0).tan()
}

/// α of the balanced disk whose upper gain margin is the factor `g` > 1: α = 2(g − 1)/(g + 1).
pub fn alpha_from_gain(g: f64) -> f64 {
    2.0 * (g - 1.0) / (g + 1.0)
}

/// |S − ½| = |1 − L| / (2 |1 + L|); ½ for an infinite L.
pub fn balanced_sensitivity(l: Option<Complex<f64>>) -> f64 {
    match l {
        Some(l) => (Complex::new(1.0, 0.0) - l).norm() / (2.0 * (l + 1.0).norm()),
        None => 0.5,
    }
}

/// A disk in the complex plane centred on the real axis, which L(jω) must avoid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disk {
    /// Centre (real).
    pub centre: f64,
    /// Radius.
    pub radius: f64,
}

impl Disk {
    /// The set of L with |S − ½| ≥ 1/α, i.e. where a perturbation in D(α, 0) can reach −1:
    /// the disk through the real points −γ and −1/γ, γ = (2 + α)/(2 − α). `None` for α ≥ 2
    /// (the region is then a half-plane or the outside of a disk, not a disk).
    pub fn balanced(alpha: f64) -> Option<Self> {
        if !(0.0..2.0).contains(&alpha) {
            return None;
        }
        let g = (2.0 + alpha) / (2.0 - alpha);
        Some(Self {
            centre: -(g + 1.0 / g) / 2.0,
            radius: (g - 1.0 / g) / 2.0,
        })
    }

    /// The set of L with |S| ≥ `ms`: the disk of radius 1/ms around −1.
    pub fn sensitivity(ms: f64) -> Self {
        Self {
            centre: -1.0,
            radius: 1.0 / ms,
        }
    }
}
