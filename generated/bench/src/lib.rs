//! Bench-only support for `cargo bench -p twv-bench`: CasADi's own generated C for vehicle8
//! (written by the Python modeling step and compiled at -O3 by build.rs), a correctness gate
//! that checks it against the generated Rust kernels, and a small paired timing harness.
//!
//! The C is the peer the Rust kernels are judged against (docs/src/benchmarks.md): both come from the
//! same CasADi graph, so a speed ratio only means something if they also compute the same numbers,
//! which [`gate`] checks before anything is timed.
//!
//! A benchmark, not a test: nothing here asserts a wall time.

use std::ffi::c_int;
use std::fmt;
use std::hint::black_box;
use std::time::{Duration, Instant};

use twv_baked_paper as baked;
use twv_generated::Vehicle8;
use twv_ir::Ir;
use twv_model::Model;

mod magnitude;
mod same_bits;

pub use same_bits::{same_bits, Run};

/// States, inputs, parameters, stored entries of ∂f/∂x and tangent vectors of vehicle8.
pub const NX: usize = Vehicle8::NX;
pub const NU: usize = Vehicle8::NU;
pub const NP: usize = Vehicle8::NP;
pub const NNZ: usize = Vehicle8::JAC_NNZ;
pub const K: usize = 8;

/// CasADi's `casadi_int` in the exported C (`long long int`).
type CasadiInt = i64;
/// `int fn(const casadi_real** arg, casadi_real** res, casadi_int* iw, casadi_real* w, int mem)`.
type EvalFn = unsafe extern "C" fn(
    *const *const f64,
    *mut *mut f64,
    *mut CasadiInt,
    *mut f64,
    c_int,
) -> c_int;
type WorkFn =
    unsafe extern "C" fn(*mut CasadiInt, *mut CasadiInt, *mut CasadiInt, *mut CasadiInt) -> c_int;
type CountFn = unsafe extern "C" fn() -> CasadiInt;
type SparsityFn = unsafe extern "C" fn(CasadiInt) -> *const CasadiInt;

/// The entry points CasADi writes for one function (see the generated header), by name.
#[derive(Clone, Copy)]
struct Entry {
    name: &'static str,
    eval: EvalFn,
    work: WorkFn,
    n_in: CountFn,
    n_out: CountFn,
    sparsity_in: SparsityFn,
    sparsity_out: SparsityFn,
}

/// `const $id: Entry` for the C function `$name` and its companions `$name_work`, ...
macro_rules! casadi_function {
    ($id:ident = $name:literal) => {
        const $id: Entry = {
            extern "C" {
                #[link_name = $name]
                fn eval(
                    arg: *const *const f64,
                    res: *mut *mut f64,
                    iw: *mut CasadiInt,
                    w: *mut f64,
                    mem: c_int,
                ) -> c_int;
                #[link_name = concat!($name, "_work")]
                fn work(
                    sz_arg: *mut CasadiInt,
                    sz_res: *mut CasadiInt,
                    sz_iw: *mut CasadiInt,
                    sz_w: *mut CasadiInt,
                ) -> c_int;
                #[link_name = concat!($name, "_n_in")]
                fn n_in() -> CasadiInt;
                #[link_name = concat!($name, "_n_out")]
                fn n_out() -> CasadiInt;
                #[link_name = concat!($name, "_sparsity_in")]
                fn sparsity_in(i: CasadiInt) -> *const CasadiInt;
                #[link_name = concat!($name, "_sparsity_out")]
                fn sparsity_out(i: CasadiInt) -> *const CasadiInt;
            }
            Entry {
                name: $name,
                eval,
                work,
                n_in,
                n_out,
                sparsity_in,
                sparsity_out,
            }
        };
    };
}

#[cfg(feature = "bicycle-peer")]
pub mod bicycle;

