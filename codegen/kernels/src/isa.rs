//! Which instruction set the generated kernels run with, decided once per process.
//!
//! The kernels are long straight-line scalar code. Built for the x86-64 baseline they have 16
//! vector registers and spill; built for AVX-512 they have 32, and the columns of a J·W product
//! become single 8-wide operations. The generated code therefore compiles every kernel twice and
//! picks the AVX-512 build when [`avx512`] says the CPU (and the OS) support it. Rust never fuses
//! a multiplication and an addition on its own, so both builds perform the same IEEE operations
//! in the same order and give the same bits (tested): the choice changes speed, never results.

use core::sync::atomic::{AtomicU8, Ordering};

const UNKNOWN: u8 = 0;
const BASELINE: u8 = 1;
const AVX512: u8 = 2;

static CHOICE: AtomicU8 = AtomicU8::new(UNKNOWN);

/// Whether the generated kernels use their AVX-512 build (AVX-512F and AVX-512VL present and
/// enabled by the OS, and not switched off with [`force_baseline`]). One relaxed atomic load
/// after the first call; never allocates.
#[inline]
pub fn avx512() -> bool {
    match CHOICE.load(Ordering::Relaxed) {
        AVX512 => true,
        BASELINE => false,
        _ => detect(),
    }
}

/// Makes every later kernel call use the baseline build (or, with `false`, the best build the
/// CPU supports again): for benchmarks that show what the AVX-512 build is worth. Results do
/// not change.
pub fn force_baseline(baseline: bool) {
    let choice = if !baseline && cpu_has_avx512() {
        AVX512
    } else {
        BASELINE
    };
    CHOICE.store(choice, Ordering::Relaxed);
}

#[cold]
fn detect() -> bool {
    let on = cpu_has_avx512();
    CHOICE.store(if on { AVX512 } else { BASELINE }, Ordering::Relaxed);
    on
}

/// AVX-512F and AVX-512VL in CPUID, and the opmask and all ZMM register states enabled in XCR0
/// (what `std::is_x86_feature_detected!` checks; this crate is `no_std`).
#[cfg(target_arch = "x86_64")]
fn cpu_has_avx512() -> bool {
    use core::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};
    const OSXSAVE: u32 = 1 << 27;
    // XCR0: SSE, AVX, opmask, upper halves of ZMM0-15, ZMM16-31.
    const ZMM_STATE: u64 = 0b1110_0110;
    const AVX512F: u32 = 1 << 16;
    const AVX512VL: u32 = 1 << 31;
    if __cpuid(0).eax < 7 || __cpuid(1).ecx & OSXSAVE == 0 {
        return false;
    }
    // SAFETY: OSXSAVE is set, so the OS has enabled XGETBV.
    let xcr0 = unsafe { _xgetbv(0) };
    let ebx = __cpuid_count(7, 0).ebx;
    xcr0 & ZMM_STATE == ZMM_STATE && ebx & AVX512F != 0 && ebx & AVX512VL != 0
}

#[cfg(not(target_arch = "x86_64"))]
fn cpu_has_avx512() -> bool {
    false
}
