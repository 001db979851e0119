//! Reading and validating a model IR file: JSON syntax, then the format version, then the schema,
//! then every index and shape, and last the content hash (so a hand-edited file reports what is
//! structurally wrong with it before saying that it was edited).

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;
use serde_json::Value;

use crate::error::{InstrProblem, IrError, OutputProblem, Problem};
use crate::hash::check_hash;
use crate::ops::{BinaryOp, UnaryOp};
use crate::types::{
    Arg, Function, Golden, Instr, Ir, Kind, Mechanics, Output, Param, Signal, FORMAT,
};

/// Functions every model has.
pub const REQUIRED_FUNCTIONS: [&str; 4] = ["f", "jac_x", "jac_u", "f_jac_x"];
/// Functions every multibody model adds (the Poincaré parts).
pub const MECHANICAL_FUNCTIONS: [&str; 6] = ["M", "Cp", "F", "Q", "energy", "momentum"];

#[derive(Deserialize)]
struct RawIr {
    hash: String,
    model: String,
    kind: Kind,
    #[serde(default)]
    description: String,
    states: Vec<Signal>,
    inputs: Vec<Signal>,
    params: Vec<Param>,
    #[serde(default)]
    mechanics: Option<Mechanics>,
    functions: BTreeMap<String, RawFunction>,
    #[serde(default)]
    golden: Vec<Golden>,
}

#[derive(Deserialize)]
struct RawFunction {
    n_values: usize,
    n_ops: usize,
    instructions: Vec<Value>,
    outputs: Vec<Output>,
}

/// Read and validate the IR file at `path`; errors name the file as given.
pub fn load_ir(path: impl AsRef<Path>) -> Result<Ir, IrError> {
    let path = path.as_ref();
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| IrError {
        file: file.clone(),
        problem: Problem::Io(e.to_string()),
    })?;
    parse_ir(&text, &file)
}

/// Validate IR text; `file` is the name used in errors.
pub fn parse_ir(text: &str, file: &str) -> Result<Ir, IrError> {
    parse_inner(text, file).map_err(|problem| IrError {
        file: file.to_string(),
        problem,
    })
}

fn parse_inner(text: &str, file: &str) -> Result<Ir, Problem> {
    serde_json::from_str::<crate::unique_keys::UniqueKeys>(text).map_err(json_problem)?;
    let value: Value = serde_json::from_str(text).map_err(json_problem)?;
    check_format(&value)?;
    let raw: RawIr = serde_json::from_value(value).map_err(|e| Problem::Schema(e.to_string()))?;
    let ir = build(raw, file)?;
    check_hash(text, &ir.hash)?;
    crate::consistency::check_jacobians(&ir)?;
    Ok(ir)
}

fn json_problem(e: serde_json::Error) -> Problem {
    let (line, column) = (e.line(), e.column());
    if e.is_eof() {
        Problem::Truncated { line, column }
    } else {
        Problem::Json {
            line,
            column,
            message: e.to_string(),
        }
    }
}

fn check_format(value: &Value) -> Result<(), Problem> {
    match value.get("format") {
        Some(Value::String(s)) if s == FORMAT => Ok(()),
        Some(other) => Err(Problem::Format {
            found: other.to_string(),
        }),
        None => Err(Problem::Format {
            found: "missing".to_string(),
        }),
    }
}

fn build(raw: RawIr, file: &str) -> Result<Ir, Problem> {
    check_params(&raw.params)?;
    let sizes = [raw.states.len(), raw.inputs.len(), raw.params.len()];
    let mut functions = BTreeMap::new();
    for (name, f) in raw.functions {
        let function = build_function(&name, f, sizes)?;
        functions.insert(name, function);
    }
    let ir = Ir {
        file: file.to_string(),
        hash: raw.hash,
        model: raw.model,
        kind: raw.kind,
        description: raw.description,
        states: raw.states,
        inputs: raw.inputs,
        params: raw.params,
        mechanics: raw.mechanics,
        functions,
        golden: raw.golden,
    };
    check_mechanics(&ir)?;
    check_shapes(&ir)?;
    check_golden(&ir)?;
    Ok(ir)
}