casadi_function!(C_F = "vehicle8_f");
casadi_function!(C_F_JAC_X = "vehicle8_f_jac_x");
casadi_function!(C_F_JW8 = "vehicle8_f_jw8");
casadi_function!(C_F_BAKED = "vehicle8_f_baked");
casadi_function!(C_F_JAC_X_BAKED = "vehicle8_f_jac_x_baked");
casadi_function!(C_F_JW8_BAKED = "vehicle8_f_jw8_baked");
casadi_function!(H_F = "vehicle8_hand_f");
casadi_function!(H_F_JAC_X = "vehicle8_hand_f_jac_x");
casadi_function!(H_F_JW8 = "vehicle8_hand_f_jw8");
casadi_function!(H_F_BAKED = "vehicle8_hand_f_baked");
casadi_function!(H_F_JAC_X_BAKED = "vehicle8_hand_f_jac_x_baked");
casadi_function!(H_F_JW8_BAKED = "vehicle8_hand_f_jw8_baked");

/// Operation counts (after CSE) of the exported functions `f`, `f_jac_x`, `f_jw8`: twv's
/// derivation, then the hand formulation (JSON written by `export-c`).
pub const OPS: [&str; 2] = [
    include_str!(concat!(env!("OUT_DIR"), "/vehicle8_ops.json")),
    include_str!(concat!(env!("OUT_DIR"), "/vehicle8_hand_ops.json")),
];

/// The dense shape `(rows, cols)` of a CasADi sparsity pattern, or `None` when it is not dense.
///
/// # Safety
/// `sp` is null or a pattern returned by the exported C (`nrow, ncol, 1` or `nrow, ncol, colind,
/// row`), which lives as long as the program.
unsafe fn dense_shape(sp: *const CasadiInt) -> Option<(usize, usize)> {
    if sp.is_null() {
        return None;
    }
    let (nrow, ncol) = (*sp, *sp.add(1));
    let (nrow, ncol) = (usize::try_from(nrow).ok()?, usize::try_from(ncol).ok()?);
    if *sp.add(2) == 1 {
        return Some((nrow, ncol));
    }
    // The long form: dense if every column is full.
    let colind = std::slice::from_raw_parts(sp.add(2), ncol + 1);
    let full = colind
        .iter()
        .enumerate()
        .all(|(c, &v)| usize::try_from(v).ok() == Some(c * nrow));
    full.then_some((nrow, ncol))
}

/// The CCS pattern `(colind, row)` of a CasADi sparsity pattern.
///
/// # Safety
/// As for [`dense_shape`], and not null.
unsafe fn ccs(sp: *const CasadiInt) -> (Vec<CasadiInt>, Vec<CasadiInt>) {
    let ncol = usize::try_from(*sp.add(1)).unwrap_or(0);
    if *sp.add(2) == 1 {
        let nrow = *sp;
        let colind = (0..=ncol as CasadiInt).map(|c| c * nrow).collect();
        let row = (0..ncol).flat_map(|_| 0..nrow).collect();
        return (colind, row);
    }
    let colind = std::slice::from_raw_parts(sp.add(2), ncol + 1).to_vec();
    let nnz = usize::try_from(colind[ncol]).unwrap_or(0);
    let row = std::slice::from_raw_parts(sp.add(3 + ncol), nnz).to_vec();
    (colind, row)
}

/// A CasADi C function whose inputs and outputs were checked against the shapes this crate
/// passes, so that [`CFunction::call`] only hands the C buffers of the sizes it reads and writes.
struct CFunction {
    entry: Entry,
}

