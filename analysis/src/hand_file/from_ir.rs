//! The derived side of the symbolic difference: the canonical form of each stored entry of an IR
//! function, computed once per value of its instruction list (the IR is a DAG of shared
//! subexpressions; expanding it as a tree could grow exponentially).

use twv_ir::ops::{BinaryOp, UnaryOp};
use twv_ir::{Arg, Function, Instr};

use super::expr::{Func, Var};
use super::normal::{call, Names, Poly, TooLarge};

fn unary(op: UnaryOp, a: &Poly, names: &Names<'_>) -> Result<Poly, TooLarge> {
    let func = |f: Func| call(&f, a, names);
    match op {
        UnaryOp::Neg => Ok(Poly::default().plus(a, -1.0)),
        UnaryOp::Sq => a.times(a),
        UnaryOp::Twice => Ok(Poly::default().plus(a, 2.0)),
        UnaryOp::Inv => a.inverse(names),
        UnaryOp::Sin => func(Func::Sin),
        UnaryOp::Cos => func(Func::Cos),
        UnaryOp::Tan => func(Func::Tan),
        UnaryOp::Sqrt => func(Func::Sqrt),
        UnaryOp::Exp => func(Func::Exp),
        UnaryOp::Log => func(Func::Log),
        other => func(Func::Other(other.name().to_string())),
    }
}

fn binary(op: BinaryOp, a: &Poly, b: &Poly, names: &Names<'_>) -> Result<Poly, TooLarge> {
    match op {
        BinaryOp::Add => Ok(a.clone().plus(b, 1.0)),
        BinaryOp::Sub => Ok(a.clone().plus(b, -1.0)),
        BinaryOp::Mul => a.times(b),
        BinaryOp::Div => a.times(&b.inverse(names)?),
        BinaryOp::Pow | BinaryOp::Constpow => match b.small_integer() {
            Some(n) => a.power(n, names),
            None => Poly::opaque(format!("({})^({})", a.print(names), b.print(names))),
        },
        other => Poly::opaque(format!(
            "{}({}, {})",
            other.name(),
            a.print(names),
            b.print(names)
        )),
    }
}

/// The canonical form of every stored entry of `output` of `function` (its CCS order);
/// `Err(TooLarge)` for an entry whose expansion grew past the limit.
pub fn entry_forms(
    function: &Function,
    output: &str,
    names: &Names<'_>,
) -> Vec<Result<Poly, TooLarge>> {
    let mut values: Vec<Result<Poly, TooLarge>> = Vec::with_capacity(function.n_values());
    for instr in function.instructions() {
        let value = match *instr {
            Instr::Input { arg, index } => Ok(Poly::var(match arg {
                Arg::X => Var::X(index),
                Arg::U => Var::U(index),
                Arg::P => Var::P(index),
            })),
            Instr::Const(c) => Ok(Poly::constant(c)),
            Instr::Unary(op, a) => match &values[a] {
                Ok(pa) => unary(op, pa, names),
                Err(e) => Err(*e),
            },
            Instr::Binary(op, a, b) => match (&values[a], &values[b]) {
                (Ok(pa), Ok(pb)) => binary(op, pa, pb, names),
                _ => Err(TooLarge),
            },
        };
        values.push(value);
    }
    function
        .output(output)
        .map(|o| o.values.iter().map(|&v| values[v].clone()).collect())
        .unwrap_or_default()
}
