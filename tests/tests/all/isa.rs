//! Every generated kernel is built three times — for the x86-64 baseline, AVX2 and AVX-512 —
//! and `twv_kernels::isa` picks one at run time. Rust never fuses a multiplication and an
//! addition on its own (and FMA is not enabled), so the builds must give the same bits: checked
//! here for every kernel of every shipped model, runtime and baked, at random points (angles
//! beyond the inline sin/cos range included, so its C-library branch runs in every build), for
//! each build this CPU can run; the others are named as not run.

use crate::common::assert_bits;
use crate::common::baked;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use twv_generated::{HenonHeiles, Lorenz, Segway7, Vehicle7, Vehicle8};

fn random_point<const NX: usize, const NU: usize>(rng: &mut ChaCha8Rng) -> ([f64; NX], [f64; NU]) {
    // Mostly moderate states; every eighth point far out (|x| up to 1e7 reaches the C library
    // branch of twv_kernels::trig::sin_cos).
    let scale = if rng.gen_range(0..8) == 0 { 1e7 } else { 3.0 };
    (
        std::array::from_fn(|_| rng.gen_range(-scale..scale)),
        std::array::from_fn(|_| rng.gen_range(-50.0..50.0)),
    )
}

/// The dispatching kernels (the build of the instruction set in force) against the baseline
/// builds, at 500 random points, with 1, 2, NX and 11 tangent vectors (some entries ±0).
macro_rules! both_builds_agree {
    ($model:expr, $nx:literal, $nu:literal, $what:expr) => {{
        let m = $model;
        let what = $what;
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..500 {
            let (x, u) = random_point::<$nx, $nu>(&mut rng);
            let (mut a, mut b) = ([0.0; $nx], [0.0; $nx]);
            m.kernel_f(&x, &u, &mut a);
            m.kernel_f_baseline(&x, &u, &mut b);
            assert_bits(&a, &b, &format!("{what} f"));
            assert_bits(
                &m.kernel_jac_x(&x, &u),
                &m.kernel_jac_x_baseline(&x, &u),
                &format!("{what} jac_x"),
            );
            let (mut ja, mut jb) = ([[0.0; $nu]; $nx], [[0.0; $nu]; $nx]);
            m.kernel_jac_u(&x, &u, &mut ja);
            m.kernel_jac_u_baseline(&x, &u, &mut jb);
            assert_bits(
                ja.as_flattened(),
                jb.as_flattened(),
                &format!("{what} jac_u"),
            );
            let (ea, eb) = (
                m.kernel_f_jac_x(&x, &u, &mut a),
                m.kernel_f_jac_x_baseline(&x, &u, &mut b),
            );
            assert_bits(&ea, &eb, &format!("{what} f_jac_x entries"));
            assert_bits(&a, &b, &format!("{what} f_jac_x f"));
            // 11: a group of eight tangent vectors in lane arrays and three one by one.
            for k in [1, 2, $nx, 11] {
                let w: Vec<[f64; $nx]> = (0..k)
                    .map(|_| std::array::from_fn(|_| crate::codegen::tangent_entry(&mut rng)))
                    .collect();
                let (mut oa, mut ob) = (vec![[0.0; $nx]; k], vec![[0.0; $nx]; k]);
                let ta = m.kernel_variational(&x, &u, &w, &mut a, &mut oa, Some(&mut ja));
                let tb = m.kernel_variational_baseline(&x, &u, &w, &mut b, &mut ob, Some(&mut jb));
                let tag = format!("{what} variational K={k}");
                assert_bits(&a, &b, &format!("{tag} f"));
                assert_bits(oa.as_flattened(), ob.as_flattened(), &format!("{tag} J·W"));
                assert_bits(
                    ja.as_flattened(),
                    jb.as_flattened(),
                    &format!("{tag} jac_u"),
                );
                assert_bits(&[ta], &[tb], &format!("{tag} trace"));
            }
        }
    }};
}

