use super::{Lanes, LANES};
use core::arch::x86_64::*;

macro_rules! op {
    ($name:ident, $intr:ident) => {
        /// The operation on every lane.
        ///
        /// # Safety
        /// The CPU must have AVX-512F and AVX-512VL.
        #[target_feature(enable = "avx512f,avx512vl")]
        #[inline]
        pub fn $name(a: Lanes, b: Lanes) -> Lanes {
            let mut out = [0.0; LANES];
            // SAFETY: unaligned loads and a store of 8 doubles from and to arrays of 8.
            unsafe {
                let r = $intr(_mm512_loadu_pd(a.as_ptr()), _mm512_loadu_pd(b.as_ptr()));
                _mm512_storeu_pd(out.as_mut_ptr(), r);
            }
            out
        }
    };
}
op!(add, _mm512_add_pd);
op!(sub, _mm512_sub_pd);
op!(mul, _mm512_mul_pd);
op!(div, _mm512_div_pd);

/// The 8×8 transpose of eight registers, `out[i][l] = rows[l][i]`, in 24 shuffles (pairs,
/// then 128-bit pieces, then halves).
#[target_feature(enable = "avx512f,avx512vl")]
#[inline]
fn transpose(r: [__m512d; LANES]) -> [__m512d; LANES] {
    // t[2p] = r[2p][0] r[2p+1][0] r[2p][2] r[2p+1][2] …, t[2p+1] the odd entries.
    let t = [
        _mm512_unpacklo_pd(r[0], r[1]),
        _mm512_unpackhi_pd(r[0], r[1]),
        _mm512_unpacklo_pd(r[2], r[3]),
        _mm512_unpackhi_pd(r[2], r[3]),
        _mm512_unpacklo_pd(r[4], r[5]),
        _mm512_unpackhi_pd(r[4], r[5]),
        _mm512_unpacklo_pd(r[6], r[7]),
        _mm512_unpackhi_pd(r[6], r[7]),
    ];
    // Entries 0, 1 (and 4, 5) of a and of b, or 2, 3 (and 6, 7).
    let low = _mm512_set_epi64(13, 12, 5, 4, 9, 8, 1, 0);
    let high = _mm512_set_epi64(15, 14, 7, 6, 11, 10, 3, 2);
    // u[..4]: rows 0–3 of entries (0 | 4), (2 | 6), (1 | 5), (3 | 7); u[4..]: rows 4–7.
    let u = [
        _mm512_permutex2var_pd(t[0], low, t[2]),
        _mm512_permutex2var_pd(t[0], high, t[2]),
        _mm512_permutex2var_pd(t[1], low, t[3]),
        _mm512_permutex2var_pd(t[1], high, t[3]),
        _mm512_permutex2var_pd(t[4], low, t[6]),
        _mm512_permutex2var_pd(t[4], high, t[6]),
        _mm512_permutex2var_pd(t[5], low, t[7]),
        _mm512_permutex2var_pd(t[5], high, t[7]),
    ];
    // The low (0x44) or high (0xEE) halves of rows 0–3 and of rows 4–7.
    [
        _mm512_shuffle_f64x2::<0x44>(u[0], u[4]),
        _mm512_shuffle_f64x2::<0x44>(u[2], u[6]),
        _mm512_shuffle_f64x2::<0x44>(u[1], u[5]),
        _mm512_shuffle_f64x2::<0x44>(u[3], u[7]),
        _mm512_shuffle_f64x2::<0xEE>(u[0], u[4]),
        _mm512_shuffle_f64x2::<0xEE>(u[2], u[6]),
        _mm512_shuffle_f64x2::<0xEE>(u[1], u[5]),
        _mm512_shuffle_f64x2::<0xEE>(u[3], u[7]),
    ]
}

/// Entries `0..n` of a register (n ≤ 8).
#[inline(always)]
fn first(n: usize) -> __mmask8 {
    (((1u16 << n) - 1) & 0xFF) as __mmask8
}

/// [`super::gather`] by 8×8 transposes of registers (the rows read 8 entries at a time, the
/// last piece masked), each lane array written with one 8-wide store (see
/// [`super::wide_avx2::gather`] for why that matters).
///
/// # Safety
/// The CPU must have AVX-512F and AVX-512VL.
#[target_feature(enable = "avx512f,avx512vl")]
#[inline]
pub fn gather<const N: usize>(rows: &[[f64; N]; LANES]) -> [Lanes; N] {
    let mut out = [[0.0; LANES]; N];
    for start in (0..N).step_by(LANES) {
        let mask = first((N - start).min(LANES));
        let mut r = [_mm512_setzero_pd(); LANES];
        for (r, row) in r.iter_mut().zip(rows) {
            // SAFETY: a masked load of entries start.. < N of an array of N.
            *r = unsafe { _mm512_maskz_loadu_pd(mask, row.as_ptr().add(start)) };
        }
        for (lanes, v) in out[start..].iter_mut().zip(transpose(r)) {
            // SAFETY: an unaligned store of 8 doubles into an array of 8.
            unsafe { _mm512_storeu_pd(lanes.as_mut_ptr(), v) };
        }
    }
    out
}

