//! twv-firmware on an emulated Cortex-M4F (QEMU `-M mps2-an386 -semihosting -icount shift=0`):
//! prints the case's results as bits (compared with the host's by .ci/cortex-m-test.sh), then
//! the instructions one RK4 step of the closed loop and one f take. With `-icount shift=0` each
//! instruction advances the virtual clock by 1 ns, and SysTick counts that clock: its ticks per
//! instruction are measured here on a loop of known length, not assumed.
#![no_std]
#![no_main]

use core::fmt::Write;

use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hio};
use twv_firmware::c_api;
use twv_firmware::case::Case;

/// The case, given at build time by .ci/cortex-m-test.sh.
const CASE: &str = env!("TWV_FIRMWARE_CASE");

/// SysTick's reload: it counts down from 2^24 − 1 and wraps.
const RELOAD: u32 = 0x00FF_FFFF;

/// SysTick ticks elapsed while `work` runs (less than 2^24 of them).
fn ticks(syst: &mut SYST, work: impl FnOnce()) -> u32 {
    syst.clear_current();
    let start = SYST::get_current();
    work();
    let end = SYST::get_current();
    start.wrapping_sub(end) & RELOAD
}

/// `n` iterations of a two-instruction loop (`subs`, `bne`): 2n instructions.
fn known_loop(n: u32) {
    // SAFETY: a register-only countdown; no memory, no stack.
    unsafe {
        core::arch::asm!("2:", "subs {0}, #1", "bne 2b", inout(reg) n => _, options(nomem, nostack));
    }
}

/// Ends the emulation with a status (`debug::exit` returns only where no debugger listens).
fn exit(status: debug::ExitStatus) -> ! {
    debug::exit(status);
    loop {
        cortex_m::asm::wfi();
    }
}

#[entry]
fn main() -> ! {
    let mut out = match hio::hstdout() {
        Ok(out) => out,
        Err(()) => exit(debug::EXIT_FAILURE),
    };
    let case = match Case::parse(CASE) {
        Ok(case) => case,
        Err(bad) => {
            let _ = writeln!(out, "case: cannot read {:?}", bad.0);
            exit(debug::EXIT_FAILURE);
        }
    };
    if case.run(&mut out).is_err() {
        exit(debug::EXIT_FAILURE);
    }

    let Some(peripherals) = cortex_m::Peripherals::take() else {
        exit(debug::EXIT_FAILURE);
    };
    let mut syst = peripherals.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(RELOAD);
    syst.enable_counter();

    // Ticks per instruction, from 2·10^6 instructions of the known loop.
    let calibration_instructions = 2_000_000u32;
    let calibration = ticks(&mut syst, || known_loop(calibration_instructions / 2));
    // One RK4 step and one f, averaged over many.
    let steps = 200u32;
    let mut state = case.x;
    let rk4 = ticks(&mut syst, || unsafe {
        // SAFETY: arrays of the lengths the C API reads and writes.
        c_api::twv_vehicle8_pd_rk4(case.p.as_ptr(), &case.pd, state.as_mut_ptr(), case.h, steps);
    });
    let calls = 800u32;
    let mut dx = [0.0; c_api::NX];
    let f = ticks(&mut syst, || {
        for _ in 0..calls {
            // SAFETY: as above; black_box keeps the calls from being merged.
            unsafe {
                c_api::twv_vehicle8_f(
                    core::hint::black_box(case.p.as_ptr()),
                    case.x.as_ptr(),
                    case.u.as_ptr(),
                    dx.as_mut_ptr(),
                )
            };
        }
    });
    let _ = writeln!(
        out,
        "timing calibration_ticks={calibration} calibration_instructions={calibration_instructions} \
         rk4_ticks={rk4} rk4_steps={steps} f_ticks={f} f_calls={calls}"
    );
    exit(debug::EXIT_SUCCESS)
}