impl CFunction {
    /// Checks the C function against the expected input and output patterns: `Ok(dense)` is a
    /// dense `(rows, cols)`, `Err((colind, row))` a sparse CCS pattern.
    #[allow(clippy::type_complexity)]
    fn checked(
        entry: Entry,
        inputs: &[(usize, usize)],
        outputs: &[Result<(usize, usize), (&[usize], &[usize])>],
    ) -> Result<Self, String> {
        let name = entry.name;
        let (mut sz_arg, mut sz_res, mut sz_iw, mut sz_w) = (0, 0, 0, 0);
        // SAFETY: the C functions only read their arguments and write through the pointers.
        unsafe {
            if (entry.work)(&mut sz_arg, &mut sz_res, &mut sz_iw, &mut sz_w) != 0 {
                return Err(format!("{name}_work failed"));
            }
            let (n_in, n_out) = ((entry.n_in)(), (entry.n_out)());
            if (n_in, n_out) != (inputs.len() as CasadiInt, outputs.len() as CasadiInt) {
                return Err(format!(
                    "{name}: {n_in} inputs and {n_out} outputs, expected {} and {}",
                    inputs.len(),
                    outputs.len()
                ));
            }
            // The pointer arrays passed are exactly n_in / n_out long and no work arrays are
            // passed, so the function must not need more (CasADi's C for these straight-line
            // functions needs none).
            if (sz_arg, sz_res, sz_iw, sz_w) != (n_in, n_out, 0, 0) {
                return Err(format!(
                    "{name}: work sizes arg {sz_arg}, res {sz_res}, iw {sz_iw}, w {sz_w}; the \
                     benchmark only supports functions without work arrays"
                ));
            }
            for (i, &shape) in inputs.iter().enumerate() {
                let got = dense_shape((entry.sparsity_in)(i as CasadiInt));
                if got != Some(shape) {
                    return Err(format!(
                        "{name}: input {i} is {got:?}, expected dense {shape:?}"
                    ));
                }
            }
            for (i, expected) in outputs.iter().enumerate() {
                let sp = (entry.sparsity_out)(i as CasadiInt);
                if sp.is_null() {
                    return Err(format!("{name}: no output {i}"));
                }
                match *expected {
                    Ok(shape) => {
                        let got = dense_shape(sp);
                        if got != Some(shape) {
                            return Err(format!(
                                "{name}: output {i} is {got:?}, expected dense {shape:?}"
                            ));
                        }
                    }
                    Err((colind, row)) => {
                        let as_int =
                            |v: &[usize]| v.iter().map(|&k| k as CasadiInt).collect::<Vec<_>>();
                        if ccs(sp) != (as_int(colind), as_int(row)) {
                            return Err(format!(
                                "{name}: output {i} has another sparsity than the IR's jac_x \
                                 (the IR and the exported C come from different model code?)"
                            ));
                        }
                    }
                }
            }
        }
        Ok(Self { entry })
    }

    /// Evaluates the function.
    ///
    /// # Safety
    /// `args[i]` and `res[i]` point to buffers of at least the sizes [`CFunction::checked`]
    /// verified for input and output `i`.
    #[inline(always)]
    unsafe fn call<const I: usize, const O: usize>(
        &self,
        args: [*const f64; I],
        mut res: [*mut f64; O],
    ) {
        // The return value is always 0 for CasADi's straight-line C (no memory to check out).
        (self.entry.eval)(
            args.as_ptr(),
            res.as_mut_ptr(),
            std::ptr::null_mut(),
            std::ptr::null_mut(),
            0,
        );
    }
}

/// CasADi's C for vehicle8, with runtime parameters (`Some`) or the defaults folded (`None`).
pub struct Casadi {
    params: Option<[f64; NP]>,
    f: CFunction,
    f_jac_x: CFunction,
    f_jw8: CFunction,
}

impl Casadi {
    /// The runtime-parameter functions (`vehicle8_f`, ...) with these parameter values.
    pub fn runtime(params: [f64; NP]) -> Result<Self, String> {
        Self::new(Some(params), [C_F, C_F_JAC_X, C_F_JW8])
    }

    /// The `*_baked` functions: CasADi folded the IR's default parameters into them.
    pub fn baked() -> Result<Self, String> {
        Self::new(None, [C_F_BAKED, C_F_JAC_X_BAKED, C_F_JW8_BAKED])
    }

    /// The hand formulation's C (`vehicle8_hand_f`, ...) with these parameter values.
    pub fn hand_runtime(params: [f64; NP]) -> Result<Self, String> {
        Self::new(Some(params), [H_F, H_F_JAC_X, H_F_JW8])
    }

    /// The hand formulation's C with the defaults folded in.
    pub fn hand_baked() -> Result<Self, String> {
        Self::new(None, [H_F_BAKED, H_F_JAC_X_BAKED, H_F_JW8_BAKED])
    }

    fn new(params: Option<[f64; NP]>, [f, fj, fjw]: [Entry; 3]) -> Result<Self, String> {
        let mut inputs = vec![(NX, 1), (NU, 1)];
        if params.is_some() {
            inputs.push((NP, 1));
        }
        let mut jw_inputs = inputs.clone();
        jw_inputs.push((NX, K));
        let jac = Err((&Vehicle8::JAC_X_COLIND[..], &Vehicle8::JAC_X_ROW[..]));
        Ok(Self {
            params,
            f: CFunction::checked(f, &inputs, &[Ok((NX, 1))])?,
            f_jac_x: CFunction::checked(fj, &inputs, &[Ok((NX, 1)), jac])?,
            f_jw8: CFunction::checked(fjw, &jw_inputs, &[Ok((NX, 1)), Ok((NX, K))])?,
        })
    }

