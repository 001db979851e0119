//! The scale the gate measures disagreements against: for each value of an IR function, the
//! first-order size of everything that went into it, m(v) = |v| + Σ |∂v/∂operand|·m(operand),
//! with m = |x| for inputs and constants. Two evaluations of the same formula that round
//! differently (a reciprocal instead of a division, a sine 1 ulp apart) differ by a few ulp of
//! m, not of |v|: where terms cancel, |v| can be 0 while m is not.

use twv_ir::{BinaryOp, Function, Instr, UnaryOp};

/// m of every value of `f` at (x, u, p); an operation without a rule here is an error naming it.
pub fn magnitudes(f: &Function, x: &[f64], u: &[f64], p: &[f64]) -> Result<Vec<f64>, String> {
    let mut v = vec![0.0; f.n_values()];
    f.eval(x, u, p, &mut v).map_err(|e| e.to_string())?;
    let mut m = vec![0.0; f.n_values()];
    for (k, instr) in f.instructions().iter().enumerate() {
        m[k] = match *instr {
            Instr::Input { .. } | Instr::Const(_) => v[k].abs(),
            Instr::Unary(op, a) => {
                let slope = match op {
                    UnaryOp::Neg | UnaryOp::Fabs => 1.0,
                    UnaryOp::Twice => 2.0,
                    UnaryOp::Sq => 2.0 * v[a].abs(),
                    UnaryOp::Sin => v[a].cos().abs(),
                    UnaryOp::Cos => v[a].sin().abs(),
                    UnaryOp::Inv => 1.0 / (v[a] * v[a]),
                    UnaryOp::Sqrt => 0.5 / v[k],
                    UnaryOp::Exp => v[k].abs(),
                    UnaryOp::Log => 1.0 / v[a].abs(),
                    other => return Err(format!("no magnitude rule for `{}`", other.name())),
                };
                v[k].abs() + slope * m[a]
            }
            Instr::Binary(op, a, b) => {
                let (sa, sb) = match op {
                    BinaryOp::Add | BinaryOp::Sub => (1.0, 1.0),
                    BinaryOp::Mul => (v[b].abs(), v[a].abs()),
                    BinaryOp::Div => (1.0 / v[b].abs(), (v[a] / (v[b] * v[b])).abs()),
                    other => return Err(format!("no magnitude rule for `{}`", other.name())),
                };
                v[k].abs() + sa * m[a] + sb * m[b]
            }
        };
    }
    Ok(m)
}
