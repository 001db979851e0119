//! The vehicles of `vehicles/paper.toml` with their parameters folded as compile-time constants.
//! Editing that file (or an IR file) and running `cargo build` rebuilds this crate with the new
//! constants: the macro `include_bytes!`es every file it reads. The tests compare these with the
//! runtime-parameter models of twv-generated bit for bit, and the kernel benchmark times both.

twv_macros::twv_model!(
    ir = "../../ir/vehicle8.json",
    name = Vehicle8,
    bake = "../../../vehicles/paper.toml"
);
twv_macros::twv_model!(
    ir = "../../ir/vehicle7.json",
    name = Vehicle7,
    bake = "../../../vehicles/paper.toml"
);