    fn p(&self) -> *const f64 {
        self.params
            .as_ref()
            .map_or(std::ptr::null(), |p| p.as_ptr())
    }

    /// ẋ = f(x, u).
    #[inline(always)]
    pub fn f(&self, x: &[f64; NX], u: &[f64; NU], out: &mut [f64; NX]) {
        // SAFETY: sizes checked in `new`; a baked function has 2 inputs and ignores the third.
        unsafe {
            if self.params.is_some() {
                self.f
                    .call([x.as_ptr(), u.as_ptr(), self.p()], [out.as_mut_ptr()]);
            } else {
                self.f.call([x.as_ptr(), u.as_ptr()], [out.as_mut_ptr()]);
            }
        }
    }

    /// ẋ and the stored entries of ∂f/∂x (CCS order, the IR's pattern).
    #[inline(always)]
    pub fn f_jac_x(&self, x: &[f64; NX], u: &[f64; NU], f: &mut [f64; NX], jac: &mut [f64; NNZ]) {
        let res = [f.as_mut_ptr(), jac.as_mut_ptr()];
        // SAFETY: sizes checked in `new`.
        unsafe {
            if self.params.is_some() {
                self.f_jac_x.call([x.as_ptr(), u.as_ptr(), self.p()], res);
            } else {
                self.f_jac_x.call([x.as_ptr(), u.as_ptr()], res);
            }
        }
    }

    /// ẋ and `out[k] = (∂f/∂x) w[k]`: `[[f64; NX]; K]` is the column-major NX×K matrix W.
    #[inline(always)]
    pub fn f_jw8(
        &self,
        x: &[f64; NX],
        u: &[f64; NU],
        w: &[[f64; NX]; K],
        f: &mut [f64; NX],
        out: &mut [[f64; NX]; K],
    ) {
        let res = [f.as_mut_ptr(), out.as_mut_ptr().cast::<f64>()];
        let w = w.as_ptr().cast::<f64>();
        // SAFETY: sizes checked in `new`; `[[f64; NX]; K]` is NX·K contiguous doubles.
        unsafe {
            if self.params.is_some() {
                self.f_jw8.call([x.as_ptr(), u.as_ptr(), self.p(), w], res);
            } else {
                self.f_jw8.call([x.as_ptr(), u.as_ptr(), w], res);
            }
        }
    }
}

/// A reproducible input: state, input and tangent vectors (a small xorshift generator, so the
/// gate needs no dependency).
#[derive(Debug, Clone, Copy)]
pub struct Point {
    pub x: [f64; NX],
    pub u: [f64; NU],
    pub w: [[f64; NX]; K],
}

impl Point {
    /// The state the benchmark times: moving, turning and leaning, every trigonometric term
    /// non-trivial.
    pub fn bench() -> Self {
        let mut p = Self::random(1);
        p.x = [0.3, 0.5, -0.2, 0.7, -0.4, 1.2, 0.1, 0.35];
        p.u = [12.0, -1.5];
        p
    }

    /// A pseudo-random point: angles and speeds in [-2, 2], inputs in [-20, 20], W in [-1, 1].
    pub fn random(seed: u64) -> Self {
        let mut next = uniform(seed);
        let x = std::array::from_fn(|_| 2.0 * next());
        let u = std::array::from_fn(|_| 20.0 * next());
        let w = std::array::from_fn(|_| std::array::from_fn(|_| next()));
        Self { x, u, w }
    }
}

/// Pseudo-random numbers in [-1, 1) from `seed` (xorshift: the gates need no dependency).
fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut s = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1;
    move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

/// The generated vehicle8 in either parameter mode: the trait methods plus the `f_jac_x` kernel
/// (an inherent method of each generated struct, so it needs this to be called generically).
pub trait Twv: Model<NX, NU> {
    /// ẋ into `f` and the stored entries of ∂f/∂x.
    fn f_jac_x(&self, x: &[f64; NX], u: &[f64; NU], f: &mut [f64; NX]) -> [f64; NNZ];
}

