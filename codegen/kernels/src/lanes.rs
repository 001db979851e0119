//! Several independent points evaluated in one instruction stream: every IR value becomes a
//! `[f64; LANES]`, one entry per point, and every operation is applied entry by entry. Built for
//! AVX-512 (see [`crate::isa`]) each operation on a lane array is one 8-wide instruction, which
//! is what makes a map of many grid points cheaper per point than one point at a time.
//!
//! Each lane performs exactly the operations of the one-point kernel in the same order (sin and
//! cos by [`wide::sin_cos`], which has the bits of [`crate::trig::sin_cos`]), so lane `l` of a
//! result has the bits of the one-point kernel at point `l`.

/// Points per lane array: one AVX-512 register of doubles.
pub const LANES: usize = twv_model::LANES;

/// A value at every lane.
pub type Lanes = [f64; LANES];

/// `[e; LANES]` with the scalar expression `e` evaluated once per lane, `a` (and `b`) bound to
/// that lane's entry of the lane arrays given after the `;`. A macro rather than a function
/// taking a closure so the expression is written out inline for every lane (closures are
/// compiled on their own and, called 8 times, not always inlined into the AVX-512 build).
#[macro_export]
macro_rules! lanewise {
    (|$a:ident| $e:expr; $x:expr) => {{
        let x: $crate::lanes::Lanes = $x;
        $crate::lanewise!(@each x; |$a| $e; 0 1 2 3 4 5 6 7)
    }};
    (|$a:ident, $b:ident| $e:expr; $x:expr, $y:expr) => {{
        let (x, y): ($crate::lanes::Lanes, $crate::lanes::Lanes) = ($x, $y);
        $crate::lanewise!(@each2 x, y; |$a, $b| $e; 0 1 2 3 4 5 6 7)
    }};
    (@each $x:ident; |$a:ident| $e:expr; $($l:literal)*) => {
        [$({
            let $a: f64 = $x[$l];
            $e
        }),*]
    };
    (@each2 $x:ident, $y:ident; |$a:ident, $b:ident| $e:expr; $($l:literal)*) => {
        [$({
            let ($a, $b): (f64, f64) = ($x[$l], $y[$l]);
            $e
        }),*]
    };
}

/// (sin, cos) of every lane, one lane after the other through [`crate::trig::sin_cos`]: the
/// rare path of [`wide::sin_cos`] (an argument for the C library), kept out of line.
#[inline(never)]
pub fn sin_cos_each(x: Lanes) -> (Lanes, Lanes) {
    let (mut s, mut c) = ([0.0; LANES], [0.0; LANES]);
    for l in 0..LANES {
        (s[l], c[l]) = crate::trig::sin_cos(x[l]);
    }
    (s, c)
}

/// (sin, cos) of every lane with the best build this CPU runs ([`crate::isa::current`]):
/// [`wide::sin_cos`], [`wide_avx2::sin_cos`], or one lane after the other. Every path has the
/// bits of [`crate::trig::sin_cos`]; for callers outside a `target_feature` build (the closed
/// loop's setpoint in the maps).
#[inline]
pub fn sin_cos(x: Lanes) -> (Lanes, Lanes) {
    #[cfg(target_arch = "x86_64")]
    match crate::isa::current() {
        // SAFETY: `current` returns an ISA only when the CPU and the OS support it.
        crate::isa::Isa::Avx512 => return unsafe { wide::sin_cos(x) },
        // SAFETY: as above.
        crate::isa::Isa::Avx2 => return unsafe { wide_avx2::sin_cos(x) },
        crate::isa::Isa::Baseline => {}
    }
    sin_cos_each(x)
}

/// `v` at every lane.
#[inline(always)]
pub const fn splat(v: f64) -> Lanes {
    [v; LANES]
}

/// Lane arrays `out[i][l] = rows[l][i]`: from one array per point to one lane array per entry.
/// The definition the lanes kernel's builds (`wide::gather`, `wide_avx2::gather`) are tested
/// against.
#[inline(always)]
pub fn gather<const N: usize>(rows: &[[f64; N]; LANES]) -> [Lanes; N] {
    let mut out = [[0.0; LANES]; N];
    for (l, row) in rows.iter().enumerate() {
        for (i, v) in row.iter().enumerate() {
            out[i][l] = *v;
        }
    }
    out
}

