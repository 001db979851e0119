//! One-dimensional numerics on the frequency axis: log-spaced grids, golden-section refinement
//! of a peak and bisection of a crossing. Shared by the margin computation and the tuner.

/// `points_per_decade` log-spaced frequencies from `lo` to `hi` inclusive (`lo`, `hi` > 0).
///
/// At most [`MAX_DECADES`] decades above `lo`: loop scales of absurd gains (Kp = 1e300) put
/// `hi` at infinity, which must make a long grid, not an infinite one.
pub fn log_grid(lo: f64, hi: f64, points_per_decade: usize) -> Vec<f64> {
    let hi = hi.min(lo * 10f64.powi(MAX_DECADES));
    let decades = (hi / lo).log10().max(0.0);
    let decades = if decades.is_finite() { decades } else { 0.0 };
    let n = ((decades * points_per_decade.max(1) as f64).ceil() as usize).max(1);
    (0..=n)
        .map(|k| lo * (hi / lo).powf(k as f64 / n as f64))
        .collect()
}

/// The most decades a frequency grid spans.
pub const MAX_DECADES: i32 = 60;

/// Maximum of `f` on [a, b] (a, b > 0) by golden-section search in ln ω, down to a relative
/// bracket of `rel_tol`. Returns (ω, f(ω)); assumes one peak in the bracket, which the caller
/// ensures by bracketing a grid maximum by its neighbours.
pub fn golden_max(f: impl Fn(f64) -> f64, a: f64, b: f64, rel_tol: f64) -> (f64, f64) {
    let inv_phi = (5f64.sqrt() - 1.0) / 2.0;
    let (mut lo, mut hi) = (a.ln(), b.ln());
    let g = |x: f64| f(x.exp());
    let mut x1 = hi - inv_phi * (hi - lo);
    let mut x2 = lo + inv_phi * (hi - lo);
    let (mut f1, mut f2) = (g(x1), g(x2));
    while hi - lo > rel_tol {
        if f1 >= f2 {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - inv_phi * (hi - lo);
            f1 = g(x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + inv_phi * (hi - lo);
            f2 = g(x2);
        }
    }
    if f1 >= f2 {
        (x1.exp(), f1)
    } else {
        (x2.exp(), f2)
    }
}

/// A root of `f` in [a, b] where `f(a)` and `f(b)` differ in sign, by bisection in ln ω to
/// machine precision. Non-finite values of `f` count as positive.
pub fn bisect_root(f: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let neg = |x: f64| f(x) < 0.0;
    let (mut lo, mut hi) = (a.ln(), b.ln());
    let lo_neg = neg(a);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if neg(mid.exp()) == lo_neg {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (0.5 * (lo + hi)).exp()
}