impl Twv for Vehicle8 {
    #[inline(always)]
    fn f_jac_x(&self, x: &[f64; NX], u: &[f64; NU], f: &mut [f64; NX]) -> [f64; NNZ] {
        self.kernel_f_jac_x(x, u, f)
    }
}

impl Twv for baked::Vehicle8 {
    #[inline(always)]
    fn f_jac_x(&self, x: &[f64; NX], u: &[f64; NU], f: &mut [f64; NX]) -> [f64; NNZ] {
        self.kernel_f_jac_x(x, u, f)
    }
}

/// Checks, at the bench point and at `n_random` pseudo-random points, that the generated Rust
/// (runtime and baked) and CasADi's C agree to 1e-13 relative to the size of the terms behind
/// each entry ([`magnitude`]; for J·W, Σ_c |J_rc| |w_kc|). Not bit for bit: the Rust kernels
/// take sin and cos from one inlined reduction (`twv_kernels::trig`, within 1 ulp of the C
/// library) and multiply by shared reciprocals where CasADi divides (`twv_ir` lowering), and
/// CasADi's C sums the products of `mtimes` in its own order. The error lists the first
/// mismatches.
pub fn gate(n_random: u64) -> Result<(), String> {
    if baked::Vehicle8::VALUES != Vehicle8::DEFAULTS {
        return Err(format!(
            "the baked Rust model folds {} but CasADi's *_baked C the IR defaults, and they \
             differ: regenerate the IR (`.venv/bin/python -m twv_modeling`) from that file",
            baked::Vehicle8::PARAMS_SOURCE
        ));
    }
    let runtime = Vehicle8::with_defaults();
    let c_runtime = Casadi::runtime(Vehicle8::DEFAULTS)?;
    let c_baked = Casadi::baked()?;
    let ir = vehicle8_ir()?;
    let mut errors = Vec::new();
    let points = std::iter::once(Point::bench()).chain((0..n_random).map(|s| Point::random(s + 2)));
    for (i, pt) in points.enumerate() {
        let scale = Scales::at(&ir, &pt)?;
        check_point(
            &runtime,
            &c_runtime,
            &pt,
            &scale,
            &format!("point {i}, runtime"),
            &mut errors,
        );
        check_point(
            &baked::Vehicle8,
            &c_baked,
            &pt,
            &scale,
            &format!("point {i}, baked"),
            &mut errors,
        );
    }
    no_mismatches(errors, "twv and CasADi's C")
}

/// The hand formulation's C (runtime and baked) against the generated Rust at the bench point
/// and `n_random` pseudo-random points: another formula for the same physics rounds
/// differently, so each of f, ∂f/∂x and J·W must agree normwise to 1e-11 of its largest entry
/// (a wrong term is off by its own size).
pub fn hand_gate(n_random: u64) -> Result<(), String> {
    let runtime = Vehicle8::with_defaults();
    let peers = [
        ("runtime", Casadi::hand_runtime(Vehicle8::DEFAULTS)?),
        ("baked", Casadi::hand_baked()?),
    ];
    let points = std::iter::once(Point::bench()).chain((0..n_random).map(|s| Point::random(s + 2)));
    for (i, pt) in points.enumerate() {
        let mut f = [0.0; NX];
        let jac = runtime.kernel_f_jac_x(&pt.x, &pt.u, &mut f);
        let (mut f2, mut jw) = ([0.0; NX], [[0.0; NX]; K]);
        runtime.f_jw::<K>(&pt.x, &pt.u, &pt.w, &mut f2, &mut jw);
        for (mode, c) in &peers {
            let (mut cf, mut cj) = ([0.0; NX], [0.0; NNZ]);
            c.f_jac_x(&pt.x, &pt.u, &mut cf, &mut cj);
            let (mut cf2, mut cjw) = ([0.0; NX], [[0.0; NX]; K]);
            c.f_jw8(&pt.x, &pt.u, &pt.w, &mut cf2, &mut cjw);
            for (what, a, b) in [
                ("f", &f[..], &cf[..]),
                ("jac_x", &jac[..], &cj[..]),
                ("J·W", jw.as_flattened(), cjw.as_flattened()),
            ] {
                let size = b.iter().fold(0.0_f64, |m, v| m.max(v.abs())).max(1e-300);
                // A NaN difference counts as a disagreement (`max` would skip it).
                let bad = a
                    .iter()
                    .zip(b)
                    .map(|(x, y)| (x - y).abs())
                    .find(|d| d.is_nan() || *d > 1e-11 * size);
                if let Some(d) = bad {
                    return Err(format!(
                        "point {i}, {mode}: the hand formulation's {what} differs by {d:e} \
                         (largest entry {size:e})"
                    ));
                }
            }
        }
    }
    Ok(())
}

