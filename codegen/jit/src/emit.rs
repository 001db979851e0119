//! The Cranelift IR of the routines: an IR function's instructions as one straight-line block
//! whose values are stored where they are needed (the interpreter's work vector, a dense
//! output, an array of the Jacobian's entries) as soon as they exist; then the trace and the
//! J·W loop, read back from that array.

use cranelift_codegen::ir::{
    types, FuncRef, InstBuilder, MemFlagsData, StackSlotData, StackSlotKind, Value,
};
use cranelift_frontend::FunctionBuilder;
use twv_ir::{BinaryOp, Function, Instr, Output, UnaryOp};

/// The routines' memory accesses: the slices are valid for what they read and write (checked
/// by the caller), aligned, and never alias each other.
const MEMORY: MemFlagsData = MemFlagsData::trusted();

/// The interpreter's helpers, as references inside the function being built.
pub struct Helpers {
    pub unary: FuncRef,
    pub binary: FuncRef,
    /// `twv_sin_cos_pair(a, b, out)`: the sines and cosines of two angles.
    pub sin_cos_pair: FuncRef,
    /// The target's pointer type (for the pair's stack slot).
    pub pointer: types::Type,
}

/// The byte offset of entry `index` of an f64 slice (bounded by the size check of
/// `Builder::compile`).
fn offset(index: usize) -> i32 {
    (index * 8) as i32
}

/// Where values go as soon as they exist: `sinks[k]` lists (base pointer, byte offset) pairs
/// for value `k`. Storing a value at once, rather than after the whole function, keeps it out
/// of the register allocator's way: a value live across the bicycle's 18 000 instructions and
/// their calls made its J·W routine 7x slower.
pub type Sinks = Vec<Vec<(Value, i32)>>;

/// Emits every instruction of `function` in order, reading x, u, p through `args` and storing
/// each value where `sinks` says.
pub fn values(
    b: &mut FunctionBuilder<'_>,
    helpers: &Helpers,
    function: &Function,
    args: [Value; 3],
    sinks: &Sinks,
) -> Vec<Value> {
    let paired = sin_cos_pairs(b, helpers, function, args);
    let mut values: Vec<Value> = Vec::with_capacity(function.n_values());
    for (instr, sinks) in function.instructions().iter().zip(sinks) {
        let value = match *instr {
            Instr::Input { arg, index } => {
                b.ins()
                    .load(types::F64, MEMORY, args[arg.number()], offset(index))
            }
            Instr::Const(c) => b.ins().f64const(c),
            Instr::Unary(op @ (UnaryOp::Sin | UnaryOp::Cos), a) if paired.contains_key(&a) => {
                let (sin, cos) = paired[&a];
                if op == UnaryOp::Sin {
                    sin
                } else {
                    cos
                }
            }
            Instr::Unary(op, a) => unary(b, helpers.unary, op, values[a]),
            Instr::Binary(op, l, r) => binary(b, helpers.binary, op, values[l], values[r]),
        };
        for &(base, at) in sinks {
            b.ins().store(MEMORY, value, base, at);
        }
        values.push(value);
    }
    values
}

/// The sines and cosines of `function`'s paired angles (`Function::paired_angles`, the
/// generated code's pairs), one `twv_sin_cos_pair` call per pair at the top of the routine, the
/// angles read straight from x or u: for each paired angle's value id, (sin, cos).
fn sin_cos_pairs(
    b: &mut FunctionBuilder<'_>,
    helpers: &Helpers,
    function: &Function,
    args: [Value; 3],
) -> std::collections::BTreeMap<usize, (Value, Value)> {
    let mut paired = std::collections::BTreeMap::new();
    for pair in function.paired_angles() {
        let [a, c] = pair.map(|(_, arg, index)| {
            b.ins()
                .load(types::F64, MEMORY, args[arg.number()], offset(index))
        });
        let slot =
            b.create_sized_stack_slot(StackSlotData::new(StackSlotKind::ExplicitSlot, 32, 3));
        let out = b.ins().stack_addr(helpers.pointer, slot, 0);
        b.ins().call(helpers.sin_cos_pair, &[a, c, out]);
        let [sa, ca, sc, cc] =
            [0, 1, 2, 3].map(|i| b.ins().load(types::F64, MEMORY, out, offset(i)));
        paired.insert(pair[0].0, (sa, ca));
        paired.insert(pair[1].0, (sc, cc));
    }
    paired
}

