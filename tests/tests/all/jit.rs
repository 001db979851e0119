//! The JIT (`twv-jit`: an IR compiled to native code at run time) against the interpreter, the
//! reference: every shipped model's equations, Jacobians and mechanics, and every operation of
//! twv-ir/1 at edge-case operands, agree bit for bit; a model is never run with code compiled
//! from another IR.

use std::sync::Arc;

use twv_ir::{Interpreted, ModelError, NativeCode};
use twv_model::Model;

use crate::codegen::all_operations::{fixture, same_operations, NX as ALL_OPS_NX};
use crate::codegen::{random_point, random_w, same_mechanics, same_model, shipped_ir};

/// The JIT-compiled and the interpreted model of shipped model `name` (its IR defaults).
fn pair<const NX: usize, const NU: usize>(
    name: &str,
) -> (Interpreted<NX, NU>, Interpreted<NX, NU>) {
    let text = twv_generated::shipped_ir_json(name).expect("a shipped model");
    let ir = twv_ir::parse_ir(text, &format!("generated/ir/{name}.json")).unwrap();
    let native: Arc<dyn NativeCode> = twv_jit::compile(&ir).unwrap();
    let jit = Interpreted::with_native(&ir, &ir.defaults(), Some(native)).unwrap();
    let interpreted = Interpreted::new(&ir, &ir.defaults()).unwrap();
    assert!(jit.is_native() && !interpreted.is_native());
    (jit, interpreted)
}

/// f + J·W of `a` and `b` for `K` tangent vectors at random points, bit for bit.
fn same_jw<const NX: usize, const NU: usize, const K: usize>(
    a: &Interpreted<NX, NU>,
    b: &Interpreted<NX, NU>,
    what: &str,
) {
    use rand::SeedableRng;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(K as u64);
    for _ in 0..50 {
        let (x, u) = random_point::<NX, NU>(&mut rng);
        let w = random_w::<NX, K>(&mut rng);
        let (mut fa, mut fb, mut oa, mut ob) =
            ([0.0; NX], [0.0; NX], [[0.0; NX]; K], [[0.0; NX]; K]);
        let ta = a.f_jw_trace(&x, &u, &w, &mut fa, &mut oa);
        let tb = b.f_jw_trace(&x, &u, &w, &mut fb, &mut ob);
        let bits = |v: &[f64]| v.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&fa), bits(&fb), "{what} K = {K}: f");
        assert_eq!(
            bits(oa.as_flattened()),
            bits(ob.as_flattened()),
            "{what} K = {K}: J·W"
        );
        assert_eq!(ta.to_bits(), tb.to_bits(), "{what} K = {K}: trace");
    }
}

/// The JIT writes J·W out for each count up to 16 and loops beyond: both against the
/// interpreter, for a small model (Lorenz) and a vehicle.
#[test]
fn written_out_and_looped_jw_have_the_interpreter_bits() {
    let (a, b) = pair::<3, 0>("lorenz");
    same_jw::<3, 0, 1>(&a, &b, "lorenz");
    same_jw::<3, 0, 16>(&a, &b, "lorenz");
    same_jw::<3, 0, 17>(&a, &b, "lorenz");
    let (a, b) = pair::<8, 2>("vehicle8");
    same_jw::<8, 2, 1>(&a, &b, "vehicle8");
    same_jw::<8, 2, 8>(&a, &b, "vehicle8");
    same_jw::<8, 2, 20>(&a, &b, "vehicle8");
}

#[test]
fn compiled_models_have_the_interpreter_bits() {
    let (a, b) = pair::<8, 2>("vehicle8");
    same_model(&a, &b, "vehicle8 JIT");
    same_mechanics::<8, 2, 4>(&a, &b, "vehicle8 JIT");
    let (a, b) = pair::<7, 2>("vehicle7");
    same_model(&a, &b, "vehicle7 JIT");
    same_mechanics::<7, 2, 4>(&a, &b, "vehicle7 JIT");
    let (a, b) = pair::<7, 2>("segway7");
    same_model(&a, &b, "segway7 JIT");
    let (a, b) = pair::<3, 0>("lorenz");
    same_model(&a, &b, "lorenz JIT");
    let (a, b) = pair::<4, 0>("henon_heiles");
    same_model(&a, &b, "henon_heiles JIT");
    // The bicycle: 33 040 instructions in f_jac_x, nine states.
    let (a, b) = pair::<9, 2>("whipple");
    same_model(&a, &b, "whipple JIT");
}

#[test]
fn every_operation_has_the_interpreter_bits() {
    let ir = fixture();
    let jit = Interpreted::<ALL_OPS_NX, 0>::with_native(
        &ir,
        &ir.defaults(),
        Some(twv_jit::compile(&ir).unwrap()),
    )
    .unwrap();
    let interpreted = Interpreted::<ALL_OPS_NX, 0>::with_defaults(&ir).unwrap();
    same_operations(&jit, &interpreted, "JIT");
}

#[test]
fn code_compiled_from_another_ir_is_refused() {
    let lorenz = shipped_ir("lorenz");
    let vehicle = shipped_ir("vehicle8");
    let native = twv_jit::compile(&lorenz).unwrap();
    let err =
        Interpreted::<8, 2>::with_native(&vehicle, &vehicle.defaults(), Some(native)).unwrap_err();
    assert!(
        matches!(&err, ModelError::NativeCode { compiled, ir, .. }
            if compiled == lorenz.hash() && ir == vehicle.hash()),
        "{err}"
    );
}
