//! CasADi's external-function C API (the functions `casadi.external("f", lib)` looks up): `f`
//! with inputs `x`, `u` and output `xdot`, and its Jacobian `jac_f` by CasADi's naming rule
//! (inputs `x`, `u`, `out_xdot`; outputs `jac_xdot_x`, `jac_xdot_u`) with the IR's sparsity,
//! so that CasADi differentiates through twv's Jacobian kernels instead of finite differences.
//! The parameters are the exported values (the IR has no ∂f/∂p for a `p` input to be
//! differentiated by). Every scratch value lives in the work vector CasADi passes
//! (`f_work`), so concurrent calls share nothing.

use core::ffi::{c_char, c_int};
use std::ffi::CString;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::OnceLock;

use crate::bundle_source;
use crate::plant::Loaded;

type CasadiInt = i64;

/// (row, column) of each stored entry of a matrix, in CCS order.
type Entries = Vec<(usize, usize)>;

/// The model, its sparsity patterns and names, loaded once from this library's own file.
struct Exported {
    model: Loaded,
    /// `[nrow, ncol, colind…, row…]` of x, u, xdot (dense columns).
    dense: [Vec<CasadiInt>; 3],
    /// The same of ∂f/∂x and ∂f/∂u, as the IR stores them.
    jac: [Vec<CasadiInt>; 2],
    /// (row, column) of each stored entry of ∂f/∂x and ∂f/∂u, in CCS order.
    entries: [Entries; 2],
    names: Vec<CString>,
}

static EXPORTED: OnceLock<Result<Exported, String>> = OnceLock::new();

fn exported() -> Option<&'static Exported> {
    let loaded = EXPORTED.get_or_init(|| {
        catch_unwind(load).unwrap_or_else(|_| Err("loading the model panicked".into()))
    });
    match loaded {
        Ok(e) => Some(e),
        Err(why) => {
            static SAID: OnceLock<()> = OnceLock::new();
            SAID.get_or_init(|| eprintln!("twv export (CasADi): {why}"));
            None
        }
    }
}

fn load() -> Result<Exported, String> {
    let model = Loaded::new(&bundle_source::from_own_file()?)?;
    let (nx, nu) = (model.ir.nx(), model.ir.nu());
    let dense = |rows: usize| {
        let mut s = vec![rows as CasadiInt, 1, 0, rows as CasadiInt];
        s.extend((0..rows).map(|r| r as CasadiInt));
        s
    };
    let pattern = |function: &str| -> Result<(Vec<CasadiInt>, Entries), String> {
        let o = model
            .ir
            .output(function, function)
            .ok_or_else(|| format!("the IR has no output {function}"))?;
        let mut s = vec![o.rows as CasadiInt, o.cols as CasadiInt];
        s.extend(o.colind.iter().map(|&c| c as CasadiInt));
        s.extend(o.row.iter().map(|&r| r as CasadiInt));
        Ok((s, o.entries().map(|(r, c, _)| (r, c)).collect()))
    };
    let (jx, ex) = pattern("jac_x")?;
    let (ju, eu) = pattern("jac_u")?;
    let names = ["x", "u", "xdot", "out_xdot", "jac_xdot_x", "jac_xdot_u"]
        .iter()
        .map(|n| CString::new(*n).unwrap_or_default())
        .collect();
    Ok(Exported {
        dense: [dense(nx), dense(nu), dense(nx)],
        jac: [jx, ju],
        entries: [ex, eu],
        names,
        model,
    })
}

impl Exported {
    fn nx(&self) -> usize {
        self.model.ir.nx()
    }
    fn nu(&self) -> usize {
        self.model.ir.nu()
    }
    /// The work vector: the plant's, ∂f/∂x and ∂f/∂u dense, and zeros for an input CasADi
    /// passes as a null pointer.
    fn work_len(&self) -> usize {
        let (nx, nu) = (self.nx(), self.nu());
        self.model.plant.work_len() + nx * nx + nx * nu + nx + nu
    }
}

/// The name of entry `i` of `names` (indices into [`Exported::names`]), or null.
fn name(e: Option<&Exported>, names: &[usize], i: CasadiInt) -> *const c_char {
    let Some(e) = e else {
        return std::ptr::null();
    };
    usize::try_from(i)
        .ok()
        .and_then(|i| names.get(i))
        .and_then(|&k| e.names.get(k))
        .map_or(std::ptr::null(), |s| s.as_ptr())
}

