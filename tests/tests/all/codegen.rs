//! Code generation audits: generated code vs the IR interpreter (bit for bit), vs CasADi's golden
//! values, vs finite differences; sparse vs dense Jacobians; J·W; baked vs runtime parameters;
//! and the clear errors of the IR validator, the parameter files and the macro.

use crate::common::assert_bits;
use crate::common::baked;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use twv_generated::{HenonHeiles, Lorenz, Segway7, Vehicle7, Vehicle8};
use twv_ir::{Interpreted, Ir};
use twv_model::{Mechanical, Model};

const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/..");

pub(crate) fn shipped_ir(name: &str) -> Ir {
    let text = twv_generated::ir_json(name).expect("shipped model");
    twv_ir::parse_ir(text, &format!("generated/ir/{name}.json")).expect("shipped IR is valid")
}

fn vehicle_params(ir: &Ir, file: &str) -> Vec<f64> {
    ir.load_params(format!("{ROOT}/vehicles/{file}"))
        .expect("shipped vehicle file is valid")
}

pub(crate) fn random_point<const NX: usize, const NU: usize>(
    rng: &mut ChaCha8Rng,
) -> ([f64; NX], [f64; NU]) {
    (
        std::array::from_fn(|_| rng.gen_range(-2.0..2.0)),
        std::array::from_fn(|_| rng.gen_range(-50.0..50.0)),
    )
}

/// K tangent vectors of [`tangent_entry`]s.
pub(crate) fn random_w<const NX: usize, const K: usize>(rng: &mut ChaCha8Rng) -> [[f64; NX]; K] {
    std::array::from_fn(|_| std::array::from_fn(|_| tangent_entry(rng)))
}

/// A tangent vector's entry: mostly in (-1, 1), one in eight an exact +0 or -0 (where a J·W
/// that summed other terms than the row form's could differ in the sign of a zero).
pub(crate) fn tangent_entry(rng: &mut ChaCha8Rng) -> f64 {
    match rng.gen_range(0..16) {
        0 => 0.0,
        1 => -0.0,
        _ => rng.gen_range(-1.0..1.0),
    }
}

#[track_caller]
fn assert_close(a: &[f64], b: &[f64], tol: f64, what: &str) {
    assert_eq!(a.len(), b.len(), "{what}: lengths");
    for (i, (x, y)) in a.iter().zip(b).enumerate() {
        let scale = 1f64.max(y.abs());
        assert!(
            (x - y).abs() <= tol * scale,
            "{what}[{i}]: {x:e} vs {y:e} (tol {tol:e})"
        );
    }
}

/// Every `Model` method of `a` and `b` agrees bit for bit at random points.
pub(crate) fn same_model<const NX: usize, const NU: usize>(
    a: &impl Model<NX, NU>,
    b: &impl Model<NX, NU>,
    what: &str,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    assert_eq!(a.jac_x_colind(), b.jac_x_colind(), "{what}: colind");
    assert_eq!(a.jac_x_row(), b.jac_x_row(), "{what}: row");
    let nnz = a.jac_x_row().len();
    for _ in 0..20 {
        let (x, u) = random_point::<NX, NU>(&mut rng);
        let (mut fa, mut fb) = ([0.0; NX], [0.0; NX]);
        a.f(&x, &u, &mut fa);
        b.f(&x, &u, &mut fb);
        assert_bits(&fa, &fb, &format!("{what} f"));
        let (mut ja, mut jb) = ([[0.0; NX]; NX], [[0.0; NX]; NX]);
        a.jac_x(&x, &u, &mut ja);
        b.jac_x(&x, &u, &mut jb);
        assert_bits(
            ja.as_flattened(),
            jb.as_flattened(),
            &format!("{what} jac_x"),
        );
        let (mut ua, mut ub) = ([[0.0; NU]; NX], [[0.0; NU]; NX]);
        a.jac_u(&x, &u, &mut ua);
        b.jac_u(&x, &u, &mut ub);
        assert_bits(
            ua.as_flattened(),
            ub.as_flattened(),
            &format!("{what} jac_u"),
        );
        let (mut sa, mut sb) = (vec![0.0; nnz], vec![0.0; nnz]);
        a.jac_x_sparse(&x, &u, &mut sa);
        b.jac_x_sparse(&x, &u, &mut sb);
        assert_bits(&sa, &sb, &format!("{what} jac_x_sparse"));
        let w = random_w::<NX, 3>(&mut rng);
        let (mut f2a, mut f2b, mut oa, mut ob) =
            ([0.0; NX], [0.0; NX], [[0.0; NX]; 3], [[0.0; NX]; 3]);
        a.f_jw(&x, &u, &w, &mut f2a, &mut oa);
        b.f_jw(&x, &u, &w, &mut f2b, &mut ob);
        assert_bits(&f2a, &f2b, &format!("{what} f_jw f"));
        assert_bits(
            oa.as_flattened(),
            ob.as_flattened(),
            &format!("{what} f_jw"),
        );
        // The trace for Σλ = ⟨tr J⟩, with f and J·W from the same evaluation.
        let (mut f4, mut o4) = ([0.0; NX], [[0.0; NX]; 3]);
        let trace_a = a.f_jw_trace(&x, &u, &w, &mut f4, &mut o4);
        let trace_b = b.f_jw_trace(&x, &u, &w, &mut f2b, &mut ob);
        assert_bits(&[trace_a], &[trace_b], &format!("{what} f_jw_trace trace"));
        assert_bits(&f4, &f2b, &format!("{what} f_jw_trace f"));
        assert_bits(
            o4.as_flattened(),
            ob.as_flattened(),
            &format!("{what} f_jw_trace jw"),
        );
        // The fused f_jw + jac_u (one kernel in generated code, two calls by default).
        let (mut f3, mut o3, mut u3) = ([0.0; NX], [[0.0; NX]; 3], [[0.0; NU]; NX]);
        a.f_jw_jac_u(&x, &u, &w, &mut f3, &mut o3, &mut u3);
        assert_bits(&f3, &f2b, &format!("{what} f_jw_jac_u f"));
        assert_bits(
            o3.as_flattened(),
            ob.as_flattened(),
            &format!("{what} f_jw_jac_u jw"),
        );
        assert_bits(
            u3.as_flattened(),
            ub.as_flattened(),
            &format!("{what} f_jw_jac_u jac_u"),
        );
    }
    // Eleven tangent vectors: a group of eight in lane arrays (generated code on a wide build)
    // and three one by one, against the interpreter's row form, some entries ±0.
    for _ in 0..20 {
        let (x, u) = random_point::<NX, NU>(&mut rng);
        let w = random_w::<NX, 11>(&mut rng);
        let (mut fa, mut fb, mut oa, mut ob) =
            ([0.0; NX], [0.0; NX], [[0.0; NX]; 11], [[0.0; NX]; 11]);
        a.f_jw(&x, &u, &w, &mut fa, &mut oa);
        b.f_jw(&x, &u, &w, &mut fb, &mut ob);
        assert_bits(
            oa.as_flattened(),
            ob.as_flattened(),
            &format!("{what} f_jw K=11"),
        );
    }
    // Eight points at once (generated: one instruction stream; interpreter: the trait's
    // default, one point after another).
    use twv_kernels::lanes::LANES;
    let mut x = [[0.0; NX]; LANES];
    let mut u = [[0.0; NU]; LANES];
    for l in 0..LANES {
        (x[l], u[l]) = random_point::<NX, NU>(&mut rng);
    }
    let w = random_w::<NX, LANES>(&mut rng);
    let (mut fa, mut oa, mut ja) = (
        [[0.0; NX]; LANES],
        [[0.0; NX]; LANES],
        [[[0.0; NU]; NX]; LANES],
    );
    let (mut fb, mut ob, mut jb) = (fa, oa, ja);
    a.f_jw_jac_u_lanes(&x, &u, &w, &mut fa, &mut oa, &mut ja);
    b.f_jw_jac_u_lanes(&x, &u, &w, &mut fb, &mut ob, &mut jb);
    assert_bits(
        fa.as_flattened(),
        fb.as_flattened(),
        &format!("{what} lanes f"),
    );
    assert_bits(
        oa.as_flattened(),
        ob.as_flattened(),
        &format!("{what} lanes J·w"),
    );
    assert_bits(
        ja.as_flattened().as_flattened(),
        jb.as_flattened().as_flattened(),
        &format!("{what} lanes jac_u"),
    );
}