/// The size of the terms behind each entry of f, the stored ∂f/∂x and J·W at one point.
struct Scales {
    f: Vec<f64>,
    jac: Vec<f64>,
    jw: [[f64; NX]; K],
}

impl Scales {
    fn at(ir: &Ir, pt: &Point) -> Result<Self, String> {
        let at = (&pt.x[..], &pt.u[..], &Vehicle8::DEFAULTS[..]);
        let jac = output_magnitudes(ir, "f_jac_x", "jac_x", at)?;
        Ok(Self {
            f: output_magnitudes(ir, "f", "f", at)?,
            jw: jw_scale(&jac, (&Vehicle8::JAC_X_COLIND, &Vehicle8::JAC_X_ROW), &pt.w),
            jac,
        })
    }
}

/// The vehicle8 IR the Rust kernels were generated from.
fn vehicle8_ir() -> Result<Ir, String> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../ir/vehicle8.json");
    twv_ir::load_ir(path).map_err(|e| e.to_string())
}

/// [`magnitude::magnitudes`] of the entries of one output, in storage order.
fn output_magnitudes(
    ir: &Ir,
    function: &str,
    output: &str,
    (x, u, p): (&[f64], &[f64], &[f64]),
) -> Result<Vec<f64>, String> {
    let f = ir
        .function(function)
        .ok_or_else(|| format!("{} IR has no `{function}`", ir.model()))?;
    let out = f
        .output(output)
        .ok_or_else(|| format!("`{function}` has no output `{output}`"))?;
    let m = magnitude::magnitudes(f, x, u, p)?;
    Ok(out.values.iter().map(|&v| m[v]).collect())
}

/// Adds to `errors` each entry where twv's value and the C's differ by more than 1e-13 of the
/// size of the terms behind it (`scale`), named `{at}: {what}[entry]`. Written so that NaN on
/// either side is a mismatch.
fn check_within(
    errors: &mut Vec<String>,
    at: &str,
    what: &str,
    twv: &[f64],
    c: &[f64],
    scale: &[f64],
) {
    for (e, ((&r, &c), &m)) in twv.iter().zip(c).zip(scale).enumerate() {
        let agree = (r - c).abs() <= 1e-13 * m;
        if !agree {
            errors.push(format!(
                "{at}: {what}[{e}]: twv {r:e}, CasADi C {c:e}, scale {m:e}"
            ));
        }
    }
}

/// `Ok` without `errors`, else the count of mismatches `between` two sides and the first 12.
fn no_mismatches(mut errors: Vec<String>, between: &str) -> Result<(), String> {
    if errors.is_empty() {
        return Ok(());
    }
    let n = errors.len();
    errors.truncate(12);
    Err(format!(
        "{n} mismatches between {between} (first {}):\n  {}",
        errors.len(),
        errors.join("\n  ")
    ))
}

fn check_point(
    twv: &impl Twv,
    c: &Casadi,
    pt: &Point,
    scale: &Scales,
    at: &str,
    errors: &mut Vec<String>,
) {
    let mut check = |what: &str, rust: &[f64], c: &[f64], scale: &[f64]| {
        check_within(errors, at, what, rust, c, scale)
    };
    let (x, u, w) = (&pt.x, &pt.u, &pt.w);
    let (mut fr, mut fc) = ([0.0; NX], [0.0; NX]);
    twv.f(x, u, &mut fr);
    c.f(x, u, &mut fc);
    check("f", &fr, &fc, &scale.f);

    let mut jc = [0.0; NNZ];
    let j = twv.f_jac_x(x, u, &mut fr);
    c.f_jac_x(x, u, &mut fc, &mut jc);
    check("f_jac_x f", &fr, &fc, &scale.f);
    check("f_jac_x jac", &j, &jc, &scale.jac);
    let mut jr = [0.0; NNZ];
    twv.jac_x_sparse(x, u, &mut jr);
    check("jac_x_sparse", &jr, &jc, &scale.jac);

    let (mut jwr, mut jwc) = ([[0.0; NX]; K], [[0.0; NX]; K]);
    twv.f_jw(x, u, w, &mut fr, &mut jwr);
    c.f_jw8(x, u, w, &mut fc, &mut jwc);
    check("f_jw8 f", &fr, &fc, &scale.f);
    check(
        "f_jw8 jw",
        jwr.as_flattened(),
        jwc.as_flattened(),
        scale.jw.as_flattened(),
    );
}

