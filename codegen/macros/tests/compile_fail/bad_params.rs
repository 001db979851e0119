// A baked parameter file with a bad value is a compile error naming the file and the field.
twv_macros::twv_model!(ir = "generated/ir/lorenz.json", name = Model, bake = "codegen/macros/tests/compile_fail/bad_params.toml");

fn main() {}
