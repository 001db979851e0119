//! Sine and cosine of one angle with one shared argument reduction, inlined into the kernels.
//!
//! Why not `f64::sin` / `f64::cos`: those are calls into the C library (13.5 ns for a merged
//! `sincos` here, two of them per vehicle evaluation: most of the time of `f`). The vehicle's
//! angles are small or moderate, so a Cody–Waite reduction modulo π/2 (valid for
//! |x| < 2^20·π/2 ≈ 1.6e6) and the minimax polynomials of Sun's fdlibm (error < 2^-58 on
//! [-π/4, π/4]; the algorithm FreeBSD and musl ship; evaluated in Estrin's scheme, a shorter
//! dependent chain, where the argument needs no reduction) give the same accuracy inline: < 1 ulp,
//! checked against the C library in the tests. Larger or non-finite arguments fall back to the
//! C library. Both the generated code and the IR interpreter call these functions, so they stay
//! bit-identical to each other.

/// 53 bits of 2/π.
pub(crate) const INV_PIO2: f64 = f64::from_bits(0x3FE4_5F30_6DC9_C883);
/// π/2 in three 33-bit pieces and their tails (fdlibm's `pio2_1`, `pio2_1t`, ...).
pub(crate) const PIO2_1: f64 = f64::from_bits(0x3FF9_21FB_5440_0000);
pub(crate) const PIO2_1T: f64 = f64::from_bits(0x3DD0_B461_1A62_6331);
pub(crate) const PIO2_2: f64 = f64::from_bits(0x3DD0_B461_1A60_0000);
pub(crate) const PIO2_2T: f64 = f64::from_bits(0x3BA3_198A_2E03_7073);
pub(crate) const PIO2_3: f64 = f64::from_bits(0x3BA3_198A_2E00_0000);
pub(crate) const PIO2_3T: f64 = f64::from_bits(0x397B_839A_2520_49C1);
/// 1.5·2^52: adding and subtracting it rounds a double of magnitude < 2^51 to an integer.
pub(crate) const TO_INT: f64 = 6_755_399_441_055_744.0;

/// sin on [-π/4, π/4]: x − x³/6 + … (degree 13).
pub(crate) const S1: f64 = f64::from_bits(0xBFC5_5555_5555_5549);
pub(crate) const S2: f64 = f64::from_bits(0x3F81_1111_1110_F8A6);
pub(crate) const S3: f64 = f64::from_bits(0xBF2A_01A0_19C1_61D5);
pub(crate) const S4: f64 = f64::from_bits(0x3EC7_1DE3_57B1_FE7D);
pub(crate) const S5: f64 = f64::from_bits(0xBE5A_E5E6_8A2B_9CEB);
pub(crate) const S6: f64 = f64::from_bits(0x3DE5_D93A_5ACF_D57C);
/// cos on [-π/4, π/4]: 1 − x²/2 + … (degree 14).
pub(crate) const C1: f64 = f64::from_bits(0x3FA5_5555_5555_554C);
pub(crate) const C2: f64 = f64::from_bits(0xBF56_C16C_16C1_5177);
pub(crate) const C3: f64 = f64::from_bits(0x3EFA_01A0_19CB_1590);
pub(crate) const C4: f64 = f64::from_bits(0xBE92_7E4F_809C_52AD);
pub(crate) const C5: f64 = f64::from_bits(0x3E21_EE9E_BDB4_B1C4);
pub(crate) const C6: f64 = f64::from_bits(0xBDA8_FAE9_BE88_38D4);

/// High 32 bits of |x|'s representation at and below which no reduction is needed (~π/4).
pub(crate) const PIO4_HIGH: u32 = 0x3FE9_21FB;
/// ... below which sin x = x and cos x = 1 in double precision (|x| < 2^-27).
pub(crate) const TINY_HIGH: u32 = 0x3E40_0000;
/// ... at and above which the three-piece reduction is not exact enough (~2^20·π/2).
pub(crate) const MEDIUM_HIGH: u32 = 0x4139_21FB;