/// (sin, cos) of every lane with the bits of [`crate::trig::sin_cos`], all lanes in one
/// instruction stream: every lane takes every path (the three rounds of the reduction, both
/// forms of fdlibm's sine kernel) and keeps the one its scalar call would take, by masks.
/// The operations and their order are those of `trig.rs`, line for line. If any lane needs
/// the C library (|x| ≥ 2²⁰·π/2 or not finite) all go through [`super::sin_cos_each`].
///
/// # Safety
/// The CPU must have AVX-512F and AVX-512VL ([`crate::isa::avx512`]); callers compiled
/// for those features (the lanes kernel) call it without `unsafe`.
#[target_feature(enable = "avx512f,avx512vl")]
#[inline]
pub fn sin_cos(x: Lanes) -> (Lanes, Lanes) {
    use crate::trig::*;
    let f = _mm512_set1_pd;
    let i = _mm512_set1_epi64;
    let (add, sub, mul) = (_mm512_add_pd, _mm512_sub_pd, _mm512_mul_pd);
    // SAFETY: an unaligned load of the 8 doubles of `x`.
    let xv = unsafe { _mm512_loadu_pd(x.as_ptr()) };
    let high = _mm512_and_si512(
        _mm512_srli_epi64::<32>(_mm512_castpd_si512(xv)),
        i(0x7FFF_FFFF),
    );
    if _mm512_cmpge_epi64_mask(high, i(MEDIUM_HIGH.into())) != 0 {
        return super::sin_cos_each(x);
    }
    let small = _mm512_cmple_epi64_mask(high, i(PIO4_HIGH.into()));
    let tiny = _mm512_cmplt_epi64_mask(high, i(TINY_HIGH.into()));
    if small == 0xFF {
        // Every lane within π/4 (a balancing vehicle's angles): `trig::unreduced!`, no
        // reduction, tiny lanes (x, 1).
        let (s, c) = unreduced!(add, sub, mul, f, xv);
        let (mut so, mut co) = ([0.0; LANES], [0.0; LANES]);
        // SAFETY: unaligned stores of 8 doubles into local arrays.
        unsafe {
            _mm512_storeu_pd(so.as_mut_ptr(), _mm512_mask_blend_pd(tiny, s, xv));
            _mm512_storeu_pd(co.as_mut_ptr(), _mm512_mask_blend_pd(tiny, c, f(1.0)));
        }
        return (so, co);
    }

    // `reduce`: x = n·π/2 + (y0 + y1); n mod 4 is in the low bits of x·2/π + 1.5·2⁵².
    let shifted = add(mul(xv, f(INV_PIO2)), f(TO_INT));
    let fnum = sub(shifted, f(TO_INT));
    let quadrant = _mm512_and_si512(_mm512_castpd_si512(shifted), i(3));
    let exponent =
        |v: __m512d| _mm512_and_si512(_mm512_srli_epi64::<52>(_mm512_castpd_si512(v)), i(0x7FF));
    let ex = _mm512_srli_epi64::<20>(high);
    let beyond = |v, bits| _mm512_cmpgt_epi64_mask(_mm512_sub_epi64(ex, exponent(v)), i(bits));
    let and = |a: __mmask8, b: __mmask8| a & b;
    let (y0, y1) = all_rounds!(sub, mul, f, xv, fnum, beyond, and, _mm512_mask_blend_pd);
    // |x| ≤ π/4: no reduction, y = (x, 0), quadrant 0.
    let y0 = _mm512_mask_blend_pd(small, y0, xv);
    let y1 = _mm512_mask_blend_pd(small, y1, f(0.0));
    let quadrant = _mm512_mask_blend_epi64(small, quadrant, i(0));

    // `tailed!` (reduced lanes) and `unreduced!`'s sine (|x| ≤ π/4). For |x| ≤ π/4 the tail
    // is 0, so the cosines agree: x·0 = ±0 and z²Q > 0.
    let (with_tail, c) = tailed!(add, sub, mul, f, y0, y1);
    let without_tail = unreduced!(add, sub, mul, f, y0).0;
    let s = _mm512_mask_blend_pd(small, with_tail, without_tail);

    // Quadrant: 0 (s, c), 1 (c, −s), 2 (−s, −c), 3 (−c, s); tiny |x|: (x, 1).
    let odd = _mm512_test_epi64_mask(quadrant, i(1));
    let neg_sin = _mm512_test_epi64_mask(quadrant, i(2));
    let neg_cos = odd ^ neg_sin;
    let negate = |m: __mmask8, v: __m512d| {
        let flipped = _mm512_castsi512_pd(_mm512_xor_si512(_mm512_castpd_si512(v), i(i64::MIN)));
        _mm512_mask_blend_pd(m, v, flipped)
    };
    let sin = negate(neg_sin, _mm512_mask_blend_pd(odd, s, c));
    let cos = negate(neg_cos, _mm512_mask_blend_pd(odd, c, s));
    let sin = _mm512_mask_blend_pd(tiny, sin, xv);
    let cos = _mm512_mask_blend_pd(tiny, cos, f(1.0));
    let (mut so, mut co) = ([0.0; LANES], [0.0; LANES]);
    // SAFETY: unaligned stores of 8 doubles into local arrays.
    unsafe {
        _mm512_storeu_pd(so.as_mut_ptr(), sin);
        _mm512_storeu_pd(co.as_mut_ptr(), cos);
    }
    (so, co)
}
