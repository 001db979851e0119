//! The IR reader and validator on any text: an error or a valid IR, never a panic, an abort, a
//! hang or a huge allocation; a valid IR's functions then evaluate on the interpreter. The
//! content hash is recomputed first, so that mutations reach the checks behind it.
#![no_main]
#![deny(warnings)]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let text = twv_ir::rehash(text);
    let Ok(ir) = twv_ir::parse_ir(&text, "fuzz.json") else {
        return;
    };
    let (x, u, p) = (vec![0.1; ir.nx()], vec![0.0; ir.nu()], ir.defaults());
    for function in ir.functions().values() {
        let mut work = vec![0.0; function.n_values()];
        function
            .eval(&x, &u, &p, &mut work)
            .expect("work of n_values is enough");
    }
});
