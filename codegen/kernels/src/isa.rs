//! Which instruction set the generated kernels run with, decided once per process.
//!
//! The kernels are long straight-line scalar code. Built for the x86-64 baseline they have 16
//! vector registers and spill; built for AVX-512 they have 32, and the columns of a J·W product
//! become single 8-wide operations. The generated code therefore compiles every kernel twice and
//! picks the AVX-512 build when [`avx512`] says the CPU (and the OS) support it. The lanes
//! kernel (eight points in one instruction stream, the maps) has a third build for AVX2, two
//! 4-wide registers per lane array, for CPUs without AVX-512 ([`avx2`]), and on aarch64 a NEON
//! build, four 2-wide registers per lane array ([`Isa::Neon`]; NEON is part of every aarch64
//! CPU, so only [`force`] turns it off). Rust never fuses a
//! multiplication and an addition on its own, so every build performs the same IEEE operations
//! in the same order and gives the same bits (tested): the choice changes speed, never results.

use core::sync::atomic::{AtomicU8, Ordering};

/// The instruction sets kernels are built for, in increasing order (NEON exists on aarch64 only,
/// AVX2 and AVX-512 on x86-64 only: [`available`] says which this CPU runs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Isa {
    /// The target's baseline (x86-64: SSE2).
    Baseline,
    /// aarch64's Advanced SIMD (the lanes kernel's 2-wide build).
    Neon,
    /// AVX2 (the lanes kernel's 4-wide build).
    Avx2,
    /// AVX-512F and AVX-512VL.
    Avx512,
}

impl Isa {
    /// How logs and benchmarks name it.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Baseline => "baseline",
            Isa::Neon => "NEON",
            Isa::Avx2 => "AVX2",
            Isa::Avx512 => "AVX-512",
        }
    }

    fn code(self) -> u8 {
        match self {
            Isa::Baseline => 1,
            Isa::Neon => 2,
            Isa::Avx2 => 3,
            Isa::Avx512 => 4,
        }
    }
}

const UNKNOWN: u8 = 0;

static CHOICE: AtomicU8 = AtomicU8::new(UNKNOWN);

/// The instruction set the kernels use now: the best the CPU supports, unless lowered with
/// [`force`]. One relaxed atomic load after the first call; never allocates.
#[inline]
pub fn current() -> Isa {
    match CHOICE.load(Ordering::Relaxed) {
        1 => Isa::Baseline,
        2 => Isa::Neon,
        3 => Isa::Avx2,
        4 => Isa::Avx512,
        _ => detect(),
    }
}

/// Whether the generated kernels use their AVX-512 build (AVX-512F and AVX-512VL present and
/// enabled by the OS, and not switched off with [`force`]).
#[inline]
pub fn avx512() -> bool {
    current() == Isa::Avx512
}

/// Whether the lanes kernel may use its AVX2 build (AVX2 present and enabled by the OS; every
/// AVX-512 CPU has it), unless lowered with [`force`].
#[inline]
pub fn avx2() -> bool {
    current() >= Isa::Avx2
}

/// Every instruction set, in increasing order.
pub const ALL: [Isa; 4] = [Isa::Baseline, Isa::Neon, Isa::Avx2, Isa::Avx512];

/// Whether this CPU and OS run the kernels' build for `isa`.
pub fn available(isa: Isa) -> bool {
    match isa {
        Isa::Baseline => true,
        Isa::Neon => cfg!(target_arch = "aarch64"),
        Isa::Avx2 => cpu_has_avx2(),
        Isa::Avx512 => cpu_has_avx512(),
    }
}

/// Whether the lanes kernel uses its NEON build (aarch64, unless lowered with [`force`]).
#[inline]
pub fn neon() -> bool {
    current() == Isa::Neon
}

/// The best instruction set this CPU and OS support.
pub fn best() -> Isa {
    best_up_to(Isa::Avx512)
}

/// The best available instruction set that is not above `limit`.
fn best_up_to(limit: Isa) -> Isa {
    ALL.into_iter()
        .filter(|&isa| isa <= limit && available(isa))
        .max()
        .unwrap_or(Isa::Baseline)
}

/// Makes every later kernel call use the best build this CPU runs that is not above `limit`,
/// and returns it: for benchmarks and tests that show each build on one machine, e.g. an
/// AVX-512 CPU running what an AVX2-only CPU runs. Results do not change.
pub fn force(limit: Isa) -> Isa {
    let isa = best_up_to(limit);
    CHOICE.store(isa.code(), Ordering::Relaxed);
    isa
}

/// [`force`] to the baseline (`true`) or back to the best build (`false`).
pub fn force_baseline(baseline: bool) {
    force(if baseline { Isa::Baseline } else { Isa::Avx512 });
}