/// `(c0 + z c1) + w (c2 + z c3) + w² (c4 + z c5)` with w = z², Estrin's scheme for a degree-5
/// polynomial in z, written with the given `add`, `mul` and constant `k` so that the scalar,
/// paired and 8-wide evaluations perform the same operations in the same order.
macro_rules! estrin {
    ($add:expr, $mul:expr, $k:expr, $z:expr, $w:expr, $c:expr) => {{
        let (add, mul, k, z, w, c) = ($add, $mul, $k, $z, $w, $c);
        add(
            add(
                add(k(c[0]), mul(z, k(c[1]))),
                mul(w, add(k(c[2]), mul(z, k(c[3])))),
            ),
            mul(mul(w, w), add(k(c[4]), mul(z, k(c[5])))),
        )
    }};
}
pub(crate) use estrin;

/// `(sin x, cos x)` for 2^-27 ≤ |x| ≲ π/4, where no reduction is needed, written with the given
/// `add`, `sub`, `mul` and constant `k`, so that the scalar, paired and 8-wide evaluations
/// perform the same operations in the same order. fdlibm's polynomials in Estrin's scheme:
/// sin x = x + x³·P(z) (6 dependent operations after z² instead of fdlibm's Horner-like 9; the
/// terms after x are below x/6, so their rounding stays far below x's last bit), and fdlibm's
/// cos x = w' + (((1 − w') − z/2) + z²·Q(z)), w' = 1 − z/2 (4 dependent operations fewer); z = x².
/// Checked against the C library in the tests.
macro_rules! unreduced {
    ($add:expr, $sub:expr, $mul:expr, $k:expr, $x:expr) => {{
        let (add, sub, mul, k, x) = ($add, $sub, $mul, $k, $x);
        let z = mul(x, x);
        let w = mul(z, z);
        // sin: x + v P, v = z x.
        let s = add(
            x,
            mul(
                mul(z, x),
                $crate::trig::estrin!(add, mul, k, z, w, SIN_POLY),
            ),
        );
        // cos: w' + (((1 − w') − hz) + w Q), w' = 1 − hz, hz = z/2.
        let q = $crate::trig::estrin!(add, mul, k, z, w, COS_POLY);
        let hz = mul(k(0.5), z);
        let wq = mul(w, q);
        let w = sub(k(1.0), hz);
        (s, add(w, add(sub(sub(k(1.0), w), hz), wq)))
    }};
}
// Used by the lanes kernels of the CPUs with vector builds (x86-64, aarch64).
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
pub(crate) use unreduced;

/// `(sin(x + y), cos(x + y))` for |x| ≲ π/4 and a tail |y| ≤ ulp(x)/2, after a reduction,
/// written with the given `add`, `sub`, `mul` and constant `k` so that the scalar and 8-wide
/// evaluations perform the same operations in the same order: fdlibm's sine kernel in the form
/// that carries the tail, and [`unreduced!`]'s cosine with the tail's term,
/// w' + (((1 − w') − z/2) + (z²·Q(z) − x y)).
macro_rules! tailed {
    ($add:expr, $sub:expr, $mul:expr, $k:expr, $x:expr, $y:expr) => {{
        let (add, sub, mul, k, x, y) = ($add, $sub, $mul, $k, $x, $y);
        let z = mul(x, x);
        let w = mul(z, z);
        let v = mul(z, x);
        let r = add(
            add(k(S2), mul(z, add(k(S3), mul(z, k(S4))))),
            mul(mul(z, w), add(k(S5), mul(z, k(S6)))),
        );
        let s = sub(
            x,
            sub(
                sub(mul(z, sub(mul(k(0.5), y), mul(v, r))), y),
                mul(v, k(S1)),
            ),
        );
        let q = $crate::trig::estrin!(add, mul, k, z, w, COS_POLY);
        let hz = mul(k(0.5), z);
        let wq = mul(w, q);
        let w = sub(k(1.0), hz);
        (s, add(w, add(sub(sub(k(1.0), w), hz), sub(wq, mul(x, y)))))
    }};
}
// Used by the lanes kernels of the CPUs with vector builds (x86-64, aarch64).
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
pub(crate) use tailed;

