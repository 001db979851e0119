// A missing IR file is a compile error naming the file.
twv_macros::twv_model!(ir = "codegen/macros/tests/compile_fail/ir/no_such_file.json", name = Model);

fn main() {}
