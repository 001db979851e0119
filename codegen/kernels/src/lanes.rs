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
/// `wide::sin_cos`, `wide_avx2::sin_cos`, `wide_neon::sin_cos` or one lane after the other.
/// Every path has the bits of [`crate::trig::sin_cos`]; for callers outside a `target_feature`
/// build (the closed loop's setpoint in the maps).
#[inline]
pub fn sin_cos(x: Lanes) -> (Lanes, Lanes) {
    #[cfg(target_arch = "x86_64")]
    match crate::isa::current() {
        // SAFETY: `current` returns an ISA only when the CPU and the OS support it.
        crate::isa::Isa::Avx512 => return unsafe { wide::sin_cos(x) },
        // SAFETY: as above.
        crate::isa::Isa::Avx2 => return unsafe { wide_avx2::sin_cos(x) },
        crate::isa::Isa::Neon | crate::isa::Isa::Baseline => {}
    }
    #[cfg(target_arch = "aarch64")]
    if crate::isa::neon() {
        // SAFETY: NEON is part of every aarch64 CPU.
        return unsafe { wide_neon::sin_cos(x) };
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

/// [`gather`] for a matrix: `out[r][c][l] = rows[l][r][c]`.
#[inline(always)]
pub fn gather_matrix<const R: usize, const C: usize>(
    rows: &[[[f64; C]; R]; LANES],
) -> [[Lanes; C]; R] {
    let mut out = [[[0.0; LANES]; C]; R];
    for (l, matrix) in rows.iter().enumerate() {
        for (out_row, row) in out.iter_mut().zip(matrix) {
            for (lanes, v) in out_row.iter_mut().zip(row) {
                lanes[l] = *v;
            }
        }
    }
    out
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
    fn wide_gathers_and_scatters_are_the_definitions() {
        fn check<const N: usize>() {
            let rows: [[f64; N]; LANES] =
                core::array::from_fn(|l| core::array::from_fn(|i| (10 * l + i) as f64 - 0.5));
            let reference = gather(&rows);
            #[cfg(target_arch = "aarch64")]
            // SAFETY: NEON is part of every aarch64 CPU.
            assert_eq!(unsafe { wide_neon::gather(&rows) }, reference);
            #[cfg(target_arch = "x86_64")]
            if crate::isa::best() >= crate::isa::Isa::Avx512 {
                // SAFETY: the CPU has AVX-512F and AVX-512VL.
                assert_eq!(unsafe { wide::gather(&rows) }, reference);
            }
            #[cfg(target_arch = "x86_64")]
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
pub mod wide;

/// The operations of [`wide`] with AVX2 instructions: each lane array is two 4-wide registers.
/// The same IEEE operations in the same order per lane as [`wide`] and [`crate::trig`] (masks
/// are vectors of all-ones lanes, selections `blendv`), so the same bits; for CPUs with AVX2
/// but without AVX-512 (e.g. AMD Zen 3), where the lanes kernel would otherwise run one point
/// after the other.
#[cfg(target_arch = "x86_64")]
pub mod wide_avx2;

/// The operations of [`wide`] with aarch64's Advanced SIMD (NEON): each lane array is four
/// 2-wide registers, masks are all-ones lanes and selections `bsl`. The same IEEE operations in
/// the same order per lane as [`crate::trig`], so the same bits. NEON is part of every aarch64
/// CPU, so no run-time check; Rust still wants the functions compiled for the feature and
/// called from code that is (the lanes kernel's NEON build) or in `unsafe`.
#[cfg(target_arch = "aarch64")]
pub mod wide_neon;