/// Picks, for one repeated job, the build that runs it fastest on this CPU — "the best
/// instruction set the CPU has" is not always the fastest (on an Intel Xeon the AVX-512 build of
/// the RK4 steps ran the study preset at 4.0 ms against 2.8 ms for the AVX2 build, with the
/// AVX-512 kernels in both). The job's first calls go to each build this CPU may run (up to
/// the [`force`] limit) in turn, [`ROUNDS`](Self::ROUNDS) each; the caller reports each call's
/// time per unit of work, and every later call goes to the build with the smallest time seen.
/// Every build gives the same bits, so the choice changes speed, never results. Plain data:
/// no clock, no allocation (the caller times).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// The fastest time per unit seen for each build, by [`Isa::code`] − 1.
    best: [f64; 4],
    calls: u32,
}

impl Calibration {
    /// Calls each build gets before the choice (the fastest of them counts, so one call slowed
    /// by the scheduler does not decide).
    pub const ROUNDS: u32 = 3;

    /// No call timed yet.
    pub const NEW: Self = Self {
        best: [f64::INFINITY; 4],
        calls: 0,
    };

    /// The builds this CPU may run now, fastest-expected first (NEON only builds the lanes
    /// kernel, so it is not a build of the steps: the baseline alone).
    fn candidates() -> ([Isa; 3], u32) {
        match current() {
            Isa::Avx512 => ([Isa::Avx512, Isa::Avx2, Isa::Baseline], 3),
            Isa::Avx2 => ([Isa::Avx2, Isa::Baseline, Isa::Baseline], 2),
            Isa::Neon | Isa::Baseline => ([Isa::Baseline; 3], 1),
        }
    }

    /// The build for the next call, and whether that call is to be timed and reported.
    pub fn next(&self) -> (Isa, bool) {
        let (builds, n) = Self::candidates();
        if n > 1 && self.calls < n * Self::ROUNDS {
            return (builds[(self.calls % n) as usize], true);
        }
        // The fastest build seen among those still allowed (a later `force` may lower them).
        let chosen = builds[..n as usize]
            .iter()
            .copied()
            .min_by(|a, b| self.time(*a).total_cmp(&self.time(*b)))
            .unwrap_or(Isa::Baseline);
        (chosen, false)
    }

    /// Books a timed call of `isa` that took `per_unit` (seconds per step, say).
    pub fn record(&mut self, isa: Isa, per_unit: f64) {
        let slot = &mut self.best[(isa.code() - 1) as usize];
        if per_unit < *slot {
            *slot = per_unit;
        }
        self.calls += 1;
    }

    /// The fastest time seen for `isa` (∞ before it ran).
    pub fn time(&self, isa: Isa) -> f64 {
        self.best[(isa.code() - 1) as usize]
    }
}

#[cold]
fn detect() -> Isa {
    let isa = best();
    CHOICE.store(isa.code(), Ordering::Relaxed);
    isa
}

#[cfg(target_arch = "x86_64")]
mod cpuid {
    use core::arch::x86_64::{__cpuid, __cpuid_count, _xgetbv};
    const OSXSAVE: u32 = 1 << 27;

    /// XCR0 (the register states the OS saves), if the OS has enabled XGETBV.
    pub fn xcr0() -> Option<u64> {
        if __cpuid(0).eax < 7 || __cpuid(1).ecx & OSXSAVE == 0 {
            return None;
        }
        // SAFETY: OSXSAVE is set, so the OS has enabled XGETBV.
        Some(unsafe { _xgetbv(0) })
    }

    /// EBX of CPUID leaf 7 (structured extended features).
    pub fn leaf7_ebx() -> u32 {
        __cpuid_count(7, 0).ebx
    }

    /// ECX of CPUID leaf 1.
    pub fn leaf1_ecx() -> u32 {
        __cpuid(1).ecx
    }
}

/// AVX-512F and AVX-512VL in CPUID, and the opmask and all ZMM register states enabled in XCR0
/// (what `std::is_x86_feature_detected!` checks; this crate is `no_std`).
#[cfg(target_arch = "x86_64")]
fn cpu_has_avx512() -> bool {
    // XCR0: SSE, AVX, opmask, upper halves of ZMM0-15, ZMM16-31.
    const ZMM_STATE: u64 = 0b1110_0110;
    const AVX512F: u32 = 1 << 16;
    const AVX512VL: u32 = 1 << 31;
    let Some(xcr0) = cpuid::xcr0() else {
        return false;
    };
    let ebx = cpuid::leaf7_ebx();
    xcr0 & ZMM_STATE == ZMM_STATE && ebx & AVX512F != 0 && ebx & AVX512VL != 0
}

/// AVX and AVX2 in CPUID, and the SSE and YMM register states enabled in XCR0.
#[cfg(target_arch = "x86_64")]
fn cpu_has_avx2() -> bool {
    const YMM_STATE: u64 = 0b110;
    const AVX: u32 = 1 << 28;
    const AVX2: u32 = 1 << 5;
    let Some(xcr0) = cpuid::xcr0() else {
        return false;
    };
    xcr0 & YMM_STATE == YMM_STATE && cpuid::leaf1_ecx() & AVX != 0 && cpuid::leaf7_ebx() & AVX2 != 0
}

#[cfg(not(target_arch = "x86_64"))]
fn cpu_has_avx512() -> bool {
    false
}

#[cfg(not(target_arch = "x86_64"))]
fn cpu_has_avx2() -> bool {
    false
}
