use super::{Lanes, LANES};
use core::arch::aarch64::*;

/// Registers per lane array (two doubles each).
const REGS: usize = LANES / 2;

/// The four registers of a lane array.
#[target_feature(enable = "neon")]
#[inline]
fn load(a: &Lanes) -> [float64x2_t; REGS] {
    // SAFETY: loads of 2 doubles at offsets 0, 2, 4 and 6 of an array of 8.
    core::array::from_fn(|r| unsafe { vld1q_f64(a.as_ptr().add(2 * r)) })
}

/// The lane array of four registers.
#[target_feature(enable = "neon")]
#[inline]
fn store(v: [float64x2_t; REGS]) -> Lanes {
    let mut out = [0.0; LANES];
    for (r, v) in v.into_iter().enumerate() {
        // SAFETY: a store of 2 doubles at offset 2r < 8 of an array of 8.
        unsafe { vst1q_f64(out.as_mut_ptr().add(2 * r), v) };
    }
    out
}

macro_rules! op {
    ($name:ident, $intr:ident) => {
        /// The operation on every lane.
        ///
        /// # Safety
        /// The CPU must have NEON, as every aarch64 CPU has.
        #[target_feature(enable = "neon")]
        #[inline]
        pub fn $name(a: Lanes, b: Lanes) -> Lanes {
            let (a, b) = (load(&a), load(&b));
            store(core::array::from_fn(|r| $intr(a[r], b[r])))
        }
    };
}
op!(add, vaddq_f64);
op!(sub, vsubq_f64);
op!(mul, vmulq_f64);
op!(div, vdivq_f64);

/// [`super::gather`]: on aarch64 the compiler's own code for the definition (no store-to-load
/// forwarding stall to avoid as on x86, see [`super::wide_avx2::gather`]; not measured on a
/// real aarch64 CPU).
///
/// # Safety
/// The CPU must have NEON, as every aarch64 CPU has.
#[target_feature(enable = "neon")]
#[inline]
pub fn gather<const N: usize>(rows: &[[f64; N]; LANES]) -> [Lanes; N] {
    super::gather(rows)
}

/// `m ? b : a` per lane, `m` all-ones or zero per lane.
#[target_feature(enable = "neon")]
#[inline]
fn select(m: uint64x2_t, a: float64x2_t, b: float64x2_t) -> float64x2_t {
    vbslq_f64(m, b, a)
}

/// The high 32 bits of |x| per lane (as 64-bit integers).
#[target_feature(enable = "neon")]
#[inline]
fn high_word(x: float64x2_t) -> uint64x2_t {
    vandq_u64(
        vshrq_n_u64::<32>(vreinterpretq_u64_f64(x)),
        vdupq_n_u64(0x7FFF_FFFF),
    )
}

/// Whether any lane of a mask is set.
#[target_feature(enable = "neon")]
#[inline]
fn any(m: uint64x2_t) -> bool {
    vmaxvq_u32(vreinterpretq_u32_u64(m)) != 0
}

/// (sin, cos) of every lane with the bits of [`crate::trig::sin_cos`]: [`super::wide::sin_cos`]
/// line for line on each pair of lanes. If any lane needs the C library all go through
/// [`super::sin_cos_each`].
///
/// # Safety
/// The CPU must have NEON, as every aarch64 CPU has.
#[target_feature(enable = "neon")]
#[inline]
pub fn sin_cos(x: Lanes) -> (Lanes, Lanes) {
    let pairs = load(&x);
    let limit = vdupq_n_u64(crate::trig::MEDIUM_HIGH.into());
    if pairs.iter().any(|&v| any(vcgeq_u64(high_word(v), limit))) {
        return super::sin_cos_each(x);
    }
    let (mut s, mut c) = ([vdupq_n_f64(0.0); REGS], [vdupq_n_f64(0.0); REGS]);
    for r in 0..REGS {
        (s[r], c[r]) = sin_cos_pair(pairs[r]);
    }
    (store(s), store(c))
}

/// [`sin_cos`] of two lanes, neither of which needs the C library.
#[target_feature(enable = "neon")]
#[inline]
fn sin_cos_pair(xv: float64x2_t) -> (float64x2_t, float64x2_t) {
    use crate::trig::*;
    let f = vdupq_n_f64;
    let u = vdupq_n_u64;
    let (add, sub, mul) = (vaddq_f64, vsubq_f64, vmulq_f64);
    let high = high_word(xv);
    let small = vcleq_u64(high, u(PIO4_HIGH.into()));
    let tiny = vcltq_u64(high, u(TINY_HIGH.into()));
    if vminvq_u32(vreinterpretq_u32_u64(small)) == u32::MAX {
        // `super::wide::sin_cos`'s path for lanes all within π/4, line for line.
        let (s, c) = unreduced!(add, sub, mul, f, xv);
        return (select(tiny, s, xv), select(tiny, c, f(1.0)));
    }

    // `reduce`: x = n·π/2 + (y0 + y1); n mod 4 is in the low bits of x·2/π + 1.5·2⁵².
    let shifted = add(mul(xv, f(INV_PIO2)), f(TO_INT));
    let fnum = sub(shifted, f(TO_INT));
    let quadrant = vandq_u64(vreinterpretq_u64_f64(shifted), u(3));
    let exponent = |v: float64x2_t| {
        vreinterpretq_s64_u64(vandq_u64(
            vshrq_n_u64::<52>(vreinterpretq_u64_f64(v)),
            u(0x7FF),
        ))
    };
    let ex = vreinterpretq_s64_u64(vshrq_n_u64::<20>(high));
    let beyond =
        |v: float64x2_t, bits: i64| vcgtq_s64(vsubq_s64(ex, exponent(v)), vdupq_n_s64(bits));
    let (y0, y1) = all_rounds!(sub, mul, f, xv, fnum, beyond, vandq_u64, select);
    // |x| ≤ π/4: no reduction, y = (x, 0), quadrant 0.
    let y0 = select(small, y0, xv);
    let y1 = select(small, y1, f(0.0));
    let quadrant = vbicq_u64(quadrant, small);

    // `tailed!` (reduced lanes) and `unreduced!`'s sine (|x| ≤ π/4). For |x| ≤ π/4 the tail
    // is 0, so the cosines agree: x·0 = ±0 and z²Q > 0.
    let (with_tail, c) = tailed!(add, sub, mul, f, y0, y1);
    let without_tail = unreduced!(add, sub, mul, f, y0).0;
    let s = select(small, with_tail, without_tail);

    // Quadrant: 0 (s, c), 1 (c, −s), 2 (−s, −c), 3 (−c, s); tiny |x|: (x, 1).
    let odd = vtstq_u64(quadrant, u(1));
    let neg_sin = vtstq_u64(quadrant, u(2));
    let neg_cos = veorq_u64(odd, neg_sin);
    let negate = |m: uint64x2_t, v: float64x2_t| {
        let flipped = vreinterpretq_f64_u64(veorq_u64(vreinterpretq_u64_f64(v), u(1 << 63)));
        select(m, v, flipped)
    };
    let sin = negate(neg_sin, select(odd, s, c));
    let cos = negate(neg_cos, select(odd, c, s));
    (select(tiny, sin, xv), select(tiny, cos, f(1.0)))
}