/// An input vector CasADi passed (a null pointer is all zeros, as CasADi means it).
///
/// # Safety
/// `ptr` is null or points to `n` values.
unsafe fn input(ptr: *const f64, n: usize, zeros: &mut [f64]) -> &[f64] {
    if ptr.is_null() {
        zeros[..n].fill(0.0);
        &zeros[..n]
    } else {
        std::slice::from_raw_parts(ptr, n)
    }
}

/// Runs an evaluation, 1 (failure, as CasADi reads it) for a missing model or a panic.
fn guard(body: impl FnOnce(&Exported) -> c_int) -> c_int {
    let Some(e) = exported() else { return 1 };
    catch_unwind(AssertUnwindSafe(|| body(e))).unwrap_or(1)
}

/// The bookkeeping functions of one external function: counts, names, sparsity, work, memory.
macro_rules! bookkeeping {
    ($name:ident, $n_in:expr, $n_out:expr, $names_in:expr, $names_out:expr,
     $sparsity_in:expr, $sparsity_out:expr) => {
        pub mod $name {
            use super::*;

            #[export_name = concat!(stringify!($name), "_n_in")]
            pub extern "C" fn n_in() -> CasadiInt {
                exported().map_or(0, |_| $n_in)
            }
            #[export_name = concat!(stringify!($name), "_n_out")]
            pub extern "C" fn n_out() -> CasadiInt {
                exported().map_or(0, |_| $n_out)
            }
            #[export_name = concat!(stringify!($name), "_name_in")]
            pub extern "C" fn name_in(i: CasadiInt) -> *const c_char {
                name(exported(), &$names_in, i)
            }
            #[export_name = concat!(stringify!($name), "_name_out")]
            pub extern "C" fn name_out(i: CasadiInt) -> *const c_char {
                name(exported(), &$names_out, i)
            }
            #[export_name = concat!(stringify!($name), "_sparsity_in")]
            pub extern "C" fn sparsity_in(i: CasadiInt) -> *const CasadiInt {
                exported()
                    .and_then(|e| ($sparsity_in)(e, i))
                    .map_or(std::ptr::null(), |s: &Vec<CasadiInt>| s.as_ptr())
            }
            #[export_name = concat!(stringify!($name), "_sparsity_out")]
            pub extern "C" fn sparsity_out(i: CasadiInt) -> *const CasadiInt {
                exported()
                    .and_then(|e| ($sparsity_out)(e, i))
                    .map_or(std::ptr::null(), |s: &Vec<CasadiInt>| s.as_ptr())
            }
            /// # Safety
            /// Null or valid out-pointers, as CasADi passes them.
            #[export_name = concat!(stringify!($name), "_work")]
            pub unsafe extern "C" fn work(
                sz_arg: *mut CasadiInt,
                sz_res: *mut CasadiInt,
                sz_iw: *mut CasadiInt,
                sz_w: *mut CasadiInt,
            ) -> c_int {
                let Some(e) = exported() else { return 1 };
                let sizes = [$n_in, $n_out, 0, e.work_len() as CasadiInt];
                for (ptr, v) in [sz_arg, sz_res, sz_iw, sz_w].into_iter().zip(sizes) {
                    if let Some(p) = ptr.as_mut() {
                        *p = v;
                    }
                }
                0
            }
            #[export_name = concat!(stringify!($name), "_incref")]
            pub extern "C" fn incref() {}
            #[export_name = concat!(stringify!($name), "_decref")]
            pub extern "C" fn decref() {}
            #[export_name = concat!(stringify!($name), "_checkout")]
            pub extern "C" fn checkout() -> c_int {
                0
            }
            #[export_name = concat!(stringify!($name), "_release")]
            pub extern "C" fn release(_mem: c_int) {}
        }
    };
}

bookkeeping!(
    f,
    2,
    1,
    [0usize, 1],
    [2usize],
    |e: &'static Exported, i: CasadiInt| match i {
        0 => Some(&e.dense[0]),
        1 => Some(&e.dense[1]),
        _ => None,
    },
    |e: &'static Exported, i: CasadiInt| (i == 0).then_some(&e.dense[2])
);

