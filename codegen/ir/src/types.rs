//! The validated model IR. Values of these types only come out of the validator
//! ([`crate::parse_ir`], [`crate::load_ir`]), and their fields are private, so every index in
//! them is known to be in range: the interpreter and the emitter rely on that.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::ops::{BinaryOp, UnaryOp};

/// The only format this crate reads.
pub const FORMAT: &str = "twv-ir/1";

/// How the equations were obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Kind {
    /// Derived from bodies and joints; carries the mechanical parts M, Cp, F, Q, energy, momentum.
    Multibody,
    /// ẋ written by hand.
    Explicit,
}

/// A state or input.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Signal {
    pub name: String,
    pub unit: String,
    pub description: String,
}

/// Kinds of parameter, deciding how a value is validated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ParamKind {
    Mass,
    Inertia,
    Length,
    Gravity,
    Other,
}

impl ParamKind {
    /// The IR's name of the kind.
    pub fn name(self) -> &'static str {
        match self {
            ParamKind::Mass => "mass",
            ParamKind::Inertia => "inertia",
            ParamKind::Length => "length",
            ParamKind::Gravity => "gravity",
            ParamKind::Other => "other",
        }
    }

    /// The magnitudes a value of this kind may have (SI units): wide enough for any vehicle
    /// from a toy to a truck, narrow enough that a typo such as `m1 = 1e308` is refused rather
    /// than making every run overflow or crawl.
    pub fn magnitude_range(self) -> (f64, f64) {
        match self {
            ParamKind::Mass => (1e-6, 1e6),
            ParamKind::Inertia => (1e-9, 1e7),
            ParamKind::Length => (0.0, 1e3),
            ParamKind::Gravity => (0.0, 1e3),
            ParamKind::Other => (0.0, 1e12),
        }
    }

    /// Whether a value of this kind must be strictly positive.
    pub fn must_be_positive(self) -> bool {
        matches!(
            self,
            ParamKind::Mass | ParamKind::Inertia | ParamKind::Gravity
        )
    }
}

/// One scalar parameter.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Param {
    pub name: String,
    pub key: String,
    pub index: Option<usize>,
    pub unit: String,
    pub kind: ParamKind,
    pub default: f64,
    pub used: bool,
    pub description: String,
}

/// The `mechanics` header of a multibody model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Mechanics {
    pub coordinates: Vec<String>,
    pub speeds: Vec<String>,
    #[serde(default)]
    pub ignorable_coordinates: Vec<String>,
    #[serde(default)]
    pub constraints: Vec<serde_json::Value>,
    #[serde(default)]
    pub mass_matrix_solve: String,
    /// Straight running at a speed, for linearisations against speed (the bicycle), if the
    /// model describes it; the IR's function `steady` is then the state at unit speed.
    #[serde(default)]
    pub steady_motion: Option<SteadyMotion>,
}

/// `mechanics.steady_motion`: which state carries the speed, and the modes studied about it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SteadyMotion {
    pub speed_state: String,
    pub modes: Vec<String>,
}

/// Reference values computed by CasADi (every parameter at its default).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Golden {
    pub x: Vec<f64>,
    pub u: Vec<f64>,
    /// ẋ (the stored entries of `f`).
    pub f: Vec<f64>,
    /// The stored entries of ∂f/∂x in the CCS order of `functions.jac_x`.
    pub jac_x: Vec<f64>,
}

/// Which argument an input instruction reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arg {
    /// Argument 0, the state.
    X,
    /// Argument 1, the input.
    U,
    /// Argument 2, the parameters.
    P,
}

impl Arg {
    /// The argument number in the IR.
    pub fn number(self) -> usize {
        match self {
            Arg::X => 0,
            Arg::U => 1,
            Arg::P => 2,
        }
    }
}

/// One instruction; instruction `k` defines value `k`, operands are earlier values.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Instr {
    Input { arg: Arg, index: usize },
    Const(f64),
    Unary(UnaryOp, usize),
    Binary(BinaryOp, usize, usize),
}

/// One output matrix in compressed-column storage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Output {
    pub name: String,
    pub rows: usize,
    pub cols: usize,
    pub colind: Vec<usize>,
    pub row: Vec<usize>,
    /// The value id of each stored entry.
    pub values: Vec<usize>,
}

