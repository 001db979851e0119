//! Straight-line function bodies: one `let` per IR instruction, and the expressions that read
//! its outputs.

use proc_macro2::{Ident, Literal, TokenStream};
use quote::{format_ident, quote};
use twv_ir::{Arg, BinaryOp, Function, Instr, Output, UnaryOp};

use crate::Params;

/// The local holding value `k`.
pub fn value(k: usize) -> Ident {
    format_ident!("v{}", k)
}

/// An exact `f64` literal (shortest round-trip digits); non-finite values as named constants.
pub fn float(v: f64) -> TokenStream {
    if v.is_nan() {
        return quote!(f64::NAN);
    }
    let magnitude = if v.is_infinite() {
        quote!(f64::INFINITY)
    } else {
        let lit = Literal::f64_suffixed(v.abs());
        quote!(#lit)
    };
    if v.is_sign_negative() {
        quote!(-#magnitude)
    } else {
        magnitude
    }
}

/// A `usize` literal.
pub fn index(i: usize) -> Literal {
    Literal::usize_unsuffixed(i)
}

/// The `let` statements of `f`. Parameters come from `self.params` or are folded as constants.
pub fn lets(f: &Function, params: &Params) -> TokenStream {
    let (pairs, paired) = angle_pairs(f, params);
    let lets = f.instructions().iter().enumerate().map(|(k, instr)| {
        let v = value(k);
        if let Instr::Unary(op @ (UnaryOp::Sin | UnaryOp::Cos), x) = *instr {
            if let Some(sc) = paired.get(&x) {
                let part = if op == UnaryOp::Sin {
                    quote!(0)
                } else {
                    quote!(1)
                };
                return quote!(let #v: f64 = #sc.#part;);
            }
        }
        let rhs = match *instr {
            Instr::Input { arg, index: i } => input(arg, i, params),
            Instr::Const(c) => float(c),
            Instr::Unary(op, a) => unary(op, &value(a)),
            Instr::Binary(op, a, b) => binary(op, &value(a), &value(b)),
        };
        quote!(let #v: f64 = #rhs;)
    });
    quote!(#(#pairs)* #(#lets)*)
}

/// The calls of `twv_kernels::trig::sin_cos_pair` for `f`'s paired angles
/// (`Function::paired_angles`), to go first, and for each paired angle's value id the name of
/// its (sin, cos).
fn angle_pairs(
    f: &Function,
    params: &Params,
) -> (Vec<TokenStream>, std::collections::BTreeMap<usize, Ident>) {
    let mut paired = std::collections::BTreeMap::new();
    let calls = f
        .paired_angles()
        .into_iter()
        .map(|pair| {
            let [(sa, ea), (sb, eb)] =
                pair.map(|(x, arg, i)| (format_ident!("sc{}", x), input(arg, i, params)));
            paired.insert(pair[0].0, sa.clone());
            paired.insert(pair[1].0, sb.clone());
            quote!(let (#sa, #sb) = ::twv_kernels::trig::sin_cos_pair(#ea, #eb);)
        })
        .collect();
    (calls, paired)
}

/// The states whose sine or cosine is taken directly (`sin(x[i])`, `cos(x[i])`) by any of
/// `functions`: the kernel computes each of their (sin, cos) once, ahead of the bodies
/// ([`lane_state_sin_cos`]), rather than once per function (the maps' kernel took vehicle8's
/// pitch's three times a stage: in `f_jac_x`, in `jac_u`, and the law's setpoint).
pub fn sin_cos_states(functions: &[&Function]) -> std::collections::BTreeSet<usize> {
    let mut states = std::collections::BTreeSet::new();
    for f in functions {
        let instructions = f.instructions();
        for instr in instructions {
            if let Instr::Unary(UnaryOp::Sin | UnaryOp::Cos, x) = *instr {
                if let Instr::Input { arg: Arg::X, index } = instructions[x] {
                    states.insert(index);
                }
            }
        }
    }
    states
}

/// The name of state `i`'s lane (sin, cos) that [`lane_state_sin_cos`] binds.
fn state_sin_cos(i: usize) -> Ident {
    format_ident!("sc_x{}", i)
}

/// For each of `states`, `let sc_xI = ...;`: the caller's (sin, cos) when it passed state
/// I's (`given: Option<(usize, &(Lanes, Lanes))>`), else `wide::sin_cos(xs[I])`.
pub fn lane_state_sin_cos(states: &std::collections::BTreeSet<usize>) -> TokenStream {
    let lets = states.iter().map(|&i| {
        let (sc, idx) = (state_sin_cos(i), index(i));
        quote! {
            let #sc = match given {
                ::core::option::Option::Some((#idx, given)) => *given,
                _ => wide::sin_cos(xs[#idx]),
            };
        }
    });
    quote!(let _ = given; #(#lets)*)
}

/// The `let`s of `f` over lane arrays (`twv_kernels::lanes`), calling the lane operations as
/// `wide::…`: the kernel brings the module of its instruction set into scope under that name
/// (`lanes::wide` for AVX-512, `lanes::wide_avx2`, `lanes::wide_neon`), so one body serves
/// every build. Each instruction's scalar expression written out for every lane, states and
/// inputs read from the gathered lane arrays `xs`, `us`; the (sin, cos) of the states in
/// `state_sin_cos_done` from [`lane_state_sin_cos`] ahead of the body. Per lane these are the
/// operations of [`lets`], in the same order (a sine is a function of its argument alone).
pub fn lane_lets(
    f: &Function,
    params: &Params,
    state_sin_cos_done: &std::collections::BTreeSet<usize>,
) -> TokenStream {
    let (a, b) = (format_ident!("a"), format_ident!("b"));
    // sin and cos of one angle come from one `lanes::wide::sin_cos` call (`scK` for value K),
    // a state's from the call ahead of the body (`sc_xI`) when there is one.
    let mut sin_cos_done = std::collections::BTreeSet::new();
    let instructions = f.instructions();
    let lets = instructions.iter().enumerate().map(|(k, instr)| {
        let v = value(k);
        if let Instr::Unary(op @ (UnaryOp::Sin | UnaryOp::Cos), x) = *instr {
            let ahead = match instructions[x] {
                Instr::Input { arg: Arg::X, index } if state_sin_cos_done.contains(&index) => {
                    Some(state_sin_cos(index))
                }
                _ => None,
            };
            let sc = ahead.clone().unwrap_or_else(|| format_ident!("sc{}", x));
            let pair = if ahead.is_none() && sin_cos_done.insert(x) {
                let x = value(x);
                quote!(let #sc = wide::sin_cos(#x);)
            } else {
                TokenStream::new()
            };
            let part = if op == UnaryOp::Sin {
                quote!(0)
            } else {
                quote!(1)
            };
            return quote!(#pair let #v: ::twv_kernels::lanes::Lanes = #sc.#part;);
        }
        let rhs = match *instr {
            Instr::Input { arg, index: i } => {
                let idx = index(i);
                match arg {
                    Arg::X => quote!(xs[#idx]),
                    Arg::U => quote!(us[#idx]),
                    Arg::P => {
                        let p = input(arg, i, params);
                        quote!(::twv_kernels::lanes::splat(#p))
                    }
                }
            }
            Instr::Const(c) => {
                let c = float(c);
                quote!(::twv_kernels::lanes::splat(#c))
            }
            Instr::Unary(op, x) => {
                let (e, x) = (unary(op, &a), value(x));
                quote!(::twv_kernels::lanewise!(|#a| #e; #x))
            }
            Instr::Binary(op, x, y) => {
                let (e, x, y) = (binary(op, &a, &b), value(x), value(y));
                match op {
                    BinaryOp::Add => quote!(wide::add(#x, #y)),
                    BinaryOp::Sub => quote!(wide::sub(#x, #y)),
                    BinaryOp::Mul => quote!(wide::mul(#x, #y)),
                    BinaryOp::Div => quote!(wide::div(#x, #y)),
                    _ => quote!(::twv_kernels::lanewise!(|#a, #b| #e; #x, #y)),
                }
            }
        };
        quote!(let #v: ::twv_kernels::lanes::Lanes = #rhs;)
    });
    quote!(#(#lets)*)
}

fn input(arg: Arg, i: usize, params: &Params) -> TokenStream {
    let idx = index(i);
    match (arg, params) {
        (Arg::X, _) => quote!(x[#idx]),
        (Arg::U, _) => quote!(u[#idx]),
        (Arg::P, Params::Runtime) => quote!(self.params[#idx]),
        (Arg::P, Params::Baked { values, .. }) => float(values.get(i).copied().unwrap_or(f64::NAN)),
    }
}

/// One arm per unary operation, no catch-all: a new operation fails to build until handled.
/// Each expression is the one in `twv_ir::ops` (CasADi's C semantics).
fn unary(op: UnaryOp, a: &Ident) -> TokenStream {
    match op {
        UnaryOp::Neg => quote!(-#a),
        UnaryOp::Exp => quote!(#a.exp()),
        UnaryOp::Log => quote!(#a.ln()),
        UnaryOp::Sqrt => quote!(#a.sqrt()),
        UnaryOp::Sq => quote!(#a * #a),
        UnaryOp::Twice => quote!(2.0 * #a),
        UnaryOp::Sin => quote!(::twv_kernels::trig::sin_cos(#a).0),
        UnaryOp::Cos => quote!(::twv_kernels::trig::sin_cos(#a).1),
        UnaryOp::Tan => quote!(#a.tan()),
        UnaryOp::Asin => quote!(#a.asin()),
        UnaryOp::Acos => quote!(#a.acos()),
        UnaryOp::Atan => quote!(#a.atan()),
        UnaryOp::Fabs => quote!(#a.abs()),
        UnaryOp::Sign => {
            quote!(if #a < 0.0 { -1.0 } else if #a > 0.0 { 1.0 } else { #a })
        }
        UnaryOp::Inv => quote!(1.0 / #a),
        UnaryOp::Sinh => quote!(#a.sinh()),
        UnaryOp::Cosh => quote!(#a.cosh()),
        UnaryOp::Tanh => quote!(#a.tanh()),
        UnaryOp::Asinh => libm(quote!(asinh), a),
        UnaryOp::Acosh => libm(quote!(acosh), a),
        UnaryOp::Atanh => libm(quote!(atanh), a),
        UnaryOp::Floor => quote!(#a.floor()),
        UnaryOp::Ceil => quote!(#a.ceil()),
        UnaryOp::Erf => libm(quote!(erf), a),
        UnaryOp::Not => quote!(if #a == 0.0 { 1.0 } else { 0.0 }),
        UnaryOp::Log1p => quote!(#a.ln_1p()),
        UnaryOp::Expm1 => quote!(#a.exp_m1()),
    }
}

/// A C library function `std` does not call (see `twv_ir::ops`).
fn libm(function: TokenStream, a: &Ident) -> TokenStream {
    quote!({
        unsafe extern "C" {
            fn #function(x: f64) -> f64;
        }
        // SAFETY: a pure C library function of one double, defined for every input.
        unsafe { #function(#a) }
    })
}

/// One arm per binary operation, no catch-all.
fn binary(op: BinaryOp, a: &Ident, b: &Ident) -> TokenStream {
    let truth = |cond: TokenStream| quote!(if #cond { 1.0 } else { 0.0 });
    match op {
        BinaryOp::Add => quote!(#a + #b),
        BinaryOp::Sub => quote!(#a - #b),
        BinaryOp::Mul => quote!(#a * #b),
        BinaryOp::Div => quote!(#a / #b),
        BinaryOp::Pow => quote!(#a.powf(#b)),
        BinaryOp::Constpow => quote!(#a.powf(#b)),
        BinaryOp::Fmin => quote!(#a.min(#b)),
        BinaryOp::Fmax => quote!(#a.max(#b)),
        BinaryOp::Atan2 => quote!(#a.atan2(#b)),
        BinaryOp::Copysign => quote!(#a.copysign(#b)),
        BinaryOp::Fmod => quote!(#a % #b),
        BinaryOp::Lt => truth(quote!(#a < #b)),
        BinaryOp::Le => truth(quote!(#a <= #b)),
        BinaryOp::Eq => truth(quote!(#a == #b)),
        BinaryOp::Ne => truth(quote!(#a != #b)),
        BinaryOp::And => truth(quote!(#a != 0.0 && #b != 0.0)),
        BinaryOp::Or => truth(quote!(#a != 0.0 || #b != 0.0)),
        BinaryOp::IfElseZero => quote!(if #a != 0.0 { #b } else { 0.0 }),
        BinaryOp::Hypot => quote!(#a.hypot(#b)),
    }
}

/// The dense matrix of an output as rows of expressions (`vK`, or at a structural zero the
/// opaque `twv_kernels::zero::zero()`).
pub fn dense(o: &Output) -> Vec<Vec<TokenStream>> {
    dense_with(o, quote!(::twv_kernels::zero::zero()))
}

/// The dense matrix of an output with `zero` at the structural zeros.
fn dense_with(o: &Output, zero: TokenStream) -> Vec<Vec<TokenStream>> {
    let mut grid = vec![vec![zero; o.cols]; o.rows];
    for (r, c, v) in o.entries() {
        let v = value(v);
        grid[r][c] = quote!(#v);
    }
    grid
}

/// A lane array of zeros.
fn lane_zero() -> TokenStream {
    quote!(::twv_kernels::lanes::splat(0.0))
}

/// `[e0, e1, ...]` of the rows of a one-column grid.
fn vector_of(grid: Vec<Vec<TokenStream>>) -> TokenStream {
    let items = grid.into_iter().map(|row| quote!(#(#row),*));
    quote!([#(#items),*])
}

/// `[[...], ...]` (row-major) of a grid.
fn matrix_of(grid: Vec<Vec<TokenStream>>) -> TokenStream {
    let rows = grid.into_iter().map(|row| quote!([#(#row),*]));
    quote!([#(#rows),*])
}

/// `[e0, e1, ...]` of a column-vector output.
pub fn vector_expr(o: &Output) -> TokenStream {
    vector_of(dense(o))
}

/// `[[...], ...]` (row-major) of a matrix output.
pub fn matrix_expr(o: &Output) -> TokenStream {
    matrix_of(dense(o))
}

/// [`vector_expr`] over lane arrays.
pub fn lane_vector_expr(o: &Output) -> TokenStream {
    vector_of(dense_with(o, lane_zero()))
}

/// [`matrix_expr`] over lane arrays.
pub fn lane_matrix_expr(o: &Output) -> TokenStream {
    matrix_of(dense_with(o, lane_zero()))
}

/// The row form of J·w (`twv_kernels::tangents`) for one tangent vector per lane: `out[r]` (lane
/// arrays) from the stored entries' values `jac.values` (lane arrays `vK`) and the gathered
/// tangent `wl`, the one-point kernel's operations in every lane.
pub fn lane_jw_rows(jac: &Output) -> TokenStream {
    let rows = jac.stored_rows().into_iter().map(|row| {
        row.into_iter()
            .map(|(c, e)| {
                let (v, c) = (value(jac.values[e]), index(c));
                quote!(wide::mul(#v, wl[#c]))
            })
            .reduce(|acc, t| quote!(wide::add(#acc, #t)))
            .unwrap_or_else(lane_zero)
    });
    quote!([#(#rows),*])
}

/// `out[k] = J · w[k]` in the row form of `twv_kernels::tangents` from the stored entries `j`,
/// for a body generic over its build `B: twv_kernels::tangents::Build`: groups of `LANES`
/// tangent vectors in lane arrays where the build is wide, the rest one by one.
pub fn jw_rows(jac: &Output) -> TokenStream {
    let stored = jac.stored_rows();
    let one = stored.iter().map(|row| {
        row.iter()
            .map(|&(c, e)| {
                let (c, e) = (index(c), index(e));
                quote!(j[#e] * wk[#c])
            })
            .reduce(|acc, t| quote!(#acc + #t))
            .unwrap_or_else(|| quote!(0.0))
    });
    let lanes = stored
        .iter()
        .map(|row| {
            row.iter()
                .map(|&(c, e)| {
                    let (c, e) = (index(c), index(e));
                    quote!(B::mul([j[#e]; ::twv_kernels::lanes::LANES], wl[#c]))
                })
                .reduce(|acc, t| quote!(B::add(#acc, #t)))
                .unwrap_or_else(lane_zero)
        })
        .collect::<Vec<_>>();
    quote! {
        let count = w.len().min(out.len());
        let grouped = ::twv_kernels::tangents::in_groups::<B>(count);
        let (w_groups, _) = w[..grouped].as_chunks::<{ ::twv_kernels::lanes::LANES }>();
        let (out_groups, _) = out[..grouped].as_chunks_mut::<{ ::twv_kernels::lanes::LANES }>();
        // The first group outside the loop: written out once more, it is straight-line code
        // after ∂f/∂x, where the entries' splats are not hoisted out of a loop and spilled
        // (f_jw with K = 8, the Lyapunov spectra's case: 0.60–0.61× the hand formulation's C
        // against 0.61–0.65 with the loop alone, four alternating runs).
        let mut groups = w_groups.iter().zip(out_groups);
        if let Some((wg, og)) = groups.next() {
            // SAFETY: `B` is the build this body is compiled into, which runs only where the
            // CPU has its instructions (`multiversion`).
            unsafe {
                let wl = B::gather(wg);
                B::scatter(&[#(#lanes),*], og);
            }
        }
        for (wg, og) in groups {
            // SAFETY: as above.
            unsafe {
                let wl = B::gather(wg);
                B::scatter(&[#(#lanes),*], og);
            }
        }
        for (wk, ok) in w[grouped..count].iter().zip(&mut out[grouped..count]) {
            // An opaque address: otherwise the optimiser vectorises across the tangent vectors
            // with gathers, slower than these scalar operations.
            let wk = ::core::hint::black_box(wk);
            *ok = [#(#one),*];
        }
    }
}