/// Adds sinks that store every value an output of `function` reads at `work[id]`.
pub fn work_sinks(sinks: &mut Sinks, function: &Function, work: Value) {
    for output in function.outputs() {
        for &id in &output.values {
            if sinks[id].is_empty() {
                sinks[id].push((work, offset(id)));
            }
        }
    }
}

/// Adds sinks that store the stored entries of `jac` in order into an array on the routine's
/// stack, and returns its address (`pointer`-typed).
pub fn entry_sinks(
    b: &mut FunctionBuilder<'_>,
    sinks: &mut Sinks,
    jac: &Output,
    pointer: types::Type,
) -> Value {
    let size = (8 * jac.values.len()) as u32;
    let slot = b.create_sized_stack_slot(StackSlotData::new(StackSlotKind::ExplicitSlot, size, 3));
    let entries = b.ins().stack_addr(pointer, slot, 0);
    for (e, &v) in jac.values.iter().enumerate() {
        sinks[v].push((entries, offset(e)));
    }
    entries
}

/// The address of each of `rows` rows of a row-major matrix at `base` whose row stride (in
/// entries) is the run-time value `stride`.
pub fn row_pointers(
    b: &mut FunctionBuilder<'_>,
    base: Value,
    stride: Value,
    rows: usize,
) -> Vec<Value> {
    let row_bytes = b.ins().imul_imm_u(stride, 8);
    let mut row = base;
    let mut out = Vec::with_capacity(rows);
    for r in 0..rows {
        if r > 0 {
            row = b.ins().iadd(row, row_bytes);
        }
        out.push(row);
    }
    out
}

/// Adds sinks that write output `output` densely, row `r` at `rows[r]`, and stores 0.0 now in
/// the cells it has no entry for.
pub fn dense_sinks(
    b: &mut FunctionBuilder<'_>,
    sinks: &mut Sinks,
    output: &Output,
    rows: &[Value],
) {
    let mut has = vec![vec![false; output.cols]; output.rows];
    for (r, c, v) in output.entries() {
        sinks[v].push((rows[r], offset(c)));
        has[r][c] = true;
    }
    let zero = b.ins().f64const(0.0);
    for (r, row) in has.iter().enumerate() {
        for (c, _) in row.iter().enumerate().filter(|(_, h)| !**h) {
            b.ins().store(MEMORY, zero, rows[r], offset(c));
        }
    }
}

/// Loads `base[index]` (a value stored by a sink).
pub fn load(b: &mut FunctionBuilder<'_>, base: Value, index: usize) -> Value {
    b.ins().load(types::F64, MEMORY, base, offset(index))
}

/// tr(∂f/∂x) as the generated code sums it: 0.0, then each stored diagonal entry in order
/// (`entries`: the stored entries of `jac`, in order).
pub fn trace(b: &mut FunctionBuilder<'_>, entries: &[Value], jac: &Output) -> Value {
    let mut sum = b.ins().f64const(0.0);
    for ((r, c, _), &entry) in jac.entries().zip(entries) {
        if r == c {
            sum = b.ins().fadd(sum, entry);
        }
    }
    sum
}

/// The loop `for k in 0..count { out[k] = J · w[k] }` (rows of `nx`), with the interpreter's
/// operations: the row form over `rows` (each row's stored entries as (column, index), read
/// back from `entries`). Leaves the builder in the block after the loop.
pub fn jw_loop(
    b: &mut FunctionBuilder<'_>,
    entries: Value,
    rows: &[Vec<(usize, usize)>],
    nx: usize,
    (w, count, out): (Value, Value, Value),
) {
    let header = b.create_block();
    let body = b.create_block();
    let exit = b.create_block();
    let k = b.append_block_param(header, types::I64);
    let start = b.ins().iconst(types::I64, 0);
    b.ins().jump(header, &[start.into()]);

    b.switch_to_block(header);
    let more = b.ins().icmp(
        cranelift_codegen::ir::condcodes::IntCC::UnsignedLessThan,
        k,
        count,
    );
    b.ins().brif(more, body, &[], exit, &[]);

    b.switch_to_block(body);
    b.seal_block(body);
    let row_bytes = b.ins().imul_imm_u(k, (nx * 8) as i64);
    let w_row = b.ins().iadd(w, row_bytes);
    let out_row = b.ins().iadd(out, row_bytes);
    row_form(b, rows, nx, (w_row, 0, out_row), |b, e| load(b, entries, e));
    let next = b.ins().iadd_imm_u(k, 1);
    b.ins().jump(header, &[next.into()]);
    b.seal_block(header);

    b.switch_to_block(exit);
    b.seal_block(exit);
}