/// Every lane of the lanes kernel, in the build of the instruction set in force, against the
/// one-point kernel at that lane's point (and the baseline lanes, and the lane-arrays form),
/// K = 1 with ∂f/∂u, at 100 random batches of 8 points.
macro_rules! lanes_agree_with_one_point {
    ($m:expr, $nx:literal, $nu:literal, $what:expr) => {{
        use twv_kernels::lanes::LANES;
        let (m, what) = (&$m, $what);
        let mut rng = ChaCha8Rng::seed_from_u64(13);
        for _ in 0..100 {
            let mut x = [[0.0; $nx]; LANES];
            let mut u = [[0.0; $nu]; LANES];
            for l in 0..LANES {
                (x[l], u[l]) = random_point::<$nx, $nu>(&mut rng);
            }
            let w: [[f64; $nx]; LANES] =
                std::array::from_fn(|_| std::array::from_fn(|_| rng.gen_range(-1.0..1.0)));
            let mut f = [[[0.0; $nx]; LANES]; 3];
            let mut out = [[[0.0; $nx]; LANES]; 3];
            let mut ju = [[[[0.0; $nu]; $nx]; LANES]; 3];
            {
                let ([f0, f1, f2], [o0, o1, o2], [j0, j1, j2]) = (&mut f, &mut out, &mut ju);
                m.kernel_variational_lanes(&x, &u, &w, f0, o0, j0);
                m.kernel_variational_lanes_baseline(&x, &u, &w, f1, o1, j1);
                // The lane-arrays form (entry-major, the maps' driver's), transposed back.
                use twv_kernels::lanes::{gather, gather_matrix, scatter, scatter_matrix};
                let (mut fa, mut oa) = ([[0.0; LANES]; $nx], [[0.0; LANES]; $nx]);
                let mut ja = gather_matrix(j2);
                m.kernel_variational_lane_arrays(
                    &gather(&x),
                    &gather(&u),
                    &gather(&w),
                    &mut fa,
                    &mut oa,
                    &mut ja,
                );
                (scatter(&fa, f2), scatter(&oa, o2), scatter_matrix(&ja, j2));
            }
            for l in 0..LANES {
                let (mut f1, mut o1, mut j1) = ([0.0; $nx], [[0.0; $nx]; 1], [[0.0; $nu]; $nx]);
                m.kernel_variational(&x[l], &u[l], &w[l..=l], &mut f1, &mut o1, Some(&mut j1));
                for build in 0..3 {
                    let tag = format!("{what} lanes (build {build}) lane {l}");
                    assert_bits(&f[build][l], &f1, &format!("{tag} f"));
                    assert_bits(&out[build][l], &o1[0], &format!("{tag} J·w"));
                    assert_bits(
                        ju[build][l].as_flattened(),
                        j1.as_flattened(),
                        &format!("{tag} jac_u"),
                    );
                }
            }
        }
    }};
}

/// `$check!(model, NX, NU, name)` for every shipped model, runtime and baked; `$what` names a
/// model for the messages.
macro_rules! every_shipped_model {
    ($check:ident, $what:expr) => {{
        $check!(Vehicle8::with_defaults(), 8, 2, $what("vehicle8"));
        $check!(baked::Vehicle8, 8, 2, $what("baked vehicle8"));
        $check!(Vehicle7::with_defaults(), 7, 2, $what("vehicle7"));
        $check!(baked::Vehicle7, 7, 2, $what("baked vehicle7"));
        $check!(Segway7::with_defaults(), 7, 2, $what("segway7"));
        $check!(baked::Segway7, 7, 2, $what("baked segway7"));
        $check!(Lorenz::with_defaults(), 3, 0, $what("lorenz"));
        $check!(baked::Lorenz, 3, 0, $what("baked lorenz"));
        $check!(HenonHeiles::with_defaults(), 4, 0, $what("henon_heiles"));
        $check!(baked::HenonHeiles, 4, 0, $what("baked henon_heiles"));
    }};
}