bookkeeping!(
    jac_f,
    3,
    2,
    [0usize, 1, 3],
    [4usize, 5],
    |e: &'static Exported, i: CasadiInt| match i {
        0 => Some(&e.dense[0]),
        1 => Some(&e.dense[1]),
        2 => Some(&e.dense[2]),
        _ => None,
    },
    |e: &'static Exported, i: CasadiInt| match i {
        0 => Some(&e.jac[0]),
        1 => Some(&e.jac[1]),
        _ => None,
    }
);

/// CasADi's work vector, split as [`Exported::work_len`] lays it out.
struct Scratch<'a> {
    work: &'a mut [f64],
    dense_x: &'a mut [f64],
    dense_u: &'a mut [f64],
    zero_x: &'a mut [f64],
    zero_u: &'a mut [f64],
}

/// # Safety
/// `w` is null or holds the `*_work` size of values.
unsafe fn scratch(e: &Exported, w: *mut f64) -> Option<Scratch<'_>> {
    if w.is_null() {
        return None;
    }
    let (nx, nu) = (e.nx(), e.nu());
    let all = std::slice::from_raw_parts_mut(w, e.work_len());
    let (work, rest) = all.split_at_mut(e.model.plant.work_len());
    let (dense_x, rest) = rest.split_at_mut(nx * nx);
    let (dense_u, rest) = rest.split_at_mut(nx * nu);
    let (zero_x, zero_u) = rest.split_at_mut(nx);
    Some(Scratch {
        work,
        dense_x,
        dense_u,
        zero_x,
        zero_u,
    })
}

/// `xdot = f(x, u)`.
///
/// # Safety
/// As CasADi calls an external function: `arg`/`res` hold `n_in`/`n_out` pointers (null
/// allowed), `w` the work `f_work` asked for.
#[no_mangle]
pub unsafe extern "C" fn f(
    arg: *const *const f64,
    res: *const *mut f64,
    _iw: *mut CasadiInt,
    w: *mut f64,
    _mem: c_int,
) -> c_int {
    guard(|e| {
        let (nx, nu) = (e.nx(), e.nu());
        let Some(s) = scratch(e, w) else { return 1 };
        let (arg, res) = (
            std::slice::from_raw_parts(arg, 2),
            std::slice::from_raw_parts(res, 1),
        );
        if res[0].is_null() {
            return 0;
        }
        let x = input(arg[0], nx, s.zero_x);
        let u = input(arg[1], nu, s.zero_u);
        let out = std::slice::from_raw_parts_mut(res[0], nx);
        e.model.plant.f(&e.model.params, x, u, out, s.work);
        0
    })
}

/// `jac_xdot_x`, `jac_xdot_u` at `(x, u)`: the stored entries of the IR's patterns.
///
/// # Safety
/// As for [`f`] (three inputs: x, u and the nominal output, which is not read).
#[no_mangle]
pub unsafe extern "C" fn jac_f(
    arg: *const *const f64,
    res: *const *mut f64,
    _iw: *mut CasadiInt,
    w: *mut f64,
    _mem: c_int,
) -> c_int {
    guard(|e| {
        let (nx, nu) = (e.nx(), e.nu());
        let Some(s) = scratch(e, w) else { return 1 };
        let (arg, res) = (
            std::slice::from_raw_parts(arg, 3),
            std::slice::from_raw_parts(res, 2),
        );
        let x = input(arg[0], nx, s.zero_x);
        let u = input(arg[1], nu, s.zero_u);
        let (plant, p) = (&e.model.plant, &e.model.params);
        if !res[0].is_null() {
            plant.jac_x(p, x, u, s.dense_x, s.work);
            stored(&e.entries[0], s.dense_x, nx, res[0]);
        }
        if !res[1].is_null() {
            plant.jac_u(p, x, u, s.dense_u, s.work);
            stored(&e.entries[1], s.dense_u, nu, res[1]);
        }
        0
    })
}

/// The stored entries of a dense row-major matrix of `cols` columns, in CCS order, into `out`.
///
/// # Safety
/// `out` points to `entries.len()` values.
unsafe fn stored(entries: &[(usize, usize)], dense: &[f64], cols: usize, out: *mut f64) {
    let out = std::slice::from_raw_parts_mut(out, entries.len());
    for (o, &(r, c)) in out.iter_mut().zip(entries) {
        *o = dense[r * cols + c];
    }
}
