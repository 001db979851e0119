use super::{Lanes, LANES};
use core::arch::x86_64::*;

/// Half a lane array.
const HALF: usize = LANES / 2;

macro_rules! op {
    ($name:ident, $intr:ident) => {
        /// The operation on every lane.
        ///
        /// # Safety
        /// The CPU must have AVX2.
        #[target_feature(enable = "avx2")]
        #[inline]
        pub fn $name(a: Lanes, b: Lanes) -> Lanes {
            let mut out = [0.0; LANES];
            // SAFETY: unaligned loads and stores of 4 doubles at offsets 0 and 4 of arrays
            // of 8.
            unsafe {
                for h in [0, HALF] {
                    let r = $intr(
                        _mm256_loadu_pd(a.as_ptr().add(h)),
                        _mm256_loadu_pd(b.as_ptr().add(h)),
                    );
                    _mm256_storeu_pd(out.as_mut_ptr().add(h), r);
                }
            }
            out
        }
    };
}
op!(add, _mm256_add_pd);
op!(sub, _mm256_sub_pd);
op!(mul, _mm256_mul_pd);
op!(div, _mm256_div_pd);

/// The 4×4 transpose of four registers, `out[i][l] = rows[l][i]`.
#[target_feature(enable = "avx2")]
#[inline]
fn transpose(r: [__m256d; HALF]) -> [__m256d; HALF] {
    let t = [
        _mm256_unpacklo_pd(r[0], r[1]),
        _mm256_unpackhi_pd(r[0], r[1]),
        _mm256_unpacklo_pd(r[2], r[3]),
        _mm256_unpackhi_pd(r[2], r[3]),
    ];
    [
        _mm256_permute2f128_pd::<0x20>(t[0], t[2]),
        _mm256_permute2f128_pd::<0x20>(t[1], t[3]),
        _mm256_permute2f128_pd::<0x31>(t[0], t[2]),
        _mm256_permute2f128_pd::<0x31>(t[1], t[3]),
    ]
}

/// Lanes `0..n` of a 4-lane mask (sign bits set), n ≤ 4.
#[target_feature(enable = "avx2")]
#[inline]
fn first(n: usize) -> __m256i {
    let on = |l: usize| if l < n { -1i64 } else { 0 };
    _mm256_set_epi64x(on(3), on(2), on(1), on(0))
}

/// Four entries of an array from `at` (`n` < 4 of them masked).
///
/// # Safety
/// `at..at + n` must be in the array.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn load(at: *const f64, n: usize) -> __m256d {
    // SAFETY: the caller's.
    unsafe {
        if n == HALF {
            _mm256_loadu_pd(at)
        } else {
            _mm256_maskload_pd(at, first(n))
        }
    }
}

/// Writes four entries of an array from `at` (`n` < 4 of them masked).
///
/// # Safety
/// `at..at + n` must be in the array.
#[target_feature(enable = "avx2")]
#[inline]
unsafe fn store(at: *mut f64, n: usize, v: __m256d) {
    // SAFETY: the caller's.
    unsafe {
        if n == HALF {
            _mm256_storeu_pd(at, v)
        } else {
            _mm256_maskstore_pd(at, first(n), v)
        }
    }
}

/// [`super::gather`] by 4×4 transposes of registers, each half of a lane array written with
/// one 4-wide store: the operations read lane arrays with 4-wide loads, and a wide load of
/// data just written one double at a time cannot be forwarded from the store buffer — it
/// waits for the stores to reach the cache (in the AVX2 map a third of the 8-wide sincos's
/// time sat on its input's load).
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
#[inline]
pub fn gather<const N: usize>(rows: &[[f64; N]; LANES]) -> [Lanes; N] {
    let mut out = [[0.0; LANES]; N];
    for h in [0, HALF] {
        for start in (0..N).step_by(HALF) {
            gather_block(rows, h, start, &mut out);
        }
    }
    out
}