/// Every `Mechanical` method of `a` and `b` agrees bit for bit at random points.
pub(crate) fn same_mechanics<const NX: usize, const NU: usize, const NS: usize>(
    a: &impl Mechanical<NX, NU, NS>,
    b: &impl Mechanical<NX, NU, NS>,
    what: &str,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for _ in 0..20 {
        let (x, u) = random_point::<NX, NU>(&mut rng);
        let (mut ma, mut mb) = ([[0.0; NS]; NS], [[0.0; NS]; NS]);
        a.mass_matrix(&x, &mut ma);
        b.mass_matrix(&x, &mut mb);
        assert_bits(ma.as_flattened(), mb.as_flattened(), &format!("{what} M"));
        let (mut va, mut vb) = ([0.0; NS], [0.0; NS]);
        a.cp(&x, &mut va);
        b.cp(&x, &mut vb);
        assert_bits(&va, &vb, &format!("{what} Cp"));
        a.gravity(&x, &mut va);
        b.gravity(&x, &mut vb);
        assert_bits(&va, &vb, &format!("{what} F"));
        a.input_forces(&x, &u, &mut va);
        b.input_forces(&x, &u, &mut vb);
        assert_bits(&va, &vb, &format!("{what} Q"));
        assert_bits(&[a.energy(&x)], &[b.energy(&x)], &format!("{what} energy"));
        assert_bits(
            &a.momentum(&x),
            &b.momentum(&x),
            &format!("{what} momentum"),
        );
    }
}

fn interpreted<const NX: usize, const NU: usize>(
    name: &str,
    params: &[f64],
) -> Interpreted<NX, NU> {
    Interpreted::new(&shipped_ir(name), params).expect("sizes match")
}

#[test]
fn generated_matches_interpreter_bit_for_bit() {
    let v8 = Vehicle8::with_defaults();
    same_model(
        &v8,
        &interpreted::<8, 2>("vehicle8", v8.params()),
        "vehicle8",
    );
    same_mechanics(
        &v8,
        &interpreted::<8, 2>("vehicle8", v8.params()),
        "vehicle8",
    );
    let v7 = Vehicle7::with_defaults();
    same_model(
        &v7,
        &interpreted::<7, 2>("vehicle7", v7.params()),
        "vehicle7",
    );
    same_mechanics(
        &v7,
        &interpreted::<7, 2>("vehicle7", v7.params()),
        "vehicle7",
    );
    let s7 = Segway7::with_defaults();
    same_model(&s7, &interpreted::<7, 2>("segway7", s7.params()), "segway7");
    same_mechanics(&s7, &interpreted::<7, 2>("segway7", s7.params()), "segway7");
    let lz = Lorenz::with_defaults();
    same_model(&lz, &interpreted::<3, 0>("lorenz", lz.params()), "lorenz");
    let hh = HenonHeiles::with_defaults();
    let hh_i = interpreted::<4, 0>("henon_heiles", hh.params());
    same_model(&hh, &hh_i, "henon_heiles");
    let x = [0.1, -0.2, 0.3, 0.05];
    assert_bits(
        &[hh.energy(&x)],
        &[Mechanical::<4, 0, 0>::energy(&hh_i, &x)],
        "henon_heiles energy",
    );
}

