//! The one rewrite every function gets after validation, so the emitter and the interpreter
//! (which both read the lowered function) stay bit-identical to each other.
//!
//! Shared reciprocals: the symbolic LDLᵀ solve divides by the same few pivots many times
//! (vehicle8's `f_jac_x`: 30 divisions by 4 denominators). A division costs several times a
//! multiplication, so each denominator gets one `inv` (placed just before its first use) and
//! each `a / d` becomes `a * (1/d)`: at most 1 ulp more rounding error per division, checked
//! against CasADi's golden values and its own C in the tests and the benchmark's gate.
//!
//! Every division is rewritten, also a denominator's only one: then a value that two functions
//! compute with the same operations (f inside `f` and inside `f_jac_x`) stays bit-identical
//! whether or not the other function shares that denominator.

use crate::ops::{BinaryOp, UnaryOp};
use crate::types::{Function, Instr};

/// `f` with each division replaced by a multiplication by one reciprocal per denominator.
pub(crate) fn share_reciprocals(f: Function) -> Function {
    if !(f.instructions.iter()).any(|i| matches!(i, Instr::Binary(BinaryOp::Div, ..))) {
        return f;
    }
    // New id of each old value, and of each denominator's reciprocal once emitted.
    let mut new_id = Vec::with_capacity(f.instructions.len());
    let mut reciprocal: Vec<Option<usize>> = vec![None; f.instructions.len()];
    let mut instructions = Vec::with_capacity(f.instructions.len() + 8);
    for instr in &f.instructions {
        let lowered = match *instr {
            Instr::Binary(BinaryOp::Div, a, d) => {
                let inv = *reciprocal[d].get_or_insert_with(|| {
                    instructions.push(Instr::Unary(UnaryOp::Inv, new_id[d]));
                    instructions.len() - 1
                });
                Instr::Binary(BinaryOp::Mul, new_id[a], inv)
            }
            Instr::Unary(op, a) => Instr::Unary(op, new_id[a]),
            Instr::Binary(op, a, b) => Instr::Binary(op, new_id[a], new_id[b]),
            other @ (Instr::Input { .. } | Instr::Const(_)) => other,
        };
        instructions.push(lowered);
        new_id.push(instructions.len() - 1);
    }
    let mut outputs = f.outputs;
    for output in &mut outputs {
        for v in &mut output.values {
            *v = new_id[*v];
        }
    }
    Function {
        instructions,
        outputs,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::types::{Arg, Output};

    fn input(index: usize) -> Instr {
        Instr::Input { arg: Arg::X, index }
    }

    fn column(values: Vec<usize>) -> Output {
        let n = values.len();
        Output {
            name: "f".into(),
            rows: n,
            cols: 1,
            colind: vec![0, n],
            row: (0..n).collect(),
            values,
        }
    }

    fn eval(f: &Function, x: &[f64]) -> Vec<f64> {
        let mut work = vec![0.0; f.n_values()];
        f.eval(x, &[], &[], &mut work).unwrap();
        f.outputs[0].values.iter().map(|&v| work[v]).collect()
    }

    #[test]
    fn each_denominator_gets_one_reciprocal() {
        // v3 = x0/x2, v4 = x1/x2, v5 = x0/x1.
        let f = Function {
            instructions: vec![
                input(0),
                input(1),
                input(2),
                Instr::Binary(BinaryOp::Div, 0, 2),
                Instr::Binary(BinaryOp::Div, 1, 2),
                Instr::Binary(BinaryOp::Div, 0, 1),
            ],
            outputs: vec![column(vec![3, 4, 5])],
        };
        let x = [3.0, -7.0, 1.7];
        let before = eval(&f, &x);
        let lowered = share_reciprocals(f);
        let expected = [
            input(0),
            input(1),
            input(2),
            Instr::Unary(UnaryOp::Inv, 2),
            Instr::Binary(BinaryOp::Mul, 0, 3),
            Instr::Binary(BinaryOp::Mul, 1, 3),
            Instr::Unary(UnaryOp::Inv, 1),
            Instr::Binary(BinaryOp::Mul, 0, 6),
        ];
        assert_eq!(lowered.instructions, expected);
        assert_eq!(lowered.outputs[0].values, [4, 5, 7]);
        let after = eval(&lowered, &x);
        for (a, b) in after.iter().zip(&before) {
            assert!((a - b).abs() <= 2.0 * f64::EPSILON * b.abs(), "{a} vs {b}");
        }
    }

    #[test]
    fn a_function_without_divisions_is_unchanged() {
        let f = Function {
            instructions: vec![input(0), input(1), Instr::Binary(BinaryOp::Mul, 0, 1)],
            outputs: vec![column(vec![2])],
        };
        assert_eq!(share_reciprocals(f.clone()), f);
    }
}