/// Entries `start..start + 4` (fewer at the end) of rows `h..h + 4` into lanes `h..h + 4`.
#[target_feature(enable = "avx2")]
#[inline]
fn gather_block<const N: usize>(
    rows: &[[f64; N]; LANES],
    h: usize,
    start: usize,
    out: &mut [Lanes; N],
) {
    let n = (N - start).min(HALF);
    let mut r = [_mm256_setzero_pd(); HALF];
    for (r, row) in r.iter_mut().zip(&rows[h..]) {
        // SAFETY: entries start..start + n ≤ N of an array of N.
        *r = unsafe { load(row.as_ptr().add(start), n) };
    }
    for (lanes, v) in out[start..].iter_mut().zip(transpose(r)) {
        // SAFETY: entries h..h + 4 ≤ 8 of an array of 8.
        unsafe { store(lanes.as_mut_ptr().add(h), HALF, v) };
    }
}

/// [`super::scatter`] by 4×4 transposes of registers, each row written 4 entries at a time
/// (the last piece masked).
///
/// # Safety
/// The CPU must have AVX2.
#[target_feature(enable = "avx2")]
#[inline]
pub fn scatter<const N: usize>(lanes: &[Lanes; N], rows: &mut [[f64; N]; LANES]) {
    for h in [0, HALF] {
        for start in (0..N).step_by(HALF) {
            let n = (N - start).min(HALF);
            let mut c = [_mm256_setzero_pd(); HALF];
            for (c, lanes) in c.iter_mut().zip(&lanes[start..]) {
                // SAFETY: entries h..h + 4 ≤ 8 of an array of 8.
                *c = unsafe { load(lanes.as_ptr().add(h), HALF) };
            }
            for (row, v) in rows[h..].iter_mut().zip(transpose(c)) {
                // SAFETY: entries start..start + n ≤ N of an array of N.
                unsafe { store(row.as_mut_ptr().add(start), n, v) };
            }
        }
    }
}

/// `m ? b : a` per lane, `m` all-ones or zero per lane.
#[target_feature(enable = "avx2")]
#[inline]
fn select(m: __m256i, a: __m256d, b: __m256d) -> __m256d {
    _mm256_blendv_pd(a, b, _mm256_castsi256_pd(m))
}

/// The high 32 bits of |x| per lane (as 64-bit integers).
#[target_feature(enable = "avx2")]
#[inline]
fn high_word(x: __m256d) -> __m256i {
    _mm256_and_si256(
        _mm256_srli_epi64::<32>(_mm256_castpd_si256(x)),
        _mm256_set1_epi64x(0x7FFF_FFFF),
    )
}

/// (sin, cos) of every lane with the bits of [`crate::trig::sin_cos`]: [`super::wide::sin_cos`]
/// line for line on each half. If any lane needs the C library all go through
/// [`super::sin_cos_each`].
///
/// # Safety
/// The CPU must have AVX2 ([`crate::isa::avx2`]).
#[target_feature(enable = "avx2")]
#[inline]
pub fn sin_cos(x: Lanes) -> (Lanes, Lanes) {
    // Read one double at a time: callers often have just written `x` one double at a time
    // (the loops' Φ), and a wide load of narrower fresh stores cannot be forwarded from the
    // store buffer (a quarter of this function's time). Volatile, or LLVM merges the reads
    // back into one wide load.
    let at = |l: usize| {
        // SAFETY: `l` < LANES, a read of an element of `x`.
        unsafe { core::ptr::read_volatile(x.as_ptr().add(l)) }
    };
    let halves = [
        _mm256_set_pd(at(3), at(2), at(1), at(0)),
        _mm256_set_pd(at(7), at(6), at(5), at(4)),
    ];
    let limit = _mm256_set1_epi64x(i64::from(crate::trig::MEDIUM_HIGH) - 1);
    let far = _mm256_or_si256(
        _mm256_cmpgt_epi64(high_word(halves[0]), limit),
        _mm256_cmpgt_epi64(high_word(halves[1]), limit),
    );
    if _mm256_movemask_pd(_mm256_castsi256_pd(far)) != 0 {
        return super::sin_cos_each(x);
    }
    let (mut so, mut co) = ([0.0; LANES], [0.0; LANES]);
    for (h, xv) in halves.into_iter().enumerate() {
        let (s, c) = sin_cos_half(xv);
        // SAFETY: unaligned stores of 4 doubles at offsets 0 and 4 of arrays of 8.
        unsafe {
            _mm256_storeu_pd(so.as_mut_ptr().add(h * HALF), s);
            _mm256_storeu_pd(co.as_mut_ptr().add(h * HALF), c);
        }
    }
    (so, co)
}

