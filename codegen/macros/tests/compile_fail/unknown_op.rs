// A malformed IR file is a compile error naming the file and the problem.
twv_macros::twv_model!(ir = "codegen/macros/tests/compile_fail/ir/unknown_op.json", name = Model);

fn main() {}