/// The rounds of [`reduce`] for several lanes at once, written with the given `sub`, `mul`,
/// constant `k` and masks, so that the 8-wide evaluations perform the scalar's operations in
/// its order: every lane takes all three rounds and keeps the one its scalar call stops at.
/// `beyond(y, bits)` is the mask of the lanes where x's exponent exceeds y's by more than
/// `bits`, `and` joins two masks, `select(m, a, b)` is `m ? b : a` per lane. Returns (y0, y1).
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
macro_rules! all_rounds {
    ($sub:expr, $mul:expr, $k:expr, $x:expr, $fnum:expr, $beyond:expr, $and:expr, $select:expr) => {{
        let (sub, mul, k, x, fnum) = ($sub, $mul, $k, $x, $fnum);
        let (beyond, and, select) = ($beyond, $and, $select);
        let r1 = sub(x, mul(fnum, k(PIO2_1)));
        let w1 = mul(fnum, k(PIO2_1T));
        let y01 = sub(r1, w1);
        let second = beyond(y01, 16);
        let w2 = mul(fnum, k(PIO2_2));
        let r2 = sub(r1, w2);
        let w2 = sub(mul(fnum, k(PIO2_2T)), sub(sub(r1, r2), w2));
        let y02 = sub(r2, w2);
        let third = and(second, beyond(y02, 49));
        let w3 = mul(fnum, k(PIO2_3));
        let r3 = sub(r2, w3);
        let w3 = sub(mul(fnum, k(PIO2_3T)), sub(sub(r2, r3), w3));
        let y03 = sub(r3, w3);
        let pick = |a, b, c| select(third, select(second, a, b), c);
        let (r, w, y0) = (pick(r1, r2, r3), pick(w1, w2, w3), pick(y01, y02, y03));
        (y0, sub(sub(r, y0), w))
    }};
}
// Used by the lanes kernels of the CPUs with vector builds (x86-64, aarch64).
#[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
pub(crate) use all_rounds;

/// The coefficients of the no-tail sine's polynomial: sin x = x + x³·P(x²).
pub(crate) const SIN_POLY: [f64; 6] = [S1, S2, S3, S4, S5, S6];
/// ... and the cosine's: cos x = 1 − x²/2 + x⁴·Q(x²).
pub(crate) const COS_POLY: [f64; 6] = [C1, C2, C3, C4, C5, C6];

unsafe extern "C" {
    #[link_name = "sin"]
    fn c_sin(x: f64) -> f64;
    #[link_name = "cos"]
    fn c_cos(x: f64) -> f64;
}