/// The lanes kernel of every shipped model, runtime and baked, in each build this CPU can run
/// (AVX-512, AVX2, NEON, one point at a time), has the one-point kernel's bits in every lane; the
/// builds it cannot run are named as not run.
#[test]
fn lanes_builds_have_the_one_point_bits_on_every_isa_here() {
    use twv_kernels::isa::Isa;
    on_each_build(
        &[Isa::Avx512, Isa::Avx2, Isa::Neon, Isa::Baseline],
        "lanes build",
        |isa| {
            let what = |m: &str| format!("{m} ({})", isa.name());
            every_shipped_model!(lanes_agree_with_one_point, what);
        },
    );
}

#[test]
fn every_build_agrees_with_the_baseline_bit_for_bit() {
    use twv_kernels::isa::Isa;
    isa_detection_matches_std_and_can_be_forced();
    // (The baseline build is what the others are compared with.)
    on_each_build(
        &[Isa::Avx512, Isa::Avx2],
        "build vs baseline comparison",
        |isa| {
            let what = |m: &str| format!("{m} ({})", isa.name());
            every_shipped_model!(both_builds_agree, what);
        },
    );
}

/// Runs `check` with each of `isas` in force that this CPU has, and says which did not run
/// (their builds would silently fall back to a lower one: running them would prove nothing).
fn on_each_build(
    isas: &[twv_kernels::isa::Isa],
    what: &str,
    check: impl Fn(twv_kernels::isa::Isa),
) {
    use twv_kernels::isa::{available, force, Isa};
    for &isa in isas {
        if !available(isa) {
            eprintln!(
                "SKIPPED: the {} {what} did not run: this CPU lacks {}",
                isa.name(),
                isa.name()
            );
            continue;
        }
        assert_eq!(force(isa), isa);
        check(isa);
    }
    force(Isa::Avx512);
}

/// The hand-written CPUID/XGETBV check (the model crate is `no_std`) says what std's says, for
/// AVX-512 and AVX2 (on aarch64: NEON), and `force_baseline` switches the choice both ways. Called at the start of the test above rather
/// than as a test of its own: a parallel test forcing the baseline would let the comparison
/// above run the baseline build twice.
fn isa_detection_matches_std_and_can_be_forced() {
    #[cfg(target_arch = "x86_64")]
    {
        let std_says = is_x86_feature_detected!("avx512f") && is_x86_feature_detected!("avx512vl");
        assert_eq!(twv_kernels::isa::avx512(), std_says);
        assert_eq!(twv_kernels::isa::avx2(), is_x86_feature_detected!("avx2"));
        twv_kernels::isa::force_baseline(true);
        assert!(!twv_kernels::isa::avx512());
        twv_kernels::isa::force_baseline(false);
        assert_eq!(twv_kernels::isa::avx512(), std_says);
    }
    #[cfg(target_arch = "aarch64")]
    {
        use twv_kernels::isa::{best, force, Isa};
        assert!(std::arch::is_aarch64_feature_detected!("neon"));
        assert_eq!((best(), twv_kernels::isa::neon()), (Isa::Neon, true));
        // The x86 limits fall back to the best this CPU has below them.
        assert_eq!(force(Isa::Avx512), Isa::Neon);
        twv_kernels::isa::force_baseline(true);
        assert!(!twv_kernels::isa::neon());
        twv_kernels::isa::force_baseline(false);
        assert!(twv_kernels::isa::neon());
    }
    #[cfg(target_arch = "x86_64")]
    // NEON is an aarch64 build: a limit of NEON is the baseline here.
    assert_eq!(
        twv_kernels::isa::force(twv_kernels::isa::Isa::Neon),
        twv_kernels::isa::Isa::Baseline
    );
    twv_kernels::isa::force_baseline(false);
}