/// f and the stored entries of ∂f/∂x at CasADi's golden points (parameters at their defaults).
fn matches_golden<const NX: usize, const NU: usize>(model: &impl Model<NX, NU>, name: &str) {
    let ir = shipped_ir(name);
    assert!(!ir.golden().is_empty(), "{name}: no golden values");
    for (k, g) in ir.golden().iter().enumerate() {
        let x: [f64; NX] = g.x.as_slice().try_into().unwrap();
        let u: [f64; NU] = g.u.as_slice().try_into().unwrap();
        let mut f = [0.0; NX];
        model.f(&x, &u, &mut f);
        // f is dense in every shipped IR, so its stored entries are f itself.
        assert_close(&f, &g.f, 1e-12, &format!("{name} golden {k} f"));
        let mut j = vec![0.0; g.jac_x.len()];
        model.jac_x_sparse(&x, &u, &mut j);
        assert_close(&j, &g.jac_x, 1e-12, &format!("{name} golden {k} jac_x"));
    }
}

#[test]
fn generated_matches_casadi_golden_values() {
    matches_golden(&Vehicle8::with_defaults(), "vehicle8");
    matches_golden(&Vehicle7::with_defaults(), "vehicle7");
    matches_golden(&Segway7::with_defaults(), "segway7");
    matches_golden(&Lorenz::with_defaults(), "lorenz");
    matches_golden(&HenonHeiles::with_defaults(), "henon_heiles");
}

/// ∂f/∂x and ∂f/∂u against central differences, relative to the scale of the entry.
fn matches_finite_differences<const NX: usize, const NU: usize>(
    model: &impl Model<NX, NU>,
    what: &str,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let central = |x: &[f64; NX], u: &[f64; NU], dx: Option<usize>, du: Option<usize>, h: f64| {
        let (mut xp, mut xm, mut up, mut um) = (*x, *x, *u, *u);
        dx.map(|j| (xp[j] += h, xm[j] -= h));
        du.map(|j| (up[j] += h, um[j] -= h));
        let (mut fp, mut fm) = ([0.0; NX], [0.0; NX]);
        model.f(&xp, &up, &mut fp);
        model.f(&xm, &um, &mut fm);
        std::array::from_fn::<f64, NX, _>(|i| (fp[i] - fm[i]) / (2.0 * h))
    };
    for _ in 0..10 {
        let (x, u) = random_point::<NX, NU>(&mut rng);
        let (mut jx, mut ju) = ([[0.0; NX]; NX], [[0.0; NU]; NX]);
        model.jac_x(&x, &u, &mut jx);
        model.jac_u(&x, &u, &mut ju);
        for j in 0..NX {
            let fd = central(&x, &u, Some(j), None, 1e-6);
            let col: Vec<f64> = jx.iter().map(|row| row[j]).collect();
            assert_close(&col, &fd, 1e-6, &format!("{what} jac_x column {j}"));
        }
        for j in 0..NU {
            let fd = central(&x, &u, None, Some(j), 1e-4);
            let col: Vec<f64> = ju.iter().map(|row| row[j]).collect();
            assert_close(&col, &fd, 1e-6, &format!("{what} jac_u column {j}"));
        }
    }
}

#[test]
fn jacobians_match_central_differences() {
    matches_finite_differences(&Vehicle8::with_defaults(), "vehicle8");
    matches_finite_differences(&Vehicle7::with_defaults(), "vehicle7");
    matches_finite_differences(&Segway7::with_defaults(), "segway7");
    matches_finite_differences(&Lorenz::with_defaults(), "lorenz");
    matches_finite_differences(&HenonHeiles::with_defaults(), "henon_heiles");
}

/// The sparse Jacobian scattered by its CCS pattern is the dense one, and the dense one is zero
/// outside the pattern; f_jw equals f and the dense product J·W.
fn sparse_and_jw_match_dense<const NX: usize, const NU: usize>(
    model: &impl Model<NX, NU>,
    what: &str,
) {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let (colind, rows) = (model.jac_x_colind(), model.jac_x_row());
    assert_eq!(colind.len(), NX + 1, "{what}: colind length");
    for _ in 0..10 {
        let (x, u) = random_point::<NX, NU>(&mut rng);
        let mut dense = [[0.0; NX]; NX];
        model.jac_x(&x, &u, &mut dense);
        let mut values = vec![0.0; rows.len()];
        model.jac_x_sparse(&x, &u, &mut values);
        let mut scattered = [[0.0; NX]; NX];
        for j in 0..NX {
            for e in colind[j]..colind[j + 1] {
                scattered[rows[e]][j] = values[e];
            }
        }
        assert_bits(
            scattered.as_flattened(),
            dense.as_flattened(),
            &format!("{what} sparse vs dense"),
        );

        let w = random_w::<NX, 8>(&mut rng);
        let (mut f_jw, mut jw, mut f) = ([0.0; NX], [[0.0; NX]; 8], [0.0; NX]);
        model.f_jw(&x, &u, &w, &mut f_jw, &mut jw);
        model.f(&x, &u, &mut f);
        assert_bits(&f_jw, &f, &format!("{what} f_jw f"));
        let product: Vec<f64> = w
            .iter()
            .flat_map(|wk| {
                dense
                    .iter()
                    .map(move |row| row.iter().zip(wk).map(|(a, b)| a * b).sum::<f64>())
            })
            .collect();
        assert_close(
            jw.as_flattened(),
            &product,
            1e-12,
            &format!("{what} f_jw vs dense J·W"),
        );
        let mut jw_only = [[0.0; NX]; 8];
        model.jw(&x, &u, &w, &mut jw_only);
        assert_bits(
            jw_only.as_flattened(),
            jw.as_flattened(),
            &format!("{what} jw"),
        );
        // The fused kernel's trace is the dense Jacobian's diagonal sum, and its f and J·W are
        // those of f_jw.
        let (mut f_tr, mut jw_tr) = ([0.0; NX], [[0.0; NX]; 8]);
        let trace = model.f_jw_trace(&x, &u, &w, &mut f_tr, &mut jw_tr);
        let dense_trace: f64 = (0..NX).map(|i| dense[i][i]).sum();
        assert_close(
            &[trace],
            &[dense_trace],
            1e-15,
            &format!("{what} f_jw_trace trace"),
        );
        assert_bits(&f_tr, &f, &format!("{what} f_jw_trace f"));
        assert_bits(
            jw_tr.as_flattened(),
            jw.as_flattened(),
            &format!("{what} f_jw_trace J·W"),
        );
    }
}

