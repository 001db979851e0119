//! The column form of a J·W product, `out = Σ_c J[:, c] · w[c]`, used by generated code and
//! the interpreter alike. Each step is a fixed-size loop over one column of the Jacobian, which
//! the compiler turns into vector operations (one 8-wide operation per column for an 8-state
//! model built for AVX-512). Structural zeros of a used column are multiplied too: the result
//! is the row-by-row sum of the stored terms in increasing column order, plus exact zeros, which
//! can change only the sign of a zero.

/// The first column's contribution: `col · s`.
#[inline(always)]
pub fn scaled<const N: usize>(col: &[f64; N], s: f64) -> [f64; N] {
    let mut out = [0.0; N];
    for (o, c) in out.iter_mut().zip(col) {
        *o = c * s;
    }
    out
}

/// Every further column: `acc += col · s`.
#[inline(always)]
pub fn add_scaled<const N: usize>(acc: &mut [f64; N], col: &[f64; N], s: f64) {
    for (a, c) in acc.iter_mut().zip(col) {
        *a += c * s;
    }
}

/// `x`, with the optimiser no longer knowing anything about it (that it is 0, 1 or the negation
/// of another entry). Costs nothing: an empty instruction template on the value's register
/// (elsewhere `core::hint::black_box`, which goes through memory).
#[inline(always)]
pub fn opaque(x: f64) -> f64 {
    #[cfg(target_arch = "x86_64")]
    {
        let mut x = x;
        // SAFETY: an empty template: no instruction runs, no memory or flag is touched.
        unsafe {
            core::arch::asm!("/* {0} */", inout(xmm_reg) x, options(pure, nomem, nostack, preserves_flags));
        }
        x
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        core::hint::black_box(x)
    }
}