/// The integrators' steps and the maps' lanes driver are built per instruction set only for
/// models compiled into the program: the constant that decides it is true for generated code,
/// false for an IR's own type (interpreter or JIT), and every field around a model passes its
/// model's on.
#[test]
fn only_compiled_in_models_get_builds_of_the_steps_per_instruction_set() {
    use twv_analysis::integrate::{OpenLoop, Projected, VectorField};
    use twv_ir::Interpreted;
    use twv_model::Model;

    fn field<F: VectorField<N>, const N: usize>(_: &F) -> bool {
        F::COMPILED_IN
    }
    fn model<M: Model<NX, NU>, const NX: usize, const NU: usize>(_: &M) -> bool {
        M::COMPILED_IN
    }

    let generated = Vehicle8::with_defaults();
    assert!(model(&generated));
    let open = OpenLoop::new(&generated, [0.0; 2]);
    assert!(field(&open) && field(&&open));
    assert!(field(&Projected {
        field: &open,
        keep: [true; 8]
    }));

    let ir = crate::codegen::shipped_ir("lorenz");
    let interpreted = Interpreted::<3, 0>::with_defaults(&ir).expect("3 states, no inputs");
    assert!(!model(&interpreted));
    let open = OpenLoop::new(&interpreted, []);
    assert!(!field(&open) && !field(&&open));
    assert!(!field(&Projected {
        field: &open,
        keep: [true; 3]
    }));
}

/// The lanes kernel given a state's (sin, cos) by its caller (the maps' driver, which needs the
/// pitch's for the sine setpoint) uses it: the pitch's own gives the kernel's bits, a perturbed
/// one changes f, and a state whose sine the kernel does not take is ignored.
#[test]
fn the_lanes_kernel_takes_a_given_states_sin_cos_and_only_where_it_uses_one() {
    use twv_kernels::lanes::{sin_cos, LANES};
    use twv_model::Model;
    let m = Vehicle8::with_defaults();
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let x: [[f64; LANES]; 8] =
        std::array::from_fn(|_| std::array::from_fn(|_| rng.gen_range(-1.0..1.0)));
    let u: [[f64; LANES]; 2] =
        std::array::from_fn(|_| std::array::from_fn(|_| rng.gen_range(-50.0..50.0)));
    let w: [[f64; LANES]; 8] =
        std::array::from_fn(|_| std::array::from_fn(|_| rng.gen_range(-1.0..1.0)));
    type Out = ([[f64; LANES]; 8], [[f64; LANES]; 8], [[[f64; LANES]; 2]; 8]);
    type SinCos = ([f64; LANES], [f64; LANES]);
    let run = |given: Option<(usize, SinCos)>| -> Out {
        let mut o: Out = ([[0.0; LANES]; 8], [[0.0; LANES]; 8], [[[0.0; LANES]; 2]; 8]);
        match given {
            Some((state, sc)) => m.f_jw_jac_u_lane_arrays_given(
                &x,
                &u,
                &w,
                &mut o.0,
                &mut o.1,
                &mut o.2,
                (state, &sc),
            ),
            None => m.f_jw_jac_u_lane_arrays(&x, &u, &w, &mut o.0, &mut o.1, &mut o.2),
        }
        o
    };
    let bits = |o: &Out| {
        (o.0.iter().chain(&o.1).chain(o.2.as_flattened()))
            .flatten()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    let own = run(None);
    // vehicle8's pitch φ is state 0, its heading state 3; state 1 (x) has no sine in it.
    for state in [0, 3] {
        assert_eq!(
            bits(&run(Some((state, sin_cos(x[state]))))),
            bits(&own),
            "state {state}"
        );
        let (mut s, c) = sin_cos(x[state]);
        s[2] += 1e-3;
        let moved = run(Some((state, (s, c))));
        assert_ne!(
            bits(&moved),
            bits(&own),
            "a changed sin of state {state} went unused"
        );
    }
    let (s, c) = sin_cos(x[1]);
    let ignored = run(Some((1, (s.map(|v| v + 0.5), c))));
    assert_eq!(
        bits(&ignored),
        bits(&own),
        "state 1's sine is not the kernel's"
    );
}
