//! A zero the optimiser cannot see through, for the structural zeros of dense kernel outputs.
//!
//! Written as the constant 0.0, a run of eight zeros (vehicle8's ∂f/∂u has eight: the
//! kinematic rows) is merged into one 512-bit store in the AVX-512 build, and on the Intel Xeon
//! this was measured on one 512-bit instruction slows the whole call: the closed-loop stage
//! kernel took 47 ns with it and 39 ns without. An opaque zero is stored like any other value;
//! together with the workspace's cap on the SLP vectoriser's register size
//! (`.cargo/config.toml`) the stores stay at most 256 bits wide.

/// +0.0, from an empty `asm!` block on x86-64 (the value is materialised, then treated as
/// unknown); the constant elsewhere.
#[inline(always)]
pub fn zero() -> f64 {
    #[allow(unused_mut)]
    let mut z = 0.0_f64;
    #[cfg(target_arch = "x86_64")]
    // SAFETY: an empty template: the register keeps its value; no memory, stack or flags.
    unsafe {
        core::arch::asm!("/* {0} */", inout(xmm_reg) z, options(pure, nomem, nostack, preserves_flags));
    }
    z
}