fn check_params(params: &[Param]) -> Result<(), Problem> {
    let bad = |p: &Param, message: String| Problem::Param {
        name: p.name.clone(),
        message,
    };
    for (i, p) in params.iter().enumerate() {
        if params[..i].iter().any(|q| q.name == p.name) {
            return Err(bad(p, "declared twice".into()));
        }
        if !p.default.is_finite() {
            return Err(bad(p, format!("default {} is not finite", p.default)));
        }
        let same_key: Vec<&Param> = params.iter().filter(|q| q.key == p.key).collect();
        let indexed = same_key.iter().filter(|q| q.index.is_some()).count();
        if indexed != 0 && indexed != same_key.len() {
            return Err(bad(
                p,
                format!("key `{}` is both a scalar and an array", p.key),
            ));
        }
        if let Some(index) = p.index {
            let dup = same_key.iter().filter(|q| q.index == Some(index)).count() > 1;
            if index >= same_key.len() || dup {
                return Err(bad(
                    p,
                    format!(
                        "index {index} of key `{}` is not one of 0..{} exactly once",
                        p.key,
                        same_key.len()
                    ),
                ));
            }
        } else if same_key.len() > 1 {
            return Err(bad(
                p,
                format!("key `{}` is used by several scalar parameters", p.key),
            ));
        }
    }
    Ok(())
}