/// `Σ_c m(J_rc) |w_kc|` for each entry of J·W, with m the size of the terms behind each stored
/// entry of ∂f/∂x, floored at the smallest normal number so an all-zero row compares exactly.
fn jw_scale<const N: usize, const W: usize>(
    jac: &[f64],
    (colind, rows): (&[usize], &[usize]),
    w: &[[f64; N]; W],
) -> [[f64; N]; W] {
    let mut scale = [[f64::MIN_POSITIVE; N]; W];
    let cols = (colind.windows(2).enumerate())
        .flat_map(|(col, pair)| (pair[0]..pair[1]).map(move |_| col));
    for ((&m, &row), col) in jac.iter().zip(rows).zip(cols) {
        for (s, wk) in scale.iter_mut().zip(w) {
            s[row] += m * wk[col].abs();
        }
    }
    scale
}

/// Median and interquartile range of a set of timings, ns per call.
#[derive(Debug, Clone, Copy)]
pub struct Stats {
    pub median: f64,
    pub q1: f64,
    pub q3: f64,
}

impl Stats {
    fn of(mut v: Vec<f64>) -> Self {
        v.sort_by(f64::total_cmp);
        let at = |q: f64| {
            let pos = q * (v.len() - 1) as f64;
            let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
            v[lo] + (v[hi] - v[lo]) * (pos - lo as f64)
        };
        Self {
            median: at(0.5),
            q1: at(0.25),
            q3: at(0.75),
        }
    }

    /// Half the interquartile range, relative to the median, in percent.
    pub fn spread_percent(&self) -> f64 {
        50.0 * (self.q3 - self.q1) / self.median
    }
}

impl fmt::Display for Stats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:.1} ±{:.1}%", self.median, self.spread_percent())
    }
}

/// The result of timing two implementations of one function side by side.
#[derive(Debug, Clone, Copy)]
pub struct Pair {
    pub twv: Stats,
    pub c: Stats,
    /// Median over the samples of the per-sample ratio twv/C.
    pub ratio: Stats,
}

/// How a [`compare`] samples.
#[derive(Debug, Clone, Copy)]
pub struct Plan {
    pub warm_up: Duration,
    pub samples: usize,
    pub sample_time: Duration,
}

/// 101 samples of >= 1 ms: on a small machine shared with other jobs (2 cores here), the speed
/// of a core changes on a millisecond scale; short alternating samples pair twv and C mostly
/// within one such phase, and the median discards the pairs that straddle two (31 samples of
/// 5 ms gave ratios that jumped between runs by up to 2x).
impl Default for Plan {
    fn default() -> Self {
        Self {
            warm_up: Duration::from_millis(100),
            samples: 101,
            sample_time: Duration::from_millis(1),
        }
    }
}

impl Plan {
    /// The default plan, with `TWV_BENCH_SAMPLES` (count) and `TWV_BENCH_SAMPLE_MS` (minimum
    /// duration of one sample) overriding it when set.
    pub fn from_env() -> Result<Self, String> {
        let mut plan = Self::default();
        let read = |name: &str| -> Result<Option<u64>, String> {
            match std::env::var(name) {
                Err(_) => Ok(None),
                Ok(v) => match v.trim().parse::<u64>() {
                    Ok(n) if n > 0 => Ok(Some(n)),
                    _ => Err(format!("{name}={v:?}: expected a positive integer")),
                },
            }
        };
        if let Some(n) = read("TWV_BENCH_SAMPLES")? {
            plan.samples = n as usize;
        }
        if let Some(ms) = read("TWV_BENCH_SAMPLE_MS")? {
            plan.sample_time = Duration::from_millis(ms);
        }
        Ok(plan)
    }
}

