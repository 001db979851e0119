//! The parameter-file reader (TOML, SI units) on any text, against the study's vehicle: values
//! or an error naming the file and key, never a panic; values it accepts make a model.
#![no_main]
#![deny(warnings)]

mod common;

use common::vehicle8;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let model = vehicle8();
    if let Ok(values) = twv_ir::parse_params(text, "fuzz.toml", model.ir.params()) {
        assert_eq!(values.len(), model.ir.params().len());
        twv_ir::check_values(&values, "fuzz.toml", model.ir.params())
            .expect("values the reader accepts pass its own check");
    }
});