/// The analysis dispatch runs a shipped model padded to the interpreter's 4 inputs, as one type
/// with the interpreted models of its state count: padded, every output is still its generated
/// kernel's bits, and the padding columns of ∂f/∂u are zero as the interpreter writes them, so
/// the padded model and the interpreter agree bit for bit on every method (lanes included).
#[test]
fn a_generated_model_padded_to_four_inputs_is_the_interpreter_bit_for_bit() {
    use twv_ir::MAX_NU;
    use twv_model::Padded;
    fn check<const NX: usize, const NU: usize, M: Model<NX, NU>>(model: M, params: &[f64]) {
        let name = model.info().name;
        let padded = Padded::<M, NU>(model);
        same_model(
            &padded,
            &interpreted::<NX, MAX_NU>(name, params),
            &format!("{name} padded"),
        );
    }
    let v8 = Vehicle8::with_defaults();
    check(v8, v8.params());
    let v7 = Vehicle7::with_defaults();
    check(v7, v7.params());
    let s7 = Segway7::with_defaults();
    check(s7, s7.params());
    let lz = Lorenz::with_defaults();
    check(lz, lz.params());
    let hh = HenonHeiles::with_defaults();
    check(hh, hh.params());
}

#[test]
fn sparse_jacobian_and_jw_match_dense() {
    sparse_and_jw_match_dense(&Vehicle8::with_defaults(), "vehicle8");
    sparse_and_jw_match_dense(&Vehicle7::with_defaults(), "vehicle7");
    sparse_and_jw_match_dense(&Segway7::with_defaults(), "segway7");
    sparse_and_jw_match_dense(&Lorenz::with_defaults(), "lorenz");
    sparse_and_jw_match_dense(&HenonHeiles::with_defaults(), "henon_heiles");
    let ir = shipped_ir("vehicle8");
    sparse_and_jw_match_dense(
        &Interpreted::<8, 2>::with_defaults(&ir).unwrap(),
        "vehicle8 interpreted",
    );
}

#[test]
fn baked_matches_runtime_bit_for_bit() {
    let paper = vehicle_params(&shipped_ir("vehicle8"), "paper.toml");
    assert_eq!(baked::Vehicle8::VALUES.as_slice(), paper.as_slice());
    let v8 = Vehicle8::new(paper.as_slice().try_into().unwrap());
    same_model(&baked::Vehicle8, &v8, "vehicle8 baked");
    same_mechanics(&baked::Vehicle8, &v8, "vehicle8 baked");
    let v7 = Vehicle7::new(
        vehicle_params(&shipped_ir("vehicle7"), "paper.toml")
            .try_into()
            .unwrap(),
    );
    same_model(&baked::Vehicle7, &v7, "vehicle7 baked");
    same_mechanics(&baked::Vehicle7, &v7, "vehicle7 baked");
    let s7 = Segway7::new(
        vehicle_params(&shipped_ir("segway7"), "segway.toml")
            .try_into()
            .unwrap(),
    );
    same_model(&baked::Segway7, &s7, "segway7 baked");
    same_mechanics(&baked::Segway7, &s7, "segway7 baked");
    same_model(&baked::Lorenz, &Lorenz::with_defaults(), "lorenz baked");
    same_model(
        &baked::HenonHeiles,
        &HenonHeiles::with_defaults(),
        "henon_heiles baked",
    );
}

#[test]
fn shipped_models_expose_sizes_and_metadata() {
    assert_eq!(
        (Vehicle8::NX, Vehicle8::NU, Vehicle8::NP, Vehicle8::NS),
        (8, 2, 16, 4)
    );
    assert_eq!((Vehicle7::NX, Vehicle7::NU, Vehicle7::NS), (7, 2, 3));
    assert_eq!((Segway7::NX, Segway7::NU, Segway7::NS), (7, 2, 3));
    assert_eq!(
        (Lorenz::NX, Lorenz::NU, Lorenz::NP, Lorenz::NS),
        (3, 0, 3, 0)
    );
    assert_eq!((HenonHeiles::NX, HenonHeiles::NP), (4, 0));
    assert_eq!(Vehicle8::PARAMS[9].name, "I2_xx");
    assert_eq!(Vehicle8::PARAMS[9].index, Some(0));
    assert_eq!(
        Vehicle8::with_defaults().info().ir_hash,
        shipped_ir("vehicle8").hash()
    );
    assert_eq!(
        baked::Segway7::PARAMS_SOURCE,
        "../../../vehicles/segway.toml"
    );
    for (name, _) in twv_generated::MODELS {
        let ir = shipped_ir(name);
        assert_eq!(ir.model(), name);
    }
}

