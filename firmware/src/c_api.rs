//! The study's vehicle (`vehicle8`) for firmware written in C: the functions declared in
//! `include/twv_firmware.h`. Arrays are caller-owned; nothing allocates; every function checks
//! its pointers and says through its return value whether the result is finite.

use core::ffi::c_int;

use twv_generated::Vehicle8;
use twv_model::Model;

use crate::pd::{ClosedLoop, PitchPd};

/// Number of states (`TWV_VEHICLE8_NX`).
pub const NX: usize = Vehicle8::NX;
/// Number of inputs (`TWV_VEHICLE8_NU`).
pub const NU: usize = Vehicle8::NU;
/// Number of parameters (`TWV_VEHICLE8_NP`).
pub const NP: usize = Vehicle8::NP;

/// The results are finite (`TWV_OK`).
pub const OK: c_int = 0;
/// A result is NaN or infinite: the state blew up or the inputs were not finite
/// (`TWV_NOT_FINITE`).
pub const NOT_FINITE: c_int = 1;
/// A pointer argument was null; nothing was written (`TWV_NULL_POINTER`).
pub const NULL_POINTER: c_int = -1;
/// The step size is not finite and > 0; nothing was written (`TWV_BAD_STEP`).
pub const BAD_STEP: c_int = -2;
/// The model lacks the law's states (`phi`, `w_y`) or input (`F1`) (`TWV_NOT_WIRED`).
pub const NOT_WIRED: c_int = -3;

/// `N` values from a C array, `None` for a null pointer.
///
/// # Safety
/// A non-null `p` points to `N` readable values.
unsafe fn read<const N: usize>(p: *const f64) -> Option<[f64; N]> {
    // SAFETY: the caller's promise; an unaligned read tolerates any double array.
    (!p.is_null()).then(|| unsafe { core::ptr::read_unaligned(p as *const [f64; N]) })
}

/// `values` into a C array (a null pointer was refused before).
///
/// # Safety
/// `p` points to `values.len()` writable values.
unsafe fn write(p: *mut f64, values: &[f64]) {
    // SAFETY: the caller's promise; the ranges cannot overlap a local array.
    unsafe { core::ptr::copy_nonoverlapping(values.as_ptr(), p, values.len()) };
}

fn finite(values: &[f64]) -> c_int {
    if values.iter().all(|v| v.is_finite()) {
        OK
    } else {
        NOT_FINITE
    }
}

/// The model at `p`, state `x` and input `u`, or `None` if any pointer is null.
///
/// # Safety
/// Non-null pointers point to `NP`, `NX` and `NU` values.
unsafe fn point(
    p: *const f64,
    x: *const f64,
    u: *const f64,
) -> Option<(Vehicle8, [f64; NX], [f64; NU])> {
    unsafe { Some((Vehicle8::new(read(p)?), read(x)?, read(u)?)) }
}

/// Writes the IR's default parameter values (the study's vehicle) into `p[NP]`.
///
/// # Safety
/// `p` is null or points to `NP` writable values.
#[unsafe(no_mangle)]
pub unsafe extern "C" fn twv_vehicle8_defaults(p: *mut f64) -> c_int {
    if p.is_null() {
        return NULL_POINTER;
    }
    unsafe { write(p, &Vehicle8::DEFAULTS) };
    OK
}

/// `dx[NX]` = f(x, u) with parameters `p[NP]`.
///
/// # Safety
/// Each pointer is null or points to its array's length of values (`dx` writable).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn twv_vehicle8_f(
    p: *const f64,
    x: *const f64,
    u: *const f64,
    dx: *mut f64,
) -> c_int {
    let Some((model, x, u)) = (unsafe { point(p, x, u) }) else {
        return NULL_POINTER;
    };
    if dx.is_null() {
        return NULL_POINTER;
    }
    let mut out = [0.0; NX];
    model.f(&x, &u, &mut out);
    unsafe { write(dx, &out) };
    finite(&out)
}

/// `jac[NX * NX]` = ∂f/∂x at (x, u), row-major (`jac[i * NX + j]` = ∂f_i/∂x_j).
///
/// # Safety
/// Each pointer is null or points to its array's length of values (`jac` writable).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn twv_vehicle8_jac_x(
    p: *const f64,
    x: *const f64,
    u: *const f64,
    jac: *mut f64,
) -> c_int {
    let Some((model, x, u)) = (unsafe { point(p, x, u) }) else {
        return NULL_POINTER;
    };
    if jac.is_null() {
        return NULL_POINTER;
    }
    let mut out = [[0.0; NX]; NX];
    model.jac_x(&x, &u, &mut out);
    unsafe { write(jac, out.as_flattened()) };
    finite(out.as_flattened())
}

/// `jac[NX * NU]` = ∂f/∂u at (x, u), row-major (`jac[i * NU + j]` = ∂f_i/∂u_j).
///
/// # Safety
/// Each pointer is null or points to its array's length of values (`jac` writable).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn twv_vehicle8_jac_u(
    p: *const f64,
    x: *const f64,
    u: *const f64,
    jac: *mut f64,
) -> c_int {
    let Some((model, x, u)) = (unsafe { point(p, x, u) }) else {
        return NULL_POINTER;
    };
    if jac.is_null() {
        return NULL_POINTER;
    }
    let mut out = [[0.0; NU]; NX];
    model.jac_u(&x, &u, &mut out);
    unsafe { write(jac, out.as_flattened()) };
    finite(out.as_flattened())
}

/// The force the law `pd` applies at state `x[NX]` [N] (NaN for a null pointer).
///
/// # Safety
/// Each pointer is null or points to its value(s).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn twv_pitch_pd_force(pd: *const PitchPd, x: *const f64) -> f64 {
    let model = Vehicle8::with_defaults();
    match (unsafe { pd.as_ref() }, unsafe { read::<NX>(x) }) {
        (Some(pd), Some(x)) => ClosedLoop::new(&model, *pd).map_or(f64::NAN, |c| c.force(&x)),
        _ => f64::NAN,
    }
}

/// `steps` RK4 steps of size `h` [s] of vehicle8 (parameters `p[NP]`) closed by the law `pd`,
/// from the state `x[NX]`, written back into `x`. Stops at the first non-finite state
/// (`TWV_NOT_FINITE`, `x` holds it).
///
/// # Safety
/// Each pointer is null or points to its value(s) (`x` writable).
#[unsafe(no_mangle)]
pub unsafe extern "C" fn twv_vehicle8_pd_rk4(
    p: *const f64,
    pd: *const PitchPd,
    x: *mut f64,
    h: f64,
    steps: u32,
) -> c_int {
    let (Some(values), Some(pd), Some(mut state)) =
        (unsafe { read::<NP>(p) }, unsafe { pd.as_ref() }, unsafe {
            read::<NX>(x)
        })
    else {
        return NULL_POINTER;
    };
    if !(h.is_finite() && h > 0.0) {
        return BAD_STEP;
    }
    let model = Vehicle8::new(values);
    let Some(closed) = ClosedLoop::new(&model, *pd) else {
        return NOT_WIRED;
    };
    let done = closed.rk4(&mut state, h, steps);
    unsafe { write(x, &state) };
    if done {
        OK
    } else {
        NOT_FINITE
    }
}