/// J·W for exactly `count` tangent vectors, written out from the Jacobian's stored entries as
/// values (`entries`, in order), for each vector the operations of [`jw_loop`] (the same bits):
/// no loop, no address arithmetic, no trip through memory.
pub fn jw_unrolled(
    b: &mut FunctionBuilder<'_>,
    entries: &[Value],
    rows: &[Vec<(usize, usize)>],
    nx: usize,
    (w, count, out): (Value, usize, Value),
) {
    for k in 0..count {
        row_form(b, rows, nx, (w, k * nx, out), |_, e| entries[e]);
    }
}

/// One tangent vector's J·w in the row form (`twv_kernels::tangents`): for each of the `nx`
/// rows its stored products `entry(e) · w[c]` summed left to right, 0.0 for a row without
/// entries; `w` and `out` read and written at `w + 8·(at + i)`, `out + 8·(at + r)`.
fn row_form(
    b: &mut FunctionBuilder<'_>,
    rows: &[Vec<(usize, usize)>],
    nx: usize,
    (w, at, out): (Value, usize, Value),
    mut entry: impl FnMut(&mut FunctionBuilder<'_>, usize) -> Value,
) {
    let mut w_values: Vec<Option<Value>> = vec![None; nx];
    for r in 0..nx {
        let mut sum = None;
        for &(c, e) in rows.get(r).map_or(&[][..], Vec::as_slice) {
            let wc = *w_values[c]
                .get_or_insert_with(|| b.ins().load(types::F64, MEMORY, w, offset(at + c)));
            let j = entry(b, e);
            let term = b.ins().fmul(j, wc);
            sum = Some(match sum {
                None => term,
                Some(s) => b.ins().fadd(s, term),
            });
        }
        let value = sum.unwrap_or_else(|| b.ins().f64const(0.0));
        b.ins().store(MEMORY, value, out, offset(at + r));
    }
}

fn unary(b: &mut FunctionBuilder<'_>, helper: FuncRef, op: UnaryOp, a: Value) -> Value {
    match op {
        UnaryOp::Neg => b.ins().fneg(a),
        UnaryOp::Sqrt => b.ins().sqrt(a),
        UnaryOp::Fabs => b.ins().fabs(a),
        UnaryOp::Sq => b.ins().fmul(a, a),
        UnaryOp::Twice => {
            let two = b.ins().f64const(2.0);
            b.ins().fmul(two, a)
        }
        UnaryOp::Inv => {
            let one = b.ins().f64const(1.0);
            b.ins().fdiv(one, a)
        }
        _ => {
            let number = UnaryOp::ALL.iter().position(|o| *o == op).unwrap_or(0);
            let number = b.ins().iconst(types::I32, number as i64);
            let call = b.ins().call(helper, &[number, a]);
            b.inst_results(call)[0]
        }
    }
}

fn binary(b: &mut FunctionBuilder<'_>, helper: FuncRef, op: BinaryOp, l: Value, r: Value) -> Value {
    match op {
        BinaryOp::Add => b.ins().fadd(l, r),
        BinaryOp::Sub => b.ins().fsub(l, r),
        BinaryOp::Mul => b.ins().fmul(l, r),
        BinaryOp::Div => b.ins().fdiv(l, r),
        BinaryOp::Copysign => b.ins().fcopysign(l, r),
        _ => {
            let number = BinaryOp::ALL.iter().position(|o| *o == op).unwrap_or(0);
            let number = b.ins().iconst(types::I32, number as i64);
            let call = b.ins().call(helper, &[number, l, r]);
            b.inst_results(call)[0]
        }
    }
}