/// `visit` hands each shipped model name to generic code as its concrete type.
#[test]
fn visit_dispatches_model_names() {
    struct Sizes;
    impl twv_generated::Visitor for Sizes {
        type Output = (&'static str, usize, usize);
        fn visit<const NX: usize, const NU: usize, M: Model<NX, NU>>(self, m: M) -> Self::Output {
            (m.info().name, NX, NU)
        }
    }
    assert_eq!(
        twv_generated::visit("vehicle7", None, Sizes).unwrap(),
        ("vehicle7", 7, 2)
    );
    assert_eq!(
        twv_generated::visit("lorenz", Some(&[10.0, 28.0, 2.5]), Sizes).unwrap(),
        ("lorenz", 3, 0)
    );
    assert!(twv_generated::visit("lorenz", Some(&[1.0]), Sizes).is_err());
    let err = twv_generated::visit("bicycle", None, Sizes).unwrap_err();
    assert!(err.to_string().contains("unknown model `bicycle`"), "{err}");
}

/// `visit_interpreted` hands an IR file's model to generic code with its sizes as constants.
#[test]
fn visit_interpreted_dispatches_ir_sizes() {
    struct FirstRate;
    impl twv_model::ModelVisitor for FirstRate {
        type Output = (usize, usize, f64);
        fn visit<const NX: usize, const NU: usize, M: Model<NX, NU>>(self, m: M) -> Self::Output {
            let mut f = [0.0; NX];
            m.f(&[0.1; NX], &[1.0; NU], &mut f);
            (NX, NU, f[NX - 1])
        }
    }
    let ir = shipped_ir("segway7");
    let (nx, nu, rate) = twv_ir::visit_interpreted(&ir, &ir.defaults(), None, FirstRate).unwrap();
    let mut f = [0.0; 7];
    Segway7::with_defaults().f(&[0.1; 7], &[1.0; 2], &mut f);
    // Every interpreted model gets MAX_NU inputs: segway7's two, then padding it never reads.
    assert_eq!(
        (nx, nu, rate.to_bits()),
        (7, twv_ir::MAX_NU, f[6].to_bits())
    );
    let err = twv_ir::visit_interpreted(&ir, &[1.0], None, FirstRate).unwrap_err();
    assert!(err.to_string().contains("16 parameters"), "{err}");
}

mod malformed_ir {
    use serde_json::{json, Value};
    use twv_ir::{parse_ir, InstrProblem, IrError, OutputProblem, Problem};

    const LORENZ: &str = include_str!("../../../generated/ir/lorenz.json");

    /// Lorenz's IR edited by `edit`, with a matching content hash (so the edit is what fails).
    fn edited(edit: impl FnOnce(&mut Value)) -> String {
        let mut ir: Value = serde_json::from_str(LORENZ).unwrap();
        edit(&mut ir);
        twv_ir::rehash(&serde_json::to_string_pretty(&ir).unwrap())
    }

    fn error(text: &str) -> IrError {
        let err = parse_ir(text, "bad.json").expect_err("must be rejected");
        assert!(
            err.to_string().starts_with("bad.json: "),
            "names the file: {err}"
        );
        err
    }

    #[test]
    fn the_shipped_file_and_a_rehashed_copy_are_accepted() {
        parse_ir(LORENZ, "lorenz.json").unwrap();
        parse_ir(&edited(|_| {}), "lorenz.json").unwrap();
    }

    #[test]
    fn wrong_format_version() {
        let err = error(&edited(|ir| ir["format"] = json!("twv-ir/2")));
        assert!(
            matches!(err.problem, Problem::Format { ref found } if found.contains("twv-ir/2")),
            "{err}"
        );
    }

    #[test]
    fn unknown_operation() {
        let err = error(&edited(|ir| {
            ir["functions"]["f"]["instructions"][3][1] = json!("frobnicate")
        }));
        let Problem::Instruction {
            function,
            index,
            problem,
        } = &err.problem
        else {
            panic!("{err}")
        };
        assert_eq!((function.as_str(), *index), ("f", 3));
        assert_eq!(problem, &InstrProblem::UnknownOp("frobnicate".into()));
        assert!(
            err.to_string().contains("unknown operation `frobnicate`"),
            "{err}"
        );
    }

    #[test]
    fn operand_not_earlier() {
        let err = error(&edited(|ir| {
            ir["functions"]["f"]["instructions"][3][2] = json!(5)
        }));
        assert!(
            matches!(
                err.problem,
                Problem::Instruction {
                    problem: InstrProblem::NotEarlier { .. },
                    ..
                }
            ),
            "{err}"
        );
        let err = error(&edited(|ir| {
            ir["functions"]["f"]["instructions"][3][2] = json!(3)
        }));
        assert!(
            matches!(
                err.problem,
                Problem::Instruction {
                    problem: InstrProblem::NotEarlier { .. },
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn input_index_out_of_range() {
        let err = error(&edited(|ir| {
            ir["functions"]["f"]["instructions"][0][3] = json!(3)
        }));
        assert!(
            matches!(
                err.problem,
                Problem::Instruction {
                    problem: InstrProblem::InputIndex {
                        arg: 2,
                        size: 3,
                        ..
                    },
                    ..
                }
            ),
            "{err}"
        );
        let err = error(&edited(|ir| {
            ir["functions"]["f"]["instructions"][0][2] = json!(4)
        }));
        assert!(
            matches!(
                err.problem,
                Problem::Instruction {
                    problem: InstrProblem::InputArg(_),
                    ..
                }
            ),
            "{err}"
        );
    }

    #[test]
    fn wrong_arity_and_malformed_instructions() {
        let err = error(&edited(|ir| {
            ir["functions"]["f"]["instructions"][3] = json!([3, "sub", 1])
        }));
        assert!(
            matches!(
                err.problem,
                Problem::Instruction {
                    problem: InstrProblem::Arity { .. },
                    ..
                }
            ),
            "{err}"
        );
        let err = error(&edited(|ir| {
            ir["functions"]["f"]["instructions"][3] = json!({"op": "sub"})
        }));
        assert!(
            matches!(
                err.problem,
                Problem::Instruction {
                    problem: InstrProblem::Malformed(_),
                    ..
                }
            ),
            "{err}"
        );
        let err = error(&edited(|ir| {
            ir["functions"]["f"]["instructions"][3][0] = json!(4)
        }));
        assert!(
            matches!(
                err.problem,
                Problem::Instruction {
                    problem: InstrProblem::Id { .. },
                    ..
                }
            ),
            "{err}"
        );
        let err = error(&edited(|ir| ir["functions"]["f"]["n_ops"] = json!(9)));
        assert!(matches!(err.problem, Problem::Function { .. }), "{err}");
    }

    fn output_problem(err: &IrError) -> &OutputProblem {
        match &err.problem {
            Problem::Output { problem, .. } => problem,
            _ => panic!("expected an output problem: {err}"),
        }
    }

    #[test]
    fn inconsistent_output_sparsity() {
        let out = |ir: &mut Value| ir["functions"]["jac_x"]["outputs"][0].clone();
        let err = error(&edited(|ir| {
            ir["functions"]["jac_x"]["outputs"][0]["colind"] = json!([0, 3, 8])
        }));
        assert!(
            matches!(
                output_problem(&err),
                OutputProblem::ColindLength {
                    expected: 4,
                    found: 3
                }
            ),
            "{err}"
        );
        let err = error(&edited(|ir| {
            ir["functions"]["jac_x"]["outputs"][0]["colind"] = json!([0, 3, 6, 7])
        }));
        assert!(
            matches!(output_problem(&err), OutputProblem::ColindOrder { .. }),
            "{err}"
        );
        let err = error(&edited(|ir| {
            ir["functions"]["jac_x"]["outputs"][0]["row"][2] = json!(3)
        }));
        assert!(
            matches!(
                output_problem(&err),
                OutputProblem::RowOutOfRange { row: 3, rows: 3 }
            ),
            "{err}"
        );
        let err = error(&edited(|ir| {
            ir["functions"]["jac_x"]["outputs"][0]["row"][2] = json!(1)
        }));
        assert!(
            matches!(output_problem(&err), OutputProblem::RowOrder { col: 0 }),
            "{err}"
        );
        let err = error(&edited(|ir| {
            let mut o = out(ir);
            o["values"].as_array_mut().unwrap().pop();
            ir["functions"]["jac_x"]["outputs"][0] = o;
        }));
        assert!(
            matches!(
                output_problem(&err),
                OutputProblem::ValuesLength {
                    expected: 8,
                    found: 7
                }
            ),
            "{err}"
        );
        let err = error(&edited(|ir| {
            ir["functions"]["jac_x"]["outputs"][0]["values"][0] = json!(11)
        }));
        assert!(
            matches!(
                output_problem(&err),
                OutputProblem::ValueOutOfRange { value: 11, .. }
            ),
            "{err}"
        );
    }

    #[test]
    fn shape_mismatch_and_missing_function() {
        let err = error(&edited(|ir| {
            ir["functions"]["f"]["outputs"][0]["rows"] = json!(4);
        }));
        assert!(
            matches!(
                output_problem(&err),
                OutputProblem::Shape { .. } | OutputProblem::RowOutOfRange { .. }
            ),
            "{err}"
        );
        let err = error(&edited(|ir| {
            ir["functions"]["f_jac_x"]["outputs"][1]["row"] = json!([0, 1, 2, 0, 1, 2, 0, 2]);
        }));
        assert!(
            matches!(output_problem(&err), OutputProblem::SparsityMismatch(_)),
            "{err}"
        );
        let err = error(&edited(|ir| {
            ir["functions"].as_object_mut().unwrap().remove("jac_u");
        }));
        assert_eq!(err.problem, Problem::MissingFunction("jac_u".into()));
    }

    #[test]
    fn truncated_and_malformed_json() {
        let err = error(&LORENZ[..LORENZ.len() / 2]);
        assert!(matches!(err.problem, Problem::Truncated { .. }), "{err}");
        let err = error(&LORENZ.replacen("\"model\"", "model", 1));
        assert!(
            matches!(err.problem, Problem::Json { line: 4, .. }),
            "{err}"
        );
        let err = error(&edited(|ir| ir["states"] = json!("x, y, z")));
        assert!(matches!(err.problem, Problem::Schema(_)), "{err}");
    }

    #[test]
    fn content_hash_mismatch() {
        let text = LORENZ.replace("Lorenz (1963) convection model.", "Edited by hand.");
        let err = error(&text);
        assert!(matches!(err.problem, Problem::HashMismatch { .. }), "{err}");
        assert!(err.to_string().contains("content hash mismatch"), "{err}");
        let text = LORENZ.replacen("sha256:c3", "sha256:zz", 1);
        assert!(matches!(error(&text).problem, Problem::MalformedHash(_)));
    }

    /// An IR whose ∂f/∂x is not the derivative of its f (one constant of `jac_x` edited, the
    /// hash recomputed) is refused at load, naming the entry.
    #[test]
    fn a_jacobian_that_disagrees_with_f_is_refused() {
        let value: Value = serde_json::from_str(LORENZ).unwrap();
        let ins = &value["functions"]["jac_x"]["instructions"];
        let k = ins
            .as_array()
            .unwrap()
            .iter()
            .position(|i| i[1] == "const" && i[2] == -1.0)
            .expect("∂ẏ/∂y = −1 is a constant");
        let mut edited = value.clone();
        edited["functions"]["jac_x"]["instructions"][k][2] = json!(-1.5);
        let text = twv_ir::rehash(&serde_json::to_string_pretty(&edited).unwrap());
        let err = error(&text);
        let msg = err.to_string();
        assert!(msg.contains("jac_x") && msg.contains("[y, y]"), "{msg}");
        assert!(msg.contains("central differences"), "{msg}");
    }

    /// Two equal keys in one object are refused (serde_json alone keeps the last silently).
    #[test]
    fn duplicate_keys_are_refused() {
        let text = LORENZ.replacen(
            "\"model\": \"lorenz\"",
            "\"model\": \"lorenz\", \"model\": \"x\"",
            1,
        );
        assert_ne!(text, LORENZ);
        let msg = error(&text).to_string();
        assert!(msg.contains("duplicate key `model`"), "{msg}");
    }

    #[test]
    fn interpreted_sizes_must_match() {
        let ir = parse_ir(LORENZ, "lorenz.json").unwrap();
        let err = twv_ir::Interpreted::<4, 0>::with_defaults(&ir).unwrap_err();
        assert!(
            err.to_string()
                .contains("lorenz.json: the model has 3 states, the caller expects 4"),
            "{err}"
        );
        // More inputs than the IR's are padding (zero columns of ∂f/∂u), fewer are an error.
        let padded = twv_ir::Interpreted::<3, 2>::with_defaults(&ir).unwrap();
        let mut ju = [[f64::NAN; 2]; 3];
        twv_model::Model::jac_u(&padded, &[1.0, 2.0, 3.0], &[5.0, 7.0], &mut ju);
        assert_eq!(ju, [[0.0; 2]; 3]);
        let segway = super::shipped_ir("segway7");
        let err = twv_ir::Interpreted::<7, 1>::with_defaults(&segway).unwrap_err();
        assert!(err.to_string().contains("2 inputs"), "{err}");
        assert!(twv_ir::Interpreted::<3, 0>::new(&ir, &[1.0, 2.0]).is_err());
        assert!(twv_ir::Interpreted::<3, 0>::new(&ir, &[1.0, f64::NAN, 2.0]).is_err());
    }
}

mod parameter_files {
    use twv_ir::{parse_params, ParamError, ParamProblem};

    const PAPER: &str = include_str!("../../../vehicles/paper.toml");

    fn params() -> Vec<twv_ir::Param> {
        super::shipped_ir("vehicle8").params().to_vec()
    }

    /// paper.toml with the line defining `key` replaced by `line`.
    fn with_line(key: &str, line: &str) -> String {
        PAPER
            .lines()
            .map(|l| {
                if l.starts_with(&format!("{key} ")) {
                    line
                } else {
                    l
                }
            })
            .collect::<Vec<_>>()
            .join("\n")
    }

    fn error(text: &str, mentions: &[&str]) -> ParamError {
        let err = parse_params(text, "my.toml", &params()).expect_err("must be rejected");
        let msg = err.to_string();
        assert!(msg.starts_with("my.toml: "), "names the file: {msg}");
        for m in mentions {
            assert!(msg.contains(m), "message mentions `{m}`: {msg}");
        }
        err
    }

    #[test]
    fn shipped_files_load() {
        let values = parse_params(PAPER, "paper.toml", &params()).unwrap();
        assert_eq!((values[0], values[9], values[11]), (115.0, 0.81, 0.03));
        let segway = include_str!("../../../vehicles/segway.toml");
        assert_eq!(
            parse_params(segway, "segway.toml", &params()).unwrap()[1],
            107.0
        );
    }

    #[test]
    fn unknown_and_missing_keys() {
        let err = error(&format!("{PAPER}\nmass = 3.0\n"), &["mass"]);
        assert_eq!(err.problem, ParamProblem::UnknownKey("mass".into()));
        let err = error(&with_line("m1", ""), &["m1"]);
        assert!(matches!(err.problem, ParamProblem::MissingKey { ref key, .. } if key == "m1"));
    }

    #[test]
    fn wrong_types() {
        let err = error(&with_line("m1", "m1 = \"heavy\""), &["m1", "heavy"]);
        assert!(matches!(err.problem, ParamProblem::WrongType { .. }));
        let err = error(&with_line("I2", "I2 = [0.81, 0.81]"), &["I2", "array of 3"]);
        assert!(matches!(err.problem, ParamProblem::WrongType { .. }));
        error(&with_line("g", "g = true"), &["g", "true"]);
    }

    #[test]
    fn non_finite_values() {
        let err = error(&with_line("b", "b = nan"), &["b", "NaN"]);
        assert!(matches!(err.problem, ParamProblem::NonFinite { .. }));
        error(
            &with_line("I2", "I2 = [0.81, inf, 0.03]"),
            &["I2_yy", "inf"],
        );
    }

    #[test]
    fn non_positive_mass_inertia_gravity() {
        let err = error(&with_line("m2", "m2 = 0.0"), &["m2", "mass", "0"]);
        assert!(matches!(err.problem, ParamProblem::NotPositive { .. }));
        error(&with_line("g", "g = -9.81"), &["g", "gravity", "-9.81"]);
        error(&with_line("I1", "I1 = [10.0, -1.0, 4.3]"), &["I1_yy", "-1"]);
        // A length may be zero or negative (a centroid below the axle), only finite.
        parse_params(&with_line("a", "a = -0.2"), "my.toml", &params()).unwrap();
    }

    #[test]
    fn inertia_triangle_inequality() {
        let err = error(
            &with_line("I2", "I2 = [0.1, 0.2, 0.5]"),
            &["I2", "triangle", "0.5"],
        );
        assert!(matches!(
            err.problem,
            ParamProblem::Triangle { index: 2, .. }
        ));
        // Equality is a flat body (a thin disc), allowed.
        parse_params(
            &with_line("I2", "I2 = [0.2, 0.3, 0.5]"),
            "my.toml",
            &params(),
        )
        .unwrap();
    }

    #[test]
    fn malformed_toml() {
        let err = error("m1 = = 3", &["malformed TOML"]);
        assert!(matches!(err.problem, ParamProblem::Syntax(_)));
    }
}

/// Every operation of twv-ir/1, emitted and interpreted, agrees bit for bit (NaN with NaN),
/// including those no shipped model uses yet. The fixture's output i applies operation i.
pub(crate) mod all_operations {
    use twv_ir::{BinaryOp, Interpreted, UnaryOp};
    use twv_model::Model;

    twv_macros::twv_model!(ir = "codegen/emit/tests/all_ops.json", name = AllOps);

    pub(crate) const NX: usize = 46;

    #[test]
    fn the_fixture_covers_every_operation() {
        let names: Vec<&str> = AllOps::INFO.states.to_vec();
        let all: Vec<&str> = UnaryOp::ALL
            .iter()
            .map(|o| o.name())
            .chain(BinaryOp::ALL.iter().map(|o| o.name()))
            .collect();
        assert_eq!(names, all);
    }

    /// The fixture's IR.
    pub(crate) fn fixture() -> twv_ir::Ir {
        twv_ir::load_ir(format!("{}/codegen/emit/tests/all_ops.json", super::ROOT)).unwrap()
    }

    #[test]
    fn every_operation_matches_the_interpreter() {
        let interpreted = Interpreted::<NX, 0>::with_defaults(&fixture()).unwrap();
        same_operations(&AllOps::with_defaults(), &interpreted, "generated");
    }

    /// `a` (named `what`) and the interpreter `b` agree on every operation of the fixture at
    /// every pair of sample operands (zeros of both signs, infinities, NaN, domain edges), NaN
    /// with NaN.
    pub(crate) fn same_operations(a: &impl Model<NX, 0>, b: &impl Model<NX, 0>, what: &str) {
        let samples = [
            -2.5,
            -1.0,
            -0.5,
            -0.0,
            0.0,
            0.3,
            0.5,
            0.99,
            1.0,
            1.5,
            3.0,
            1e300,
            f64::INFINITY,
            f64::NAN,
        ];
        for shift in 0..samples.len() {
            for equal_neighbours in [false, true] {
                let x: [f64; NX] = std::array::from_fn(|i| {
                    let k = if equal_neighbours { shift } else { i + shift };
                    samples[k % samples.len()]
                });
                let (mut fa, mut fb) = ([0.0; NX], [0.0; NX]);
                a.f(&x, &[], &mut fa);
                b.f(&x, &[], &mut fb);
                for i in 0..NX {
                    let same =
                        fa[i].to_bits() == fb[i].to_bits() || (fa[i].is_nan() && fb[i].is_nan());
                    assert!(
                        same,
                        "{} at {:?}: {what} {:e}, interpreted {:e}",
                        AllOps::INFO.states[i],
                        (x[i], x[(i + 1) % NX]),
                        fa[i],
                        fb[i]
                    );
                }
            }
        }
    }
}

/// The report prints the IR's functions as formulas; for Lorenz they are the textbook ones.
#[test]
fn formulas_print_the_textbook_equations() {
    let ir = shipped_ir("lorenz");
    let names: Vec<String> = ir.states().iter().map(|s| s.name.clone()).collect();
    let f = twv_ir::formulas(&ir, ir.function("f").unwrap(), &names, &[]);
    assert!(f.temporaries.is_empty() || f.temporaries.iter().all(|(n, _)| n.starts_with('t')));
    let text: Vec<String> = f
        .entries
        .iter()
        .map(|(l, e)| format!("{l} = {e}"))
        .collect();
    let expanded: Vec<String> = text
        .iter()
        .map(|line| {
            f.temporaries.iter().fold(line.clone(), |acc, (n, e)| {
                acc.replace(n.as_str(), &format!("({e})"))
            })
        })
        .collect();
    assert_eq!(
        expanded,
        [
            "f[x] = sigma*(y - x)",
            "f[y] = x*(rho - z) - y",
            "f[z] = x*y - beta*z"
        ],
        "{text:?}"
    );
    let ir = shipped_ir("vehicle8");
    let speeds: Vec<String> = ir.states()[4..].iter().map(|s| s.name.clone()).collect();
    let gravity = twv_ir::formulas(&ir, ir.function("F").unwrap(), &speeds, &[]);
    assert_eq!(gravity.entries[0].0, "F[w_y]");
    assert!(gravity.entries[0].1.contains("sin(phi)") && gravity.entries[0].1.contains("m2"));
}