impl Output {
    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.row.len()
    }

    /// Stored entries as (row, column, value id), in CCS order.
    pub fn entries(&self) -> impl Iterator<Item = (usize, usize, usize)> + '_ {
        self.colind
            .windows(2)
            .enumerate()
            .flat_map(move |(col, w)| (w[0]..w[1]).map(move |e| (self.row[e], col, self.values[e])))
    }

    /// Each row's stored entries in increasing column order, as (column, CCS index): the row
    /// form of J·w that every path computes (`twv_kernels::tangents`).
    pub fn stored_rows(&self) -> Vec<Vec<(usize, usize)>> {
        let mut rows = vec![Vec::new(); self.rows];
        for (e, (r, c, _)) in self.entries().enumerate() {
            rows[r].push((c, e));
        }
        rows
    }

    /// [`stored_rows`](Self::stored_rows) with each entry's value id instead of its CCS
    /// index: what the interpreter's J·W multiplies by (the JIT's reads the entries by CCS index
    /// from an array of its own).
    pub fn stored_row_values(&self) -> Vec<Vec<(usize, usize)>> {
        let mut rows = self.stored_rows();
        for (_, e) in rows.iter_mut().flatten() {
            *e = self.values[*e];
        }
        rows
    }

    /// Whether two outputs store the same entries (same shape and pattern).
    pub fn same_sparsity(&self, other: &Output) -> bool {
        self.rows == other.rows
            && self.cols == other.cols
            && self.colind == other.colind
            && self.row == other.row
    }
}

/// A straight-line function of (x, u, p).
#[derive(Debug, Clone, PartialEq)]
pub struct Function {
    pub(crate) instructions: Vec<Instr>,
    pub(crate) outputs: Vec<Output>,
}

impl Function {
    /// The instructions; instruction `k` defines value `k`.
    pub fn instructions(&self) -> &[Instr] {
        &self.instructions
    }

    /// The angles whose sines and cosines compiled code takes two at a time
    /// (`twv_kernels::trig::sin_cos_pair`): states or inputs (so they exist before any
    /// instruction) that a `sin` or `cos` reads, in order of first use, paired off; an odd one
    /// out is left alone. Each as (value id, argument, index). The generated code and the JIT
    /// pair the same angles.
    pub fn paired_angles(&self) -> Vec<[(usize, Arg, usize); 2]> {
        let mut angles: Vec<(usize, Arg, usize)> = Vec::new();
        for instr in &self.instructions {
            if let Instr::Unary(UnaryOp::Sin | UnaryOp::Cos, x) = *instr {
                if let Some(&Instr::Input {
                    arg: arg @ (Arg::X | Arg::U),
                    index,
                }) = self.instructions.get(x)
                {
                    if !angles.iter().any(|a| a.0 == x) {
                        angles.push((x, arg, index));
                    }
                }
            }
        }
        angles.chunks_exact(2).map(|p| [p[0], p[1]]).collect()
    }

    /// Number of values defined (= instructions).
    pub fn n_values(&self) -> usize {
        self.instructions.len()
    }

    /// Instructions that are operations (not inputs or constants).
    pub fn n_ops(&self) -> usize {
        self.instructions
            .iter()
            .filter(|i| matches!(i, Instr::Unary(..) | Instr::Binary(..)))
            .count()
    }

    /// The outputs, in order.
    pub fn outputs(&self) -> &[Output] {
        &self.outputs
    }

    /// The output of this name.
    pub fn output(&self, name: &str) -> Option<&Output> {
        self.outputs.iter().find(|o| o.name == name)
    }

    /// Whether any instruction reads argument `arg`.
    pub fn reads(&self, arg: Arg) -> bool {
        self.instructions
            .iter()
            .any(|i| matches!(i, Instr::Input { arg: a, .. } if *a == arg))
    }
}