/// The inverse of [`gather`]: `rows[l][i] = lanes[i][l]`.
#[inline(always)]
pub fn scatter<const N: usize>(lanes: &[Lanes; N], rows: &mut [[f64; N]; LANES]) {
    for (l, row) in rows.iter_mut().enumerate() {
        let row = core::hint::black_box(row);
        for (i, v) in row.iter_mut().enumerate() {
            *v = lanes[i][l];
        }
    }
}

/// [`scatter`] for a matrix: `out[l][r][c] = lanes[r][c][l]`.
#[inline(always)]
pub fn scatter_matrix<const R: usize, const C: usize>(
    lanes: &[[Lanes; C]; R],
    out: &mut [[[f64; C]; R]; LANES],
) {
    for (l, matrix) in out.iter_mut().enumerate() {
        let matrix = core::hint::black_box(matrix);
        for (row, lanes_row) in matrix.iter_mut().zip(lanes) {
            for (v, lane) in row.iter_mut().zip(lanes_row) {
                *v = lane[l];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanewise_applies_the_expression_to_every_lane() {
        let x: Lanes = core::array::from_fn(|l| l as f64 - 3.5);
        let y: Lanes = core::array::from_fn(|l| 0.25 * l as f64);
        let s = crate::lanewise!(|a| a * a - 1.0; x);
        let d = crate::lanewise!(|a, b| a / (b + 1.0); x, y);
        for l in 0..LANES {
            assert_eq!(s[l].to_bits(), (x[l] * x[l] - 1.0).to_bits());
            assert_eq!(d[l].to_bits(), (x[l] / (y[l] + 1.0)).to_bits());
        }
    }

    #[test]
    fn scatters_invert_gather() {
        let rows: [[f64; 3]; LANES] = core::array::from_fn(|l| [l as f64, -(l as f64), 0.5]);
        let lanes = gather(&rows);
        assert_eq!(lanes[1][5], -5.0);
        let mut back = [[0.0; 3]; LANES];
        scatter(&lanes, &mut back);
        assert_eq!(back, rows);
        let matrices: [[[f64; 3]; 2]; LANES] =
            core::array::from_fn(|l| [rows[l], [0.25 * l as f64, 1.0, -2.0]]);
        let lanes = [
            gather(&matrices.map(|m| m[0])),
            gather(&matrices.map(|m| m[1])),
        ];
        let mut back = [[[0.0; 3]; 2]; LANES];
        scatter_matrix(&lanes, &mut back);
        assert_eq!(back, matrices);
    }

    /// The wide gathers and the AVX2 scatter (transposes of registers, masked at the end of a
    /// row) are [`gather`] and [`scatter`], for rows shorter than, equal to and longer than a
    /// register, for each build this CPU can run.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn wide_gathers_and_scatters_are_the_definitions() {
        fn check<const N: usize>() {
            let rows: [[f64; N]; LANES] =
                core::array::from_fn(|l| core::array::from_fn(|i| (10 * l + i) as f64 - 0.5));
            let reference = gather(&rows);
            if crate::isa::best() >= crate::isa::Isa::Avx512 {
                // SAFETY: the CPU has AVX-512F and AVX-512VL.
                assert_eq!(unsafe { wide::gather(&rows) }, reference);
            }
            if crate::isa::best() >= crate::isa::Isa::Avx2 {
                // SAFETY: the CPU has AVX2.
                assert_eq!(unsafe { wide_avx2::gather(&rows) }, reference);
                let mut back = [[f64::NAN; N]; LANES];
                // SAFETY: as above.
                unsafe { wide_avx2::scatter(&reference, &mut back) };
                assert_eq!(back, rows);
            }
        }
        check::<1>();
        check::<3>();
        check::<4>();
        check::<5>();
        check::<8>();
        check::<11>();
        check::<16>();
    }
}

/// Exact IEEE operations on all lanes at once with AVX-512 instructions. Each function is
/// compiled for AVX-512F and VL: code built for those features (the lanes kernel) calls them
/// directly, anything else only through `unsafe`, after checking [`crate::isa::avx512`].
#[cfg(target_arch = "x86_64")]
pub mod wide {
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
        let exponent = |v: __m512d| {
            _mm512_and_si512(_mm512_srli_epi64::<52>(_mm512_castpd_si512(v)), i(0x7FF))
        };
        let ex = _mm512_srli_epi64::<20>(high);
        let r1 = sub(xv, mul(fnum, f(PIO2_1)));
        let w1 = mul(fnum, f(PIO2_1T));
        let y01 = sub(r1, w1);
        let second = _mm512_cmpgt_epi64_mask(_mm512_sub_epi64(ex, exponent(y01)), i(16));
        let w2 = mul(fnum, f(PIO2_2));
        let r2 = sub(r1, w2);
        let w2 = sub(mul(fnum, f(PIO2_2T)), sub(sub(r1, r2), w2));
        let y02 = sub(r2, w2);
        let third = second & _mm512_cmpgt_epi64_mask(_mm512_sub_epi64(ex, exponent(y02)), i(49));
        let w3 = mul(fnum, f(PIO2_3));
        let r3 = sub(r2, w3);
        let w3 = sub(mul(fnum, f(PIO2_3T)), sub(sub(r2, r3), w3));
        let y03 = sub(r3, w3);
        let pick = |a, b, c| _mm512_mask_blend_pd(third, _mm512_mask_blend_pd(second, a, b), c);
        let (r, w, y0) = (pick(r1, r2, r3), pick(w1, w2, w3), pick(y01, y02, y03));
        let y1 = sub(sub(r, y0), w);
        // |x| ≤ π/4: no reduction, y = (x, 0), quadrant 0.
        let y0 = _mm512_mask_blend_pd(small, y0, xv);
        let y1 = _mm512_mask_blend_pd(small, y1, f(0.0));
        let quadrant = _mm512_mask_blend_epi64(small, quadrant, i(0));

        // `kernel_sin` (reduced lanes) and `unreduced!`'s sine (|x| ≤ π/4).
        let z = mul(y0, y0);
        let w = mul(z, z);
        let r = add(
            add(f(S2), mul(z, add(f(S3), mul(z, f(S4))))),
            mul(mul(z, w), add(f(S5), mul(z, f(S6)))),
        );
        let v = mul(z, y0);
        let with_tail = sub(
            y0,
            sub(
                sub(mul(z, sub(mul(f(0.5), y1), mul(v, r))), y1),
                mul(v, f(S1)),
            ),
        );
        let without_tail = add(y0, mul(v, estrin!(add, mul, f, z, w, SIN_POLY)));
        let s = _mm512_mask_blend_pd(small, with_tail, without_tail);
        // `kernel_cos` (for |x| ≤ π/4 the tail is 0, x·0 = ±0 and z²Q > 0: `unreduced!`'s bits).
        let q = estrin!(add, mul, f, z, w, COS_POLY);
        let hz = mul(f(0.5), z);
        let wq = mul(w, q);
        let w = sub(f(1.0), hz);
        let c = add(w, add(sub(sub(f(1.0), w), hz), sub(wq, mul(y0, y1))));

        // Quadrant: 0 (s, c), 1 (c, −s), 2 (−s, −c), 3 (−c, s); tiny |x|: (x, 1).
        let odd = _mm512_test_epi64_mask(quadrant, i(1));
        let neg_sin = _mm512_test_epi64_mask(quadrant, i(2));
        let neg_cos = odd ^ neg_sin;
        let negate = |m: __mmask8, v: __m512d| {
            let flipped =
                _mm512_castsi512_pd(_mm512_xor_si512(_mm512_castpd_si512(v), i(i64::MIN)));
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
}

/// The operations of [`wide`] with AVX2 instructions: each lane array is two 4-wide registers.
/// The same IEEE operations in the same order per lane as [`wide`] and [`crate::trig`] (masks
/// are vectors of all-ones lanes, selections `blendv`), so the same bits; for CPUs with AVX2
/// but without AVX-512 (e.g. AMD Zen 3), where the lanes kernel would otherwise run one point
/// after the other.
#[cfg(target_arch = "x86_64")]
pub mod wide_avx2 {
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
        let exponent = |v: __m256d| {
            _mm256_and_si256(_mm256_srli_epi64::<52>(_mm256_castpd_si256(v)), i(0x7FF))
        };
        let ex = _mm256_srli_epi64::<20>(high);
        let r1 = sub(xv, mul(fnum, f(PIO2_1)));
        let w1 = mul(fnum, f(PIO2_1T));
        let y01 = sub(r1, w1);
        let second = _mm256_cmpgt_epi64(_mm256_sub_epi64(ex, exponent(y01)), i(16));
        let w2 = mul(fnum, f(PIO2_2));
        let r2 = sub(r1, w2);
        let w2 = sub(mul(fnum, f(PIO2_2T)), sub(sub(r1, r2), w2));
        let y02 = sub(r2, w2);
        let third = _mm256_and_si256(
            second,
            _mm256_cmpgt_epi64(_mm256_sub_epi64(ex, exponent(y02)), i(49)),
        );
        let w3 = mul(fnum, f(PIO2_3));
        let r3 = sub(r2, w3);
        let w3 = sub(mul(fnum, f(PIO2_3T)), sub(sub(r2, r3), w3));
        let y03 = sub(r3, w3);
        let pick = |a, b, c| select(third, select(second, a, b), c);
        let (r, w, y0) = (pick(r1, r2, r3), pick(w1, w2, w3), pick(y01, y02, y03));
        let y1 = sub(sub(r, y0), w);
        // |x| ≤ π/4: no reduction, y = (x, 0), quadrant 0.
        let y0 = select(small, y0, xv);
        let y1 = select(small, y1, f(0.0));
        let quadrant = _mm256_andnot_si256(small, quadrant);

        // `kernel_sin` (reduced lanes) and `unreduced!`'s sine (|x| ≤ π/4).
        let z = mul(y0, y0);
        let w = mul(z, z);
        let r = add(
            add(f(S2), mul(z, add(f(S3), mul(z, f(S4))))),
            mul(mul(z, w), add(f(S5), mul(z, f(S6)))),
        );
        let v = mul(z, y0);
        let with_tail = sub(
            y0,
            sub(
                sub(mul(z, sub(mul(f(0.5), y1), mul(v, r))), y1),
                mul(v, f(S1)),
            ),
        );
        let without_tail = add(y0, mul(v, estrin!(add, mul, f, z, w, SIN_POLY)));
        let s = select(small, with_tail, without_tail);
        // `kernel_cos` (for |x| ≤ π/4 the tail is 0, x·0 = ±0 and z²Q > 0: `unreduced!`'s bits).
        let q = estrin!(add, mul, f, z, w, COS_POLY);
        let hz = mul(f(0.5), z);
        let wq = mul(w, q);
        let w = sub(f(1.0), hz);
        let c = add(w, add(sub(sub(f(1.0), w), hz), sub(wq, mul(y0, y1))));

        // Quadrant: 0 (s, c), 1 (c, −s), 2 (−s, −c), 3 (−c, s); tiny |x|: (x, 1).
        let odd = _mm256_cmpeq_epi64(_mm256_and_si256(quadrant, i(1)), i(1));
        let neg_sin = _mm256_cmpeq_epi64(_mm256_and_si256(quadrant, i(2)), i(2));
        let neg_cos = _mm256_xor_si256(odd, neg_sin);
        let negate = |m: __m256i, v: __m256d| {
            let flipped =
                _mm256_castsi256_pd(_mm256_xor_si256(_mm256_castpd_si256(v), i(i64::MIN)));
            select(m, v, flipped)
        };
        let sin = negate(neg_sin, select(odd, s, c));
        let cos = negate(neg_cos, select(odd, c, s));
        (select(tiny, sin, xv), select(tiny, cos, f(1.0)))
    }
}
