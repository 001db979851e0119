//! Zero heap allocations in the hot methods (f, jac_x, jac_x_sparse, f_jw, f_jw_jac_u and its
//! eight-lane form) of generated, interpreted and JIT-compiled models, after construction (and,
//! for the JIT, after the first call that compiles each routine). Its own test
//! binary because it installs a counting global allocator; the counter is per thread so the test
//! harness's threads do not interfere.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use twv_ir::Interpreted;
use twv_model::Model;

struct Counting;

thread_local! {
    static ALLOCATIONS: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: forwards to the system allocator; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.with(|n| n.set(n.get() + 1));
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.with(|n| n.set(n.get() + 1));
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

fn allocations() -> usize {
    ALLOCATIONS.with(Cell::get)
}

/// Allocations made by the hot methods of `model` at one point.
fn hot_path_allocations<const NX: usize, const NU: usize>(model: &impl Model<NX, NU>) -> usize {
    let (x, u) = ([0.1; NX], [0.2; NU]);
    let w = [[0.3; NX]; 8];
    let (mut f, mut jac, mut jw) = ([0.0; NX], [[0.0; NX]; NX], [[0.0; NX]; 8]);
    let mut sparse = [0.0; 64];
    let mut ju = [[0.0; NU]; NX];
    const L: usize = twv_kernels::lanes::LANES;
    let (xl, ul, wl) = ([x; L], [u; L], [[0.3; NX]; L]);
    let (mut fl, mut jwl, mut jul) = ([[0.0; NX]; L], [[0.0; NX]; L], [[[0.0; NU]; NX]; L]);
    let (xa, ua, wa) = ([[0.1; L]; NX], [[0.2; L]; NU], [[0.3; L]; NX]);
    let (mut fa, mut jwa, mut jua) = ([[0.0; L]; NX], [[0.0; L]; NX], [[[0.0; L]; NU]; NX]);
    let before = allocations();
    model.f(&x, &u, &mut f);
    model.jac_x(&x, &u, &mut jac);
    model.jac_x_sparse(&x, &u, &mut sparse);
    model.f_jw(&x, &u, &w, &mut f, &mut jw);
    model.jw(&x, &u, &w, &mut jw);
    model.f_jw_jac_u(&x, &u, &w, &mut f, &mut jw, &mut ju);
    model.f_jw_jac_u_lanes(&xl, &ul, &wl, &mut fl, &mut jwl, &mut jul);
    model.f_jw_jac_u_lane_arrays(&xa, &ua, &wa, &mut fa, &mut jwa, &mut jua);
    let after = allocations();
    std::hint::black_box((&f, &jac, &jw, &sparse, &ju, &fl, &jwl, &jul));
    std::hint::black_box((&fa, &jwa, &jua));
    after - before
}

#[test]
fn generated_models_do_not_allocate() {
    assert_eq!(
        hot_path_allocations(&twv_generated::Vehicle8::with_defaults()),
        0
    );
    assert_eq!(
        hot_path_allocations(&twv_generated::Vehicle7::with_defaults()),
        0
    );
    assert_eq!(
        hot_path_allocations(&twv_generated::Segway7::with_defaults()),
        0
    );
    assert_eq!(
        hot_path_allocations(&twv_generated::Lorenz::with_defaults()),
        0
    );
    assert_eq!(hot_path_allocations(&twv_baked_paper::Vehicle8), 0);
}

#[test]
fn interpreted_models_do_not_allocate_after_construction() {
    let ir =
        twv_ir::parse_ir(twv_generated::ir_json("vehicle8").unwrap(), "vehicle8.json").unwrap();
    let model = Interpreted::<8, 2>::with_defaults(&ir).unwrap();
    assert_eq!(hot_path_allocations(&model), 0);
    let ir = twv_ir::parse_ir(twv_generated::ir_json("lorenz").unwrap(), "lorenz.json").unwrap();
    let model = Interpreted::<3, 0>::with_defaults(&ir).unwrap();
    assert_eq!(hot_path_allocations(&model), 0);
}

#[test]
fn jit_compiled_models_do_not_allocate_once_their_routines_exist() {
    for name in ["vehicle8", "lorenz"] {
        let ir = twv_ir::parse_ir(twv_generated::ir_json(name).unwrap(), name).unwrap();
        let native = twv_jit::compile(&ir).unwrap();
        let check = |model: &dyn Fn() -> usize| {
            // The first calls compile the routines they use (and allocate); later ones do not.
            assert!(model() > 0, "{name}: the first calls compile");
            assert_eq!(model(), 0, "{name}: calls after the first");
        };
        if name == "vehicle8" {
            let model =
                Interpreted::<8, 2>::with_native(&ir, &ir.defaults(), Some(native)).unwrap();
            check(&|| hot_path_allocations(&model));
        } else {
            let model =
                Interpreted::<3, 0>::with_native(&ir, &ir.defaults(), Some(native)).unwrap();
            check(&|| hot_path_allocations(&model));
        }
    }
}

/// The counter works: the zeros above are not vacuous.
#[test]
fn the_counter_counts() {
    let before = allocations();
    std::hint::black_box(vec![1.0_f64; 4]);
    assert!(allocations() > before);
}
