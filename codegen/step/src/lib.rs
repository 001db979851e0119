//! The classical fourth-order Runge–Kutta step of ẋ = f(x) on a plain state, for code that runs
//! outside twv's analysis library: an exported FMU's co-simulation (`fmi2DoStep`) and firmware
//! (`no_std`, no allocation). Per entry it does the operations of the analysis library's RK4
//! (`twv_analysis::integrate::Rk4`) in the same order, so a run here has the bits of `twv ride`
//! with the same step.
#![no_std]

/// The equal steps from `t` to `t + rest` of at most about `h`: their number and size. The
/// 1e-9 slack keeps an exact multiple of `h` from turning into one extra tiny step through
/// rounding.
pub fn equal_steps(rest: f64, h: f64) -> (u64, f64) {
    let n = ceil(rest / h * (1.0 - 1e-9)).max(1.0);
    (n as u64, rest / n)
}

/// ⌈x⌉ for x ≥ 0 up to 2^64 (`f64::ceil` is not in `core`); NaN gives 0, as `as u64` does.
fn ceil(x: f64) -> f64 {
    let t = x as u64;
    if (t as f64) < x {
        (t + 1) as f64
    } else {
        t as f64
    }
}

/// Scratch space of [`rk4_step`] for a state of `n` entries: `3 n` values.
pub const fn scratch_len(n: usize) -> usize {
    3 * n
}

/// One RK4 step of size `h` of `y` (`y.len()` entries) under `f(x, out)`, with `scratch` of at
/// least [`scratch_len`]`(y.len())` values; returns whether the new state is finite (`false`:
/// it blew up, and `y` holds the non-finite values). Panics never: a short `scratch` leaves `y`
/// unchanged and returns `false`.
pub fn rk4_step(
    mut f: impl FnMut(&[f64], &mut [f64]),
    y: &mut [f64],
    h: f64,
    scratch: &mut [f64],
) -> bool {
    let n = y.len();
    if scratch.len() < scratch_len(n) {
        return false;
    }
    let (k, rest) = scratch.split_at_mut(n);
    let (acc, rest) = rest.split_at_mut(n);
    let tmp = &mut rest[..n];
    let half = 0.5 * h;
    f(y, k);
    for i in 0..n {
        acc[i] = k[i];
        tmp[i] = y[i] + half * k[i];
    }
    f(tmp, k);
    for i in 0..n {
        acc[i] += 2.0 * k[i];
        tmp[i] = y[i] + half * k[i];
    }
    f(tmp, k);
    for i in 0..n {
        acc[i] += 2.0 * k[i];
        tmp[i] = y[i] + h * k[i];
    }
    f(tmp, k);
    let c = h / 6.0;
    let mut finite = true;
    for i in 0..n {
        y[i] += c * (acc[i] + k[i]);
        finite &= y[i].is_finite();
    }
    finite
}

/// [`rk4_step`] on a fixed-size state with its scratch on the stack.
pub fn rk4_step_array<const N: usize>(
    f: impl FnMut(&[f64], &mut [f64]),
    y: &mut [f64; N],
    h: f64,
) -> bool {
    let mut scratch = [[0.0; N]; 3];
    rk4_step(f, y, h, scratch.as_flattened_mut())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// ẋ = λx: one step multiplies by the degree-4 Taylor polynomial of e^{λh}.
    #[test]
    fn a_step_of_a_linear_equation_is_the_taylor_polynomial() {
        let (lambda, h) = (-1.3, 0.1);
        let mut y = [2.0];
        assert!(rk4_step_array(|x, out| out[0] = lambda * x[0], &mut y, h));
        let z: f64 = lambda * h;
        let taylor = 1.0 + z + z * z / 2.0 + z * z * z / 6.0 + z * z * z * z / 24.0;
        assert!((y[0] - 2.0 * taylor).abs() < 1e-15);
    }

    /// A blow-up is reported; short scratch refuses to step.
    #[test]
    fn a_blow_up_and_short_scratch_are_reported() {
        let mut y = [1.0];
        assert!(!rk4_step_array(
            |_, out| out[0] = f64::INFINITY,
            &mut y,
            0.1
        ));
        let mut y = [1.0, 2.0];
        assert!(!rk4_step(|_, _| {}, &mut y, 0.1, &mut [0.0; 5]));
        assert_eq!(y, [1.0, 2.0]);
    }

    /// An exact multiple is that many steps; any rest is split evenly.
    #[test]
    fn equal_steps_land_on_the_stop() {
        assert_eq!(equal_steps(0.1, 1e-3), (100, 0.1 / 100.0));
        assert_eq!(equal_steps(0.0105, 1e-3).0, 11);
        assert_eq!(equal_steps(1e-4, 1e-3).0, 1);
        for x in [
            0.0,
            0.5,
            1.0,
            1.0 + 1e-15,
            7.3,
            1e6 + 0.25,
            4503599627370497.0,
        ] {
            assert_eq!(ceil(x), f64::ceil(x), "{x}");
        }
    }
}
