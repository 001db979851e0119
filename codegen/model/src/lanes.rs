//! Several independent points evaluated in one instruction stream: every IR value becomes a
//! `[f64; LANES]`, one entry per point, and every operation is applied entry by entry. Built for
//! AVX-512 (see [`crate::isa`]) each operation on a lane array is one 8-wide instruction, which
//! is what makes a map of many grid points cheaper per point than one point at a time.
//!
//! Each lane performs exactly the operations of the one-point kernel in the same order (sin and
//! cos through the same [`crate::trig::sin_cos`]), so lane `l` of a result has the bits of the
//! one-point kernel at point `l`.

/// Points per lane array: one AVX-512 register of doubles.
pub const LANES: usize = 8;

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

/// (sin, cos) of every lane, one lane after the other through [`crate::trig::sin_cos`] (same
/// bits as the one-point kernels). Not inlined on purpose: the branches of eight inline sincos
/// would split the kernel into many basic blocks, and the vectoriser, which works within one
/// block, would then leave the whole lane kernel scalar.
#[inline(never)]
pub fn sin_cos(x: Lanes) -> (Lanes, Lanes) {
    let (mut s, mut c) = ([0.0; LANES], [0.0; LANES]);
    for l in 0..LANES {
        (s[l], c[l]) = crate::trig::sin_cos(x[l]);
    }
    (s, c)
}

/// `v` at every lane.
#[inline(always)]
pub const fn splat(v: f64) -> Lanes {
    [v; LANES]
}

/// Lane arrays `out[i][l] = rows[l][i]`: from one array per point to one lane array per entry.
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
    fn scatter_inverts_gather() {
        let rows: [[f64; 3]; LANES] = core::array::from_fn(|l| [l as f64, -(l as f64), 0.5]);
        let lanes = gather(&rows);
        assert_eq!(lanes[1][5], -5.0);
        let mut back = [[0.0; 3]; LANES];
        scatter(&lanes, &mut back);
        assert_eq!(back, rows);
    }
}

/// Exact IEEE operations on all lanes at once with AVX-512 instructions. Only for code that runs
/// in an AVX-512 build (the caller guarantees the CPU has it).
#[cfg(target_arch = "x86_64")]
pub mod wide {
    use super::Lanes;
    use core::arch::x86_64::*;

    macro_rules! op {
        ($name:ident, $intr:ident) => {
            #[inline(always)]
            pub fn $name(a: Lanes, b: Lanes) -> Lanes {
                let mut out = [0.0; 8];
                // SAFETY: only called from AVX-512 builds; unaligned loads/stores of 8 doubles.
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
}
