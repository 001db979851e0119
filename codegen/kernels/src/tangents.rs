//! J·W, the Jacobian times each tangent vector, in the row form every path computes (the
//! generated kernels, the lanes kernel, the interpreter, the JIT): for each row r,
//! `out[r] = J[r, c₀]·w[c₀] + J[r, c₁]·w[c₁] + …` over the row's stored entries in increasing
//! column order, summed left to right; a row without stored entries is 0.0. Only stored entries
//! are multiplied: vehicle8's 8×8 Jacobian has 24, so 24 products and 16 sums per vector (a
//! column form over the six used columns multiplied 48 entries, half of them structural zeros).
//!
//! The generated kernels evaluate it for [`LANES`] tangent vectors at once where the CPU has
//! wide registers: the vectors transposed into lane arrays (lane k = tangent vector k, one
//! array per state), each stored entry multiplied as a splat, the rows transposed back. Each
//! lane performs the row form's operations in its order, so each result has the bits of the
//! one-vector form. [`Build`] names the instructions a kernel body is compiled for.

use crate::lanes::{Lanes, LANES};

/// The lane-array operations of one build of a kernel, for a body generic over the build.
///
/// # Safety
/// Implementations compute exactly the IEEE operation of each lane (the same bits as the
/// scalar operation) and move data without changing it.
pub unsafe trait Build {
    /// Whether groups of [`LANES`] tangent vectors go through lane arrays (else the vectors go
    /// one by one).
    const WIDE: bool;

    /// `a + b` in every lane.
    ///
    /// # Safety
    /// The CPU must run this build ([`crate::isa`]).
    unsafe fn add(a: Lanes, b: Lanes) -> Lanes;

    /// `a · b` in every lane.
    ///
    /// # Safety
    /// The CPU must run this build.
    unsafe fn mul(a: Lanes, b: Lanes) -> Lanes;

    /// One lane array per entry from one array per tangent vector ([`crate::lanes::gather`]).
    ///
    /// # Safety
    /// The CPU must run this build.
    unsafe fn gather<const N: usize>(rows: &[[f64; N]; LANES]) -> [Lanes; N];

    /// The inverse of [`Build::gather`] ([`crate::lanes::scatter`]).
    ///
    /// # Safety
    /// The CPU must run this build.
    unsafe fn scatter<const N: usize>(lanes: &[Lanes; N], rows: &mut [[f64; N]; LANES]);
}

/// The target's baseline instructions: tangent vectors one by one.
pub struct Baseline;

/// AVX2: lane arrays as two 4-wide registers.
pub struct Avx2;

/// AVX-512F and AVX-512VL (lane arrays as two 4-wide registers, see below).
pub struct Avx512;

// SAFETY: plain scalar operations lane by lane.
unsafe impl Build for Baseline {
    const WIDE: bool = false;

    #[inline(always)]
    unsafe fn add(a: Lanes, b: Lanes) -> Lanes {
        crate::lanewise!(|x, y| x + y; a, b)
    }

    #[inline(always)]
    unsafe fn mul(a: Lanes, b: Lanes) -> Lanes {
        crate::lanewise!(|x, y| x * y; a, b)
    }

    #[inline(always)]
    unsafe fn gather<const N: usize>(rows: &[[f64; N]; LANES]) -> [Lanes; N] {
        crate::lanes::gather(rows)
    }

    #[inline(always)]
    unsafe fn scatter<const N: usize>(lanes: &[Lanes; N], rows: &mut [[f64; N]; LANES]) {
        crate::lanes::scatter(lanes, rows)
    }
}

/// `Build` for a wide build through `lanes::wide_avx2` (4-wide registers, see below), or lane
/// by lane where the target is not x86-64 (where these builds never run).
macro_rules! wide_build {
    ($build:ty) => {
        // SAFETY: `wide_avx2`'s functions are exact lane-wise IEEE operations and data moves
        // (tested against the scalar definitions in `lanes`).
        unsafe impl Build for $build {
            const WIDE: bool = cfg!(target_arch = "x86_64");

            #[inline(always)]
            unsafe fn add(a: Lanes, b: Lanes) -> Lanes {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the caller's promise that the CPU runs this build.
                return unsafe { crate::lanes::wide_avx2::add(a, b) };
                #[cfg(not(target_arch = "x86_64"))]
                // SAFETY: scalar operations.
                return unsafe { Baseline::add(a, b) };
            }

            #[inline(always)]
            unsafe fn mul(a: Lanes, b: Lanes) -> Lanes {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the caller's promise that the CPU runs this build.
                return unsafe { crate::lanes::wide_avx2::mul(a, b) };
                #[cfg(not(target_arch = "x86_64"))]
                // SAFETY: scalar operations.
                return unsafe { Baseline::mul(a, b) };
            }

            #[inline(always)]
            unsafe fn gather<const N: usize>(rows: &[[f64; N]; LANES]) -> [Lanes; N] {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the caller's promise that the CPU runs this build.
                return unsafe { crate::lanes::wide_avx2::gather(rows) };
                #[cfg(not(target_arch = "x86_64"))]
                return crate::lanes::gather(rows);
            }

            #[inline(always)]
            unsafe fn scatter<const N: usize>(lanes: &[Lanes; N], rows: &mut [[f64; N]; LANES]) {
                #[cfg(target_arch = "x86_64")]
                // SAFETY: the caller's promise that the CPU runs this build.
                return unsafe { crate::lanes::wide_avx2::scatter(lanes, rows) };
                #[cfg(not(target_arch = "x86_64"))]
                return crate::lanes::scatter(lanes, rows);
            }
        }
    };
}

wide_build!(Avx2);
// The AVX-512 build's J·W also works on 4-wide registers: on the Intel Xeon this was measured
// on, vehicle8's f_jw (K = 8) took 73 ns with 8-wide registers and 65 ns with 4-wide ones (the
// 8-wide transposes and products cost more than twice the 4-wide); on Zen 4, which splits an
// 8-wide operation into two 4-wide ones, the width makes no difference.
wide_build!(Avx512);

/// How many of the `count` tangent vectors build `B` takes in groups of [`LANES`] (the rest go
/// one by one).
#[inline(always)]
pub fn in_groups<B: Build>(count: usize) -> usize {
    if B::WIDE {
        count / LANES * LANES
    } else {
        0
    }
}