/// (sin x, cos x). Call it once per angle: sin and cos share the reduction.
#[inline(always)]
pub fn sin_cos(x: f64) -> (f64, f64) {
    let high = high_word(x);
    if high <= PIO4_HIGH {
        if high < TINY_HIGH {
            // Also keeps the sign of -0.0.
            return (x, 1.0);
        }
        return unreduced!(|a, b| a + b, |a, b| a - b, |a, b| a * b, |c| c, x);
    }
    if high >= MEDIUM_HIGH {
        // Huge or non-finite (NaN, ±inf give NaN): the C library's full reduction.
        // SAFETY: pure C library functions of one double, defined for every input.
        return unsafe { (c_sin(x), c_cos(x)) };
    }
    let (n, y0, y1) = reduce(x, high);
    let (s, c) = kernel_sin_cos(y0, y1);
    match n & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// ((sin a, cos a), (sin b, cos b)) with the bits of [`sin_cos`] for each: the kernels with
/// the most angles have two (vehicle8's pitch and yaw). Where both are in the range that needs
/// no reduction (2^-27 ≤ |x| ≲ π/4, where the vehicle's angles mostly are) the two angles'
/// polynomials run side by side in the two lanes of SSE2 (x86-64) or NEON (aarch64) registers —
/// each the baseline of its target, so in every build — with the scalar operations in their
/// order; otherwise one after the other.
#[inline(always)]
pub fn sin_cos_pair(a: f64, b: f64) -> ((f64, f64), (f64, f64)) {
    #[cfg(any(target_arch = "x86_64", target_arch = "aarch64"))]
    {
        let in_range = |x: f64| (TINY_HIGH..=PIO4_HIGH).contains(&high_word(x));
        if in_range(a) && in_range(b) {
            return pair::unreduced(a, b);
        }
    }
    (sin_cos(a), sin_cos(b))
}

/// The high 32 bits of |x|'s representation.
#[inline(always)]
fn high_word(x: f64) -> u32 {
    (x.to_bits() >> 32) as u32 & 0x7FFF_FFFF
}

/// [`unreduced!`] for two arguments at once.
#[cfg(target_arch = "x86_64")]
mod pair {
    use super::*;
    use core::arch::x86_64::*;

    /// The operations of [`unreduced!`] on (a, b) in the two lanes.
    #[inline(always)]
    pub(super) fn unreduced(a: f64, b: f64) -> ((f64, f64), (f64, f64)) {
        // SAFETY: SSE2 is part of the x86-64 baseline, present on every CPU this runs on.
        unsafe {
            let k = _mm_set1_pd;
            let (add, sub, mul) = (_mm_add_pd, _mm_sub_pd, _mm_mul_pd);
            let (s, c) = unreduced!(add, sub, mul, k, _mm_set_pd(b, a));
            let lane = |v: __m128d, high: bool| {
                if high {
                    _mm_cvtsd_f64(_mm_unpackhi_pd(v, v))
                } else {
                    _mm_cvtsd_f64(v)
                }
            };
            (
                (lane(s, false), lane(c, false)),
                (lane(s, true), lane(c, true)),
            )
        }
    }
}

/// [`unreduced!`] for two arguments at once.
#[cfg(target_arch = "aarch64")]
mod pair {
    use super::*;
    use core::arch::aarch64::*;

    /// The operations of [`unreduced!`] on (a, b) in the two lanes.
    #[inline(always)]
    pub(super) fn unreduced(a: f64, b: f64) -> ((f64, f64), (f64, f64)) {
        // SAFETY: NEON is part of every aarch64 CPU; the load reads the two doubles of a local
        // array.
        unsafe {
            let k = vdupq_n_f64;
            let (add, sub, mul) = (vaddq_f64, vsubq_f64, vmulq_f64);
            let (s, c) = unreduced!(add, sub, mul, k, vld1q_f64([a, b].as_ptr()));
            (
                (vgetq_lane_f64::<0>(s), vgetq_lane_f64::<0>(c)),
                (vgetq_lane_f64::<1>(s), vgetq_lane_f64::<1>(c)),
            )
        }
    }
}

/// x = n·π/2 + (y0 + y1) with |y0 + y1| ≲ π/4, for |x| < 2^20·π/2: the nearest multiple is
/// removed in one, two or three rounds, as many as the cancellation needs (fdlibm's medium case).
#[inline(always)]
fn reduce(x: f64, high: u32) -> (i64, f64, f64) {
    let fnum = (x * INV_PIO2 + TO_INT) - TO_INT;
    let exponent = |v: f64| ((v.to_bits() >> 52) & 0x7FF) as i32;
    let ex = (high >> 20) as i32;
    let mut r = x - fnum * PIO2_1;
    let mut w = fnum * PIO2_1T;
    let mut y0 = r - w;
    if ex - exponent(y0) > 16 {
        let t = r;
        w = fnum * PIO2_2;
        r = t - w;
        w = fnum * PIO2_2T - ((t - r) - w);
        y0 = r - w;
        if ex - exponent(y0) > 49 {
            let t = r;
            w = fnum * PIO2_3;
            r = t - w;
            w = fnum * PIO2_3T - ((t - r) - w);
            y0 = r - w;
        }
    }
    let y1 = (r - y0) - w;
    (fnum as i64, y0, y1)
}

/// `(sin(x + y), cos(x + y))` from [`tailed!`], one argument.
#[inline(always)]
fn kernel_sin_cos(x: f64, y: f64) -> (f64, f64) {
    tailed!(|a, b| a + b, |a, b| a - b, |a, b| a * b, |c| c, x, y)
}
