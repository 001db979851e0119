//! A function of the IR as readable infix formulas: what a person checks against a textbook
//! derivation (the report prints M, Cp, F, Q this way).
//!
//! Values used more than once become named temporaries `t1, t2, …` (the IR's common
//! subexpressions); values used once are written inline. Inputs print as the state, input and
//! parameter names.

use crate::ops::{BinaryOp, UnaryOp};
use crate::types::{Arg, Function, Instr, Ir};

/// A function's formulas: temporaries in order, then one formula per stored output entry.
#[derive(Debug, Clone, PartialEq)]
pub struct Formulas {
    /// (name, formula) of each shared subexpression, in evaluation order.
    pub temporaries: Vec<(String, String)>,
    /// (label, formula) of each stored output entry, e.g. `M[w_y,v_x]`.
    pub entries: Vec<(String, String)>,
}

/// How tightly an expression binds, for parenthesising.
#[derive(Clone, Copy, PartialEq, PartialOrd)]
enum Prec {
    Sum = 1,
    Product = 2,
    Unary = 3,
    Atom = 4,
}

fn wrap(text: &(String, Prec), need: Prec) -> String {
    if text.1 < need {
        format!("({})", text.0)
    } else {
        text.0.clone()
    }
}

fn number(v: f64) -> (String, Prec) {
    let s = format!("{v}");
    let prec = if v < 0.0 { Prec::Unary } else { Prec::Atom };
    (s, prec)
}

fn unary(op: UnaryOp, a: &(String, Prec)) -> (String, Prec) {
    match op {
        UnaryOp::Neg => (format!("-{}", wrap(a, Prec::Unary)), Prec::Unary),
        UnaryOp::Sq => (format!("{}^2", wrap(a, Prec::Atom)), Prec::Unary),
        UnaryOp::Twice => (format!("2*{}", wrap(a, Prec::Product)), Prec::Product),
        UnaryOp::Inv => (format!("1/{}", wrap(a, Prec::Unary)), Prec::Product),
        other => (format!("{}({})", other.name(), a.0), Prec::Atom),
    }
}

fn binary(op: BinaryOp, a: &(String, Prec), b: &(String, Prec)) -> (String, Prec) {
    match op {
        BinaryOp::Add => (
            format!("{} + {}", wrap(a, Prec::Sum), wrap(b, Prec::Sum)),
            Prec::Sum,
        ),
        BinaryOp::Sub => (
            format!("{} - {}", wrap(a, Prec::Sum), wrap(b, Prec::Product)),
            Prec::Sum,
        ),
        BinaryOp::Mul => (
            format!("{}*{}", wrap(a, Prec::Product), wrap(b, Prec::Product)),
            Prec::Product,
        ),
        BinaryOp::Div => (
            format!("{}/{}", wrap(a, Prec::Product), wrap(b, Prec::Unary)),
            Prec::Product,
        ),
        BinaryOp::Pow | BinaryOp::Constpow => (
            format!("{}^{}", wrap(a, Prec::Atom), wrap(b, Prec::Atom)),
            Prec::Unary,
        ),
        other => (format!("{}({}, {})", other.name(), a.0, b.0), Prec::Atom),
    }
}

/// Names of the three arguments' components.
fn input_name(ir: &Ir, arg: Arg, index: usize) -> String {
    let name = match arg {
        Arg::X => ir.states().get(index).map(|s| s.name.clone()),
        Arg::U => ir.inputs().get(index).map(|s| s.name.clone()),
        Arg::P => ir.params().get(index).map(|p| p.name.clone()),
    };
    name.unwrap_or_else(|| format!("arg{}[{index}]", arg.number()))
}

/// The formulas of `function` (a function of `ir`); `row_names`/`col_names` label the entries.
pub fn formulas(
    ir: &Ir,
    function: &Function,
    row_names: &[String],
    col_names: &[String],
) -> Formulas {
    let ins = function.instructions();
    let mut uses = vec![0usize; ins.len()];
    for i in ins {
        match *i {
            Instr::Unary(_, a) => uses[a] += 1,
            Instr::Binary(_, a, b) => {
                uses[a] += 1;
                uses[b] += 1;
            }
            _ => {}
        }
    }
    for o in function.outputs() {
        for &v in &o.values {
            uses[v] += 1;
        }
    }
    let mut text: Vec<(String, Prec)> = Vec::with_capacity(ins.len());
    let mut temporaries = Vec::new();
    for (k, i) in ins.iter().enumerate() {
        let expr = match *i {
            Instr::Input { arg, index } => (input_name(ir, arg, index), Prec::Atom),
            Instr::Const(v) => number(v),
            Instr::Unary(op, a) => unary(op, &text[a]),
            Instr::Binary(op, a, b) => binary(op, &text[a], &text[b]),
        };
        let is_operation = matches!(i, Instr::Unary(..) | Instr::Binary(..));
        if is_operation && uses[k] > 1 {
            let name = format!("t{}", temporaries.len() + 1);
            temporaries.push((name.clone(), expr.0));
            text.push((name, Prec::Atom));
        } else {
            text.push(expr);
        }
    }
    let label = |names: &[String], i: usize| names.get(i).cloned().unwrap_or_else(|| i.to_string());
    let mut entries = Vec::new();
    for o in function.outputs() {
        for (r, c, v) in o.entries() {
            let l = if o.cols == 1 {
                format!("{}[{}]", o.name, label(row_names, r))
            } else {
                format!(
                    "{}[{},{}]",
                    o.name,
                    label(row_names, r),
                    label(col_names, c)
                )
            };
            entries.push((l, text[v].0.clone()));
        }
    }
    Formulas {
        temporaries,
        entries,
    }
}
