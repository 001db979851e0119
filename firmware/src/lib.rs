//! twv's generated kernels on a microcontroller. `no_std`, no allocation, no panics: what a
//! balancing vehicle's firmware runs beside its sensors.
//!
//! - [`pd`]: the pitch PD law of `twv simulate` (F = sat(Kp (Φ − A sin Φ) + Kd w_y)) and the
//!   model closed by it, stepped with fixed-step RK4 ([`twv_step`]); for any model with the
//!   states `phi`, `w_y` and the input `F1`. Same operations in the same order as the analysis
//!   library, so the same bits on every IEEE-754 CPU.
//! - [`c_api`]: the study's vehicle (`vehicle8`) for firmware written in C: the functions of
//!   `include/twv_firmware.h`, in the static library `libtwv_firmware.a`.
//! - [`case`]: one fixed computation printed as bits, run on the host and under QEMU's Cortex-M4
//!   emulation by `.ci/cortex-m-test.sh` to show both give the same bits.
//!
//! The kernels are f64 everywhere. On a Cortex-M4F (single-precision FPU only) double arithmetic
//! is compiler-builtins' software floating point: IEEE-exact, so the bits of an x86-64 run, at
//! the cost in cycles that `docs/src/export.md` reports. No f32 build is made: an f32 loop
//! would not reproduce the results twv's analyses certify.
#![no_std]

// Hosted builds (the tests, the static library for a PC) link std for its panic handler.
#[cfg(not(target_os = "none"))]
extern crate std;

pub mod c_api;
pub mod case;
pub mod pd;

/// Bare metal: a panic (none is reachable: no indexing out of range, no unwrap) stops the core.
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}
