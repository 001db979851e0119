// A malformed IR file is a compile error naming the file and the problem.
twv_macros::twv_model!(ir = "codegen/macros/tests/compile_fail/ir/bad_index.json", name = Model);

fn main() {}