fn build_function(name: &str, raw: RawFunction, sizes: [usize; 3]) -> Result<Function, Problem> {
    let instructions = raw
        .instructions
        .iter()
        .enumerate()
        .map(|(k, v)| {
            parse_instr(k, v, sizes).map_err(|problem| Problem::Instruction {
                function: name.to_string(),
                index: k,
                problem,
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    let function = Function {
        instructions,
        outputs: raw.outputs,
    };
    let counts_wrong = |what: &str, stated: usize, found: usize| Problem::Function {
        function: name.to_string(),
        message: format!("{what} says {stated}, the instruction list has {found}"),
    };
    if raw.n_values != function.n_values() {
        return Err(counts_wrong("n_values", raw.n_values, function.n_values()));
    }
    if raw.n_ops != function.n_ops() {
        return Err(counts_wrong("n_ops", raw.n_ops, function.n_ops()));
    }
    for output in &function.outputs {
        check_output(output, function.n_values()).map_err(|problem| Problem::Output {
            function: name.to_string(),
            output: output.name.clone(),
            problem,
        })?;
    }
    Ok(crate::lower::share_reciprocals(function))
}

const ARG_NAMES: [&str; 3] = ["x", "u", "p"];

fn parse_instr(k: usize, v: &Value, sizes: [usize; 3]) -> Result<Instr, InstrProblem> {
    let items = v
        .as_array()
        .filter(|a| a.len() >= 2)
        .ok_or_else(|| InstrProblem::Malformed(v.to_string()))?;
    if items[0].as_u64() != Some(k as u64) {
        return Err(InstrProblem::Id {
            expected: k,
            found: items[0].to_string(),
        });
    }
    let op = items[1]
        .as_str()
        .ok_or_else(|| InstrProblem::Malformed(v.to_string()))?;
    let operands = &items[2..];
    let arity = |expected: usize| {
        if operands.len() == expected {
            Ok(())
        } else {
            Err(InstrProblem::Arity {
                op: op.to_string(),
                expected,
                found: operands.len(),
            })
        }
    };
    if op == "input" {
        arity(2)?;
        return parse_input(&operands[0], &operands[1], sizes);
    }
    if op == "const" {
        arity(1)?;
        return match operands[0].as_f64() {
            Some(c) if c.is_finite() => Ok(Instr::Const(c)),
            _ => Err(InstrProblem::BadConst(operands[0].to_string())),
        };
    }
    if let Some(op) = UnaryOp::from_name(op) {
        arity(1)?;
        return Ok(Instr::Unary(op, operand(&operands[0], k)?));
    }
    if let Some(op) = BinaryOp::from_name(op) {
        arity(2)?;
        return Ok(Instr::Binary(
            op,
            operand(&operands[0], k)?,
            operand(&operands[1], k)?,
        ));
    }
    Err(InstrProblem::UnknownOp(op.to_string()))
}

fn parse_input(arg: &Value, index: &Value, sizes: [usize; 3]) -> Result<Instr, InstrProblem> {
    let arg_no = arg
        .as_u64()
        .filter(|&a| a < 3)
        .ok_or_else(|| InstrProblem::InputArg(arg.to_string()))? as usize;
    let size = sizes[arg_no];
    match index.as_u64() {
        Some(i) if (i as usize) < size => Ok(Instr::Input {
            arg: [Arg::X, Arg::U, Arg::P][arg_no],
            index: i as usize,
        }),
        _ => Err(InstrProblem::InputIndex {
            arg: arg_no,
            name: ARG_NAMES[arg_no],
            index: index.to_string(),
            size,
        }),
    }
}

fn operand(v: &Value, k: usize) -> Result<usize, InstrProblem> {
    match v.as_u64() {
        Some(a) if (a as usize) < k => Ok(a as usize),
        _ => Err(InstrProblem::NotEarlier {
            operand: v.to_string(),
            index: k,
        }),
    }
}

fn check_output(o: &Output, n_values: usize) -> Result<(), OutputProblem> {
    if o.colind.len() != o.cols + 1 {
        return Err(OutputProblem::ColindLength {
            expected: o.cols + 1,
            found: o.colind.len(),
        });
    }
    let nnz = o.row.len();
    let ordered = o.colind.windows(2).all(|w| w[0] <= w[1]);
    if o.colind.first() != Some(&0) || o.colind.last() != Some(&nnz) || !ordered {
        return Err(OutputProblem::ColindOrder { nnz });
    }
    if o.values.len() != nnz {
        return Err(OutputProblem::ValuesLength {
            expected: nnz,
            found: o.values.len(),
        });
    }
    if let Some(&row) = o.row.iter().find(|&&r| r >= o.rows) {
        return Err(OutputProblem::RowOutOfRange { row, rows: o.rows });
    }
    for (col, w) in o.colind.windows(2).enumerate() {
        if o.row[w[0]..w[1]].windows(2).any(|r| r[0] >= r[1]) {
            return Err(OutputProblem::RowOrder { col });
        }
    }
    match o.values.iter().find(|&&v| v >= n_values) {
        Some(&value) => Err(OutputProblem::ValueOutOfRange { value, n_values }),
        None => Ok(()),
    }
}

fn check_mechanics(ir: &Ir) -> Result<(), Problem> {
    match (&ir.mechanics, ir.kind) {
        (None, Kind::Multibody) => Err(Problem::Mechanics(
            "a multibody model needs the `mechanics` header".into(),
        )),
        (Some(m), _) if m.speeds.is_empty() || m.speeds.len() > ir.nx() => Err(Problem::Mechanics(
            format!("{} speeds for {} states", m.speeds.len(), ir.nx()),
        )),
        _ => Ok(()),
    }
}

/// The expected shape of each output (by function and output name) for this model.
fn expected_shapes(ir: &Ir) -> Vec<(&'static str, &'static str, usize, usize)> {
    let (nx, nu, ns) = (ir.nx(), ir.nu(), ir.ns());
    let mut shapes = vec![
        ("f", "f", nx, 1),
        ("jac_x", "jac_x", nx, nx),
        ("jac_u", "jac_u", nx, nu),
        ("f_jac_x", "f", nx, 1),
        ("f_jac_x", "jac_x", nx, nx),
    ];
    if ir.kind == Kind::Multibody {
        shapes.extend([
            ("M", "M", ns, ns),
            ("Cp", "Cp", ns, 1),
            ("F", "F", ns, 1),
            ("Q", "Q", ns, 1),
            ("energy", "energy", 1, 1),
            ("momentum", "momentum", 3, 1),
        ]);
    } else if ir.functions.contains_key("energy") {
        shapes.push(("energy", "energy", 1, 1));
    }
    shapes
}

fn check_shapes(ir: &Ir) -> Result<(), Problem> {
    for (function, output, rows, cols) in expected_shapes(ir) {
        let f = ir
            .functions
            .get(function)
            .ok_or_else(|| Problem::MissingFunction(function.to_string()))?;
        let bad = |problem| Problem::Output {
            function: function.to_string(),
            output: output.to_string(),
            problem,
        };
        let o = f
            .output(output)
            .ok_or_else(|| bad(OutputProblem::Missing))?;
        if (o.rows, o.cols) != (rows, cols) {
            return Err(bad(OutputProblem::Shape {
                rows,
                cols,
                found_rows: o.rows,
                found_cols: o.cols,
            }));
        }
    }
    // f_jac_x must store exactly what f and jac_x store: one sparsity serves all three.
    for name in ["f", "jac_x"] {
        let single = ir.output(name, name);
        let joint = ir.output("f_jac_x", name);
        if !matches!((single, joint), (Some(s), Some(j)) if s.same_sparsity(j)) {
            return Err(Problem::Output {
                function: "f_jac_x".into(),
                output: name.into(),
                problem: OutputProblem::SparsityMismatch(name.into()),
            });
        }
    }
    Ok(())
}

fn check_golden(ir: &Ir) -> Result<(), Problem> {
    let nnz = |name: &str| ir.output(name, name).map_or(0, Output::nnz);
    let (nnz_f, nnz_j) = (nnz("f"), nnz("jac_x"));
    for (index, g) in ir.golden.iter().enumerate() {
        let lens = [g.x.len(), g.u.len(), g.f.len(), g.jac_x.len()];
        let expected = [ir.nx(), ir.nu(), nnz_f, nnz_j];
        if lens != expected {
            return Err(Problem::Golden {
                index,
                message: format!("lengths (x, u, f, jac_x) are {lens:?}, expected {expected:?}"),
            });
        }
    }
    Ok(())
}