/// A validated model IR.
#[derive(Debug, Clone, PartialEq)]
pub struct Ir {
    pub(crate) file: String,
    pub(crate) hash: String,
    pub(crate) model: String,
    pub(crate) kind: Kind,
    pub(crate) description: String,
    pub(crate) states: Vec<Signal>,
    pub(crate) inputs: Vec<Signal>,
    pub(crate) params: Vec<Param>,
    pub(crate) mechanics: Option<Mechanics>,
    pub(crate) functions: BTreeMap<String, Function>,
    pub(crate) golden: Vec<Golden>,
}

impl Ir {
    /// The file name the IR was loaded from (as the caller named it).
    pub fn file(&self) -> &str {
        &self.file
    }
    /// `sha256:<hex>`, verified against the content.
    pub fn hash(&self) -> &str {
        &self.hash
    }
    /// Model name.
    pub fn model(&self) -> &str {
        &self.model
    }
    /// Multibody or explicit.
    pub fn kind(&self) -> Kind {
        self.kind
    }
    /// One sentence.
    pub fn description(&self) -> &str {
        &self.description
    }
    /// States in vector order.
    pub fn states(&self) -> &[Signal] {
        &self.states
    }
    /// Inputs in vector order.
    pub fn inputs(&self) -> &[Signal] {
        &self.inputs
    }
    /// Parameters in vector order.
    pub fn params(&self) -> &[Param] {
        &self.params
    }
    /// The mechanics header (multibody models).
    pub fn mechanics(&self) -> Option<&Mechanics> {
        self.mechanics.as_ref()
    }
    /// The function of this name.
    pub fn function(&self, name: &str) -> Option<&Function> {
        self.functions.get(name)
    }
    /// All functions, by name.
    pub fn functions(&self) -> &BTreeMap<String, Function> {
        &self.functions
    }
    /// CasADi's reference values.
    pub fn golden(&self) -> &[Golden] {
        &self.golden
    }
    /// Number of states.
    pub fn nx(&self) -> usize {
        self.states.len()
    }
    /// Number of inputs.
    pub fn nu(&self) -> usize {
        self.inputs.len()
    }
    /// Number of parameters.
    pub fn np(&self) -> usize {
        self.params.len()
    }
    /// Number of quasi-velocities (multibody models), else 0.
    pub fn ns(&self) -> usize {
        self.mechanics.as_ref().map_or(0, |m| m.speeds.len())
    }
    /// The default of every parameter, in order.
    pub fn defaults(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.default).collect()
    }
    /// The size of argument `arg`.
    pub fn arg_size(&self, arg: Arg) -> usize {
        match arg {
            Arg::X => self.nx(),
            Arg::U => self.nu(),
            Arg::P => self.np(),
        }
    }
    /// Output `output` of function `function`.
    pub fn output(&self, function: &str, output: &str) -> Option<&Output> {
        self.functions.get(function)?.output(output)
    }
    /// The sparsity of ∂f/∂x (validation guarantees it exists for a loaded IR).
    pub fn jac_x_sparsity(&self) -> Option<&Output> {
        self.output("jac_x", "jac_x")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// States and inputs pair off in order of first use; an angle that is computed, a
    /// parameter, or the odd one out is not paired.
    #[test]
    fn paired_angles_are_states_and_inputs_in_order_of_first_use() {
        let x = |index| Instr::Input { arg: Arg::X, index };
        let f = Function {
            instructions: vec![
                x(3),                          // 0: theta
                Instr::Unary(UnaryOp::Cos, 0), // 1
                Instr::Input {
                    arg: Arg::P,
                    index: 0,
                }, // 2: a parameter
                Instr::Unary(UnaryOp::Sin, 2), // 3
                x(0),                          // 4: phi
                Instr::Binary(BinaryOp::Add, 0, 4), // 5: computed
                Instr::Unary(UnaryOp::Sin, 5), // 6
                Instr::Unary(UnaryOp::Sin, 4), // 7
                Instr::Unary(UnaryOp::Sin, 0), // 8: theta again
                Instr::Input {
                    arg: Arg::U,
                    index: 1,
                }, // 9: an input
                Instr::Unary(UnaryOp::Cos, 9), // 10: the odd one out
            ],
            outputs: vec![],
        };
        assert_eq!(f.paired_angles(), [[(0, Arg::X, 3), (4, Arg::X, 0)]]);
    }
}