/// [`sin_cos`] of four lanes, none of which needs the C library.
#[target_feature(enable = "avx2")]
#[inline]
fn sin_cos_half(xv: __m256d) -> (__m256d, __m256d) {
    use crate::trig::*;
    let f = _mm256_set1_pd;
    let i = _mm256_set1_epi64x;
    let (add, sub, mul) = (_mm256_add_pd, _mm256_sub_pd, _mm256_mul_pd);
    let high = high_word(xv);
    // high ≤ PIO4_HIGH and high < TINY_HIGH, as signed 64-bit compares of small values.
    let small = _mm256_cmpgt_epi64(i(i64::from(PIO4_HIGH) + 1), high);
    let tiny = _mm256_cmpgt_epi64(i(TINY_HIGH.into()), high);
    if _mm256_movemask_pd(_mm256_castsi256_pd(small)) == 0xF {
        // `super::wide::sin_cos`'s path for lanes all within π/4, line for line.
        let (s, c) = unreduced!(add, sub, mul, f, xv);
        return (select(tiny, s, xv), select(tiny, c, f(1.0)));
    }

    // `reduce`: x = n·π/2 + (y0 + y1); n mod 4 is in the low bits of x·2/π + 1.5·2⁵².
    let shifted = add(mul(xv, f(INV_PIO2)), f(TO_INT));
    let fnum = sub(shifted, f(TO_INT));
    let quadrant = _mm256_and_si256(_mm256_castpd_si256(shifted), i(3));
    let exponent =
        |v: __m256d| _mm256_and_si256(_mm256_srli_epi64::<52>(_mm256_castpd_si256(v)), i(0x7FF));
    let ex = _mm256_srli_epi64::<20>(high);
    let beyond = |v, bits| _mm256_cmpgt_epi64(_mm256_sub_epi64(ex, exponent(v)), i(bits));
    let (y0, y1) = all_rounds!(sub, mul, f, xv, fnum, beyond, _mm256_and_si256, select);
    // |x| ≤ π/4: no reduction, y = (x, 0), quadrant 0.
    let y0 = select(small, y0, xv);
    let y1 = select(small, y1, f(0.0));
    let quadrant = _mm256_andnot_si256(small, quadrant);

    // `tailed!` (reduced lanes) and `unreduced!`'s sine (|x| ≤ π/4). For |x| ≤ π/4 the tail
    // is 0, so the cosines agree: x·0 = ±0 and z²Q > 0.
    let (with_tail, c) = tailed!(add, sub, mul, f, y0, y1);
    let without_tail = unreduced!(add, sub, mul, f, y0).0;
    let s = select(small, with_tail, without_tail);

    // Quadrant: 0 (s, c), 1 (c, −s), 2 (−s, −c), 3 (−c, s); tiny |x|: (x, 1).
    let odd = _mm256_cmpeq_epi64(_mm256_and_si256(quadrant, i(1)), i(1));
    let neg_sin = _mm256_cmpeq_epi64(_mm256_and_si256(quadrant, i(2)), i(2));
    let neg_cos = _mm256_xor_si256(odd, neg_sin);
    let negate = |m: __m256i, v: __m256d| {
        let flipped = _mm256_castsi256_pd(_mm256_xor_si256(_mm256_castpd_si256(v), i(i64::MIN)));
        select(m, v, flipped)
    };
    let sin = negate(neg_sin, select(odd, s, c));
    let cos = negate(neg_cos, select(odd, c, s));
    (select(tiny, sin, xv), select(tiny, cos, f(1.0)))
}
