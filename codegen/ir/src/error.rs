//! Typed errors. Each names the file it is about; the problem enums say exactly what is wrong so
//! tests (and callers) can match on them, and their messages are written for a person.

use thiserror::Error;

/// A model IR file that cannot be used.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{file}: {problem}")]
pub struct IrError {
    /// The file as the caller named it.
    pub file: String,
    /// What is wrong with it.
    pub problem: Problem,
}

/// What is wrong with a model IR file.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum Problem {
    #[error("cannot read: {0}")]
    Io(String),
    #[error("truncated JSON: unexpected end of file at line {line}, column {column}")]
    Truncated { line: usize, column: usize },
    #[error("malformed JSON at line {line}, column {column}: {message}")]
    Json {
        line: usize,
        column: usize,
        message: String,
    },
    #[error("format is {found}, expected \"twv-ir/1\" (a reader rejects any other version)")]
    Format { found: String },
    #[error("does not follow the twv-ir/1 schema: {0}")]
    Schema(String),
    #[error("parameter `{name}`: {message}")]
    Param { name: String, message: String },
    #[error("mechanics: {0}")]
    Mechanics(String),
    #[error("missing function `{0}`")]
    MissingFunction(String),
    #[error("function `{function}`: {message}")]
    Function { function: String, message: String },
    #[error("function `{function}`, instruction {index}: {problem}")]
    Instruction {
        function: String,
        index: usize,
        problem: InstrProblem,
    },
    #[error("function `{function}`, output `{output}`: {problem}")]
    Output {
        function: String,
        output: String,
        problem: OutputProblem,
    },
    #[error("golden value {index}: {message}")]
    Golden { index: usize, message: String },
    #[error("malformed hash {0:?}: expected \"sha256:\" followed by 64 hex digits")]
    MalformedHash(String),
    #[error("content hash mismatch: the file says {stored} but its content hashes to {actual} (edited by hand? regenerate it with `python -m twv_modeling derive`)")]
    HashMismatch { stored: String, actual: String },
}

/// What is wrong with one instruction.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum InstrProblem {
    #[error("defines value {found}, expected {expected} (values are numbered in order)")]
    Id { expected: usize, found: String },
    #[error("unknown operation `{0}`")]
    UnknownOp(String),
    #[error("malformed instruction {0}")]
    Malformed(String),
    #[error("`{op}` takes {expected} operand(s), found {found}")]
    Arity {
        op: String,
        expected: usize,
        found: usize,
    },
    #[error("operand {operand} is not an earlier value (SSA: operands must be < {index})")]
    NotEarlier { operand: String, index: usize },
    #[error("input argument {0} does not exist (0 = x, 1 = u, 2 = p)")]
    InputArg(String),
    #[error("input index {index} out of range for argument {arg} ({name}) of size {size}")]
    InputIndex {
        arg: usize,
        name: &'static str,
        index: String,
        size: usize,
    },
    #[error("constant {0} is not a finite number")]
    BadConst(String),
}

/// What is wrong with the compressed-column storage of one output.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum OutputProblem {
    #[error("colind has {found} entries, expected cols + 1 = {expected}")]
    ColindLength { expected: usize, found: usize },
    #[error(
        "colind must start at 0, never decrease and end at the number of stored entries ({nnz})"
    )]
    ColindOrder { nnz: usize },
    #[error("row {row} out of range for {rows} rows")]
    RowOutOfRange { row: usize, rows: usize },
    #[error("rows must increase strictly within each column (column {col})")]
    RowOrder { col: usize },
    #[error("values has {found} entries, expected one per stored entry ({expected})")]
    ValuesLength { expected: usize, found: usize },
    #[error("value id {value} out of range (the function defines {n_values} values)")]
    ValueOutOfRange { value: usize, n_values: usize },
    #[error("shape {found_rows}x{found_cols}, expected {rows}x{cols}")]
    Shape {
        rows: usize,
        cols: usize,
        found_rows: usize,
        found_cols: usize,
    },
    #[error("missing (expected an output of this name)")]
    Missing,
    #[error("sparsity differs from the one of function `{0}`")]
    SparsityMismatch(String),
}

/// A parameter file that cannot be used.
#[derive(Debug, Clone, PartialEq, Error)]
#[error("{file}: {problem}")]
pub struct ParamError {
    /// The file as the caller named it.
    pub file: String,
    /// What is wrong with it.
    pub problem: ParamProblem,
}

/// What is wrong with a parameter file.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ParamProblem {
    #[error("cannot read: {0}")]
    Io(String),
    #[error("malformed TOML: {0}")]
    Syntax(String),
    #[error("unknown key `{0}` (not a parameter of this model)")]
    UnknownKey(String),
    #[error("missing key `{key}` ({description})")]
    MissingKey { key: String, description: String },
    #[error("`{field}` must be {expected}, got {value}")]
    WrongType {
        field: String,
        expected: String,
        value: String,
    },
    #[error("`{field}` must be finite, got {value}")]
    NonFinite { field: String, value: f64 },
    #[error("`{field}` ({kind}) must be positive, got {value}")]
    NotPositive {
        field: String,
        kind: String,
        value: f64,
    },
    #[error("`{field}` = {value:e} is not a plausible {kind}: its magnitude must lie in [{lo:e}, {hi:e}] (SI units)")]
    Magnitude {
        field: String,
        kind: String,
        value: f64,
        lo: f64,
        hi: f64,
    },
    #[error("inertia `{key}` = {values:?} violates the triangle inequality: component {index} ({value}) exceeds the sum of the other two")]
    Triangle {
        key: String,
        values: Vec<f64>,
        index: usize,
        value: f64,
    },
    #[error("{given} values given, the model has {expected} parameters")]
    Count { expected: usize, given: usize },
}

/// An IR and values that cannot make an interpreted model of the requested sizes.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum ModelError {
    #[error("{file}: the model has {found} {what}, the caller expects {expected}")]
    Size {
        file: String,
        what: &'static str,
        found: usize,
        expected: usize,
    },
    #[error(transparent)]
    Params(#[from] ParamError),
    #[error("{file}: native code compiled from IR {compiled} given for IR {ir}")]
    NativeCode {
        file: String,
        compiled: String,
        ir: String,
    },
}

/// A work vector too short for the function evaluated into it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Error)]
#[error("work vector of {given} values, the function needs {needed}")]
pub struct WorkTooShort {
    pub needed: usize,
    pub given: usize,
}