/// Times `twv` and `c` (one call each) in alternating samples, so that a slow phase of the
/// machine (frequency, another process) hits both and largely cancels in the per-sample ratio.
pub fn compare(plan: Plan, mut twv: impl FnMut(), mut c: impl FnMut()) -> Pair {
    let warm = Instant::now();
    while warm.elapsed() < plan.warm_up {
        run(&mut twv, 1000);
        run(&mut c, 1000);
    }
    let (nt, nc) = (
        calibrate(&mut twv, plan.sample_time),
        calibrate(&mut c, plan.sample_time),
    );
    let (mut ts, mut cs, mut rs) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..plan.samples {
        let t = run(&mut twv, nt).as_nanos() as f64 / nt as f64;
        let c = run(&mut c, nc).as_nanos() as f64 / nc as f64;
        ts.push(t);
        cs.push(c);
        rs.push(t / c);
    }
    Pair {
        twv: Stats::of(ts),
        c: Stats::of(cs),
        ratio: Stats::of(rs),
    }
}

/// Times `f` (one call) alone, sampled as in [`compare`]: for reference costs such as one libm
/// call.
pub fn time(plan: Plan, mut f: impl FnMut()) -> Stats {
    let warm = Instant::now();
    while warm.elapsed() < plan.warm_up {
        run(&mut f, 1000);
    }
    let n = calibrate(&mut f, plan.sample_time);
    Stats::of(
        (0..plan.samples)
            .map(|_| run(&mut f, n).as_nanos() as f64 / n as f64)
            .collect(),
    )
}

/// How a measured ratio (lower is better) stands against a goal: "within" at or below it,
/// "above" otherwise (a NaN ratio included).
pub fn against_goal(ratio: f64, goal: f64) -> &'static str {
    if ratio <= goal {
        "within"
    } else {
        "above"
    }
}

/// Iterations per sample so that one sample takes at least `target`.
fn calibrate(f: &mut impl FnMut(), target: Duration) -> u64 {
    let mut n = 16;
    loop {
        let t = run(f, n);
        if t >= target {
            return n;
        }
        let grow = if t.is_zero() {
            16.0
        } else {
            (target.as_secs_f64() / t.as_secs_f64() * 1.2).min(16.0)
        };
        n = ((n as f64 * grow).ceil() as u64).max(n + 1);
    }
}

/// `n` calls of `f`, timed. Not inlined into the caller so every closure gets its own loop.
#[inline(never)]
fn run(f: &mut impl FnMut(), n: u64) -> Duration {
    let start = Instant::now();
    for _ in 0..n {
        f();
    }
    black_box(start.elapsed())
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_ratio_is_within_its_goal_up_to_it_and_above_beyond() {
        use super::against_goal;
        assert_eq!(against_goal(1.04, 1.2), "within");
        assert_eq!(against_goal(1.2, 1.2), "within");
        assert_eq!(against_goal(1.21, 1.2), "above");
        assert_eq!(against_goal(f64::NAN, 1.2), "above");
    }

    use super::*;

    /// The gate is not vacuous: C evaluated with the base mass off by one part in 10^9 (far
    /// above rounding, far below anything a person would notice in a plot) is caught.
    #[test]
    fn gate_catches_a_one_in_a_billion_parameter_change() {
        let mut params = Vehicle8::DEFAULTS;
        params[0] *= 1.0 + 1e-9;
        let c = Casadi::runtime(params).unwrap();
        let pt = Point::bench();
        let runtime = Vehicle8::with_defaults();
        let ir = vehicle8_ir().unwrap();
        let scale = Scales::at(&ir, &pt).unwrap();
        let mut errors = Vec::new();
        check_point(&runtime, &c, &pt, &scale, "here", &mut errors);
        assert!(errors.iter().any(|e| e.contains(": f[")), "{errors:?}");
    }

    /// The gate as a test (no timing): the generated Rust agrees with CasADi's own C.
    #[test]
    fn twv_agrees_with_casadi_c() {
        if let Err(e) = super::gate(200) {
            panic!("{e}");
        }
    }
}
