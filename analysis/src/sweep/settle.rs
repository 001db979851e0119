//! The settled-tail shortcut of the max-Lyapunov metric: once a closed loop has come to rest,
//! the rest of its horizon is linear, and is computed in one go instead of step by step.
//!
//! At rest at x*, the tangent obeys ẇ = P J(x*) w (P: the kept pitch-loop coordinates), and
//! RK4 with step h advances it by the fixed matrix S = I + hA + (hA)²/2 + (hA)³/6 + (hA)⁴/24,
//! A = P J(x*). With one tangent vector the per-interval growth factors of the remaining m steps
//! multiply to ‖Sᵐ w‖, so their log sum is ln ‖Sᵐ w‖: about 14 squarings of an NA × NA matrix
//! instead of m steps of the closed loop (10⁴ for a loop settled at the start of the average).
//!
//! "At rest" is judged at an interval end after the transient: the interval's local exponent
//! r = ln R / T is negative and the pitch-loop state's speed is at most `distance · |r|` — were
//! it decaying at rate r, it has at most `distance` (state units) left to go. What is left of
//! the motion then changes J by O(distance), which moves λ1 by much less: on the study's
//! 100 × 100 (Kp, Kd) map with the default distance 3·10⁻³ no point's λ1 moved by more than
//! [`SETTLED_TAIL_TOLERANCE`] (README, Stability maps; `tests/tests/all/sweep_lanes.rs` checks it on a
//! grid whose points settle early, late, slowly and not at all). A loop still moving (unstable,
//! oscillating, neutral) never qualifies and runs every step.

use nalgebra::SMatrix;

use crate::integrate::{project, Projected, VectorField};

/// The largest change of a point's λ1 [1/s] the shortcut is allowed, against the same point
/// run step by step to the end (checked by the tests and the map benchmark).
pub const SETTLED_TAIL_TOLERANCE: f64 = 1e-3;

/// Whether the loop `field` (its tangent projected onto `field.keep`) is at rest at `x` (time
/// `t`) after an interval whose local exponent was `rate` [1/s].
pub(super) fn at_rest<F: VectorField<N>, const N: usize>(
    field: &Projected<F, N>,
    t: f64,
    x: &[f64; N],
    rate: f64,
    distance: f64,
) -> bool {
    if rate.is_nan() || rate >= 0.0 {
        return false;
    }
    let mut f = [0.0; N];
    field.rhs(t, x, &mut f);
    project(&field.keep, &mut f);
    let speed = f.iter().map(|v| v * v).sum::<f64>().sqrt();
    speed <= distance * -rate
}

/// Σ ln R over the next `steps` RK4 steps of size `h` of the unit tangent `w` at rest at `x`:
/// ln ‖Sᵐ w‖ (module docs); `None` if it is not finite (the caller then keeps stepping).
pub(super) fn tail_log_growth<F: VectorField<N>, const N: usize>(
    field: &F,
    t: f64,
    x: &[f64; N],
    w: &[f64; N],
    h: f64,
    steps: u64,
) -> Option<f64> {
    // The columns of P J: the projected field's tangent derivatives of the unit vectors.
    let unit: [[f64; N]; N] = core::array::from_fn(|j| core::array::from_fn(|i| f64::from(i == j)));
    let (mut f, mut columns) = ([0.0; N], [[0.0; N]; N]);
    field.eval::<N>(t, x, &unit, &mut f, &mut columns);
    log_growth(&columns, w, h, steps)
}

/// The field-independent part of [`tail_log_growth`], from the columns of P J: compiled once
/// per state size rather than once per field.
#[inline(never)]
fn log_growth<const N: usize>(
    columns: &[[f64; N]; N],
    w: &[f64; N],
    h: f64,
    steps: u64,
) -> Option<f64> {
    let a = SMatrix::<f64, N, N>::from_fn(|i, j| h * columns[j][i]);
    let id = SMatrix::<f64, N, N>::identity();
    // S = I + A (I + A/2 (I + A/3 (I + A/4))).
    let mut power = id + a * (id + a * (id + a * (id + a / 4.0) / 3.0) / 2.0);
    // Binary powering; `power` is kept at unit size, its scale in `power_log`.
    let mut v = nalgebra::SVector::<f64, N>::from_column_slice(w);
    let (mut log, mut power_log, mut m) = (0.0, 0.0, steps);
    while m > 0 {
        if m & 1 == 1 {
            v = power * v;
            let n = v.norm();
            log += n.ln() + power_log;
            v /= n;
        }
        m >>= 1;
        if m > 0 {
            power = power * power;
            power_log *= 2.0;
            let n = power.amax();
            power /= n;
            power_log += n.ln();
        }
    }
    log.is_finite().then_some(log)
}
