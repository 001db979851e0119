//! `twv_model!` turns every problem with its files into a `compile_error!` naming the file and
//! the problem: wrong version, unknown op, bad index, truncated JSON, a bad parameter, no file.
//! The IR fixtures are copies of lorenz.json with one defect each (compile_fail/ir/).

#[test]
fn macro_errors_are_compile_errors() {
    trybuild::TestCases::new().compile_fail("tests/compile_fail/*.rs");
}
