//! Physics tests of the hand model: facts any correct model satisfies (docs/src/conventions.md).

// Index loops mirror the matrix formulas (M[i][j], J[i][j]) and read better than iterator chains.
#![allow(clippy::needless_range_loop)]

use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use twv_analysis::hand_model::scalar::*;
use twv_analysis::hand_model::*;
use twv_model::{Mechanical, Model};

fn load(file: &str) -> VehicleParams {
    let path = format!("{}/../vehicles/{file}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).expect("parameter file");
    let t: toml::Table = text.parse().expect("valid TOML");
    let num = |k: &str| t[k].as_float().expect(k);
    let arr = |k: &str| {
        let a = t[k].as_array().expect(k);
        [0, 1, 2].map(|i| a[i].as_float().expect(k))
    };
    VehicleParams {
        m1: num("m1"),
        m2: num("m2"),
        g: num("g"),
        a: num("a"),
        b: num("b"),
        c: num("c"),
        i1: arr("I1"),
        i2: arr("I2"),
        r: num("R"),
        m_w: num("m_w"),
        j_a: num("J_a"),
        j_d: num("J_d"),
    }
}

fn param_sets() -> [VehicleParams; 2] {
    [load("paper.toml"), load("segway.toml")]
}

/// The three models for one parameter set, with their "mirror" input maps.
struct Models {
    v8: HandVehicle8,
    v7: HandVehicle7,
    s7: HandSegway7,
}

fn models(p: VehicleParams) -> Models {
    Models {
        v8: HandVehicle8::new(p),
        v7: HandVehicle7::new(p),
        s7: HandSegway7::new(p),
    }
}

fn random_state<const NX: usize>(rng: &mut ChaCha8Rng) -> [f64; NX] {
    let mut x = [0.0; NX];
    x[0] = rng.gen_range(-3.1..3.1);
    x[1] = rng.gen_range(-5.0..5.0);
    x[2] = rng.gen_range(-5.0..5.0);
    x[3] = rng.gen_range(-3.1..3.1);
    for v in x.iter_mut().skip(4) {
        *v = rng.gen_range(-5.0..5.0);
    }
    x
}

fn random_input<const NU: usize>(rng: &mut ChaCha8Rng) -> [f64; NU] {
    [0.0; NU].map(|_| rng.gen_range(-50.0..50.0))
}

fn rk4<M: Model<NX, NU>, const NX: usize, const NU: usize>(
    m: &M,
    x: &mut [f64; NX],
    u: &[f64; NU],
    h: f64,
) {
    let add = |a: &[f64; NX], k: &[f64; NX], s: f64| {
        let mut o = *a;
        for (oi, ki) in o.iter_mut().zip(k.iter()) {
            *oi += s * ki;
        }
        o
    };
    let (mut k1, mut k2, mut k3, mut k4) = ([0.0; NX], [0.0; NX], [0.0; NX], [0.0; NX]);
    m.f(x, u, &mut k1);
    m.f(&add(x, &k1, 0.5 * h), u, &mut k2);
    m.f(&add(x, &k2, 0.5 * h), u, &mut k3);
    m.f(&add(x, &k3, h), u, &mut k4);
    for i in 0..NX {
        x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / (1.0 + a.abs().max(b.abs()))
}

// ---------------------------------------------------------------------------------------------
// Generic checks, run for every model and parameter set.

/// Dual-number Jacobians agree with central differences of f (validates the Dual arithmetic).
fn check_jacobians<M, const NX: usize, const NU: usize>(m: &M, rng: &mut ChaCha8Rng)
where
    M: Model<NX, NU>,
{
    for _ in 0..5 {
        let x: [f64; NX] = random_state(rng);
        let u: [f64; NU] = random_input(rng);
        let mut jx = [[0.0; NX]; NX];
        let mut ju = [[0.0; NU]; NX];
        m.jac_x(&x, &u, &mut jx);
        m.jac_u(&x, &u, &mut ju);
        for j in 0..NX {
            let h = 1e-6 * (1.0 + x[j].abs());
            let (mut xp, mut xm) = (x, x);
            xp[j] += h;
            xm[j] -= h;
            let (mut fp, mut fm) = ([0.0; NX], [0.0; NX]);
            m.f(&xp, &u, &mut fp);
            m.f(&xm, &u, &mut fm);
            for i in 0..NX {
                let fd = (fp[i] - fm[i]) / (2.0 * h);
                assert!(
                    rel(fd, jx[i][j]) < 1e-6,
                    "jac_x[{i}][{j}]: {fd} vs {}",
                    jx[i][j]
                );
            }
        }
        for j in 0..NU {
            let (mut up, mut um) = (u, u);
            up[j] += 1e-3;
            um[j] -= 1e-3;
            let (mut fp, mut fm) = ([0.0; NX], [0.0; NX]);
            m.f(&x, &up, &mut fp);
            m.f(&x, &um, &mut fm);
            for i in 0..NX {
                let fd = (fp[i] - fm[i]) / 2e-3;
                assert!(rel(fd, ju[i][j]) < 1e-8, "jac_u[{i}][{j}]");
            }
        }
        // The sparse view and J·w agree with the dense Jacobian.
        let nnz = m.jac_x_row().len();
        assert_eq!(m.jac_x_colind().len(), NX + 1);
        assert_eq!(nnz, NX * NX);
        let mut vals = vec![0.0; nnz];
        m.jac_x_sparse(&x, &u, &mut vals);
        for j in 0..NX {
            for k in m.jac_x_colind()[j]..m.jac_x_colind()[j + 1] {
                assert_eq!(vals[k], jx[m.jac_x_row()[k]][j]);
            }
        }
        let w: [[f64; NX]; 2] = [random_state(rng), random_state(rng)];
        let (mut f, mut jw) = ([0.0; NX], [[0.0; NX]; 2]);
        m.f_jw(&x, &u, &w, &mut f, &mut jw);
        for k in 0..2 {
            for i in 0..NX {
                let dense: f64 = (0..NX).map(|j| jx[i][j] * w[k][j]).sum();
                assert!(rel(dense, jw[k][i]) < 1e-12);
            }
        }
    }
}

/// Structural identities at random states: M symmetric, ½ pᵀ M p = T (M is the Hessian of the
/// body-by-body kinetic energy), pᵀ Cp = ½ pᵀ Ṁ p, dE/dt = Qᵀ p, mirror symmetry, and
/// independence of the base centroid height `a`.
fn check_identities<E, const NX: usize, const NU: usize, const NS: usize>(
    e: &E,
    with_a: &E,
    mirror_x: &[usize],
    mirror_u: fn([f64; NU]) -> [f64; NU],
    rng: &mut ChaCha8Rng,
) where
    E: HandEquations<NX, NU, NS> + Mechanical<NX, NU, NS>,
{
    for _ in 0..20 {
        let x: [f64; NX] = random_state(rng);
        let u: [f64; NU] = random_input(rng);
        let p = &x[4..];
        let mut m = [[0.0; NS]; NS];
        e.mass_matrix(&x, &mut m);
        let mut x0 = x;
        x0[4..].iter_mut().for_each(|v| *v = 0.0);
        let t = e.energy(&x) - e.energy(&x0);
        let mut half_pmp = 0.0;
        for i in 0..NS {
            for j in 0..NS {
                assert_eq!(m[i][j], m[j][i], "M symmetric");
                half_pmp += 0.5 * p[i] * m[i][j] * p[j];
            }
        }
        assert!(rel(half_pmp, t) < 1e-12, "½pᵀMp = {half_pmp}, T = {t}");

        let mut cp = [0.0; NS];
        e.cp(&x, &mut cp);
        let pcp: f64 = (0..NS).map(|i| p[i] * cp[i]).sum();
        let md = mass_rate(e, &x);
        let mut half_pmdp = 0.0;
        for i in 0..NS {
            for j in 0..NS {
                half_pmdp += 0.5 * p[i] * md[i][j] * p[j];
            }
        }
        assert!(
            rel(pcp, half_pmdp) < 1e-12,
            "pᵀCp = {pcp}, ½pᵀṀp = {half_pmdp}"
        );

        let mut q = [0.0; NS];
        e.input_forces(&x, &u, &mut q);
        let power: f64 = (0..NS).map(|i| q[i] * p[i]).sum();
        let de = energy_rate(e, &x, &u);
        assert!(rel(de, power) < 1e-10, "dE/dt = {de}, Qᵀp = {power}");

        let (mut f, mut fm, mut fa) = ([0.0; NX], [0.0; NX], [0.0; NX]);
        e.f(&x, &u, &mut f);
        let mut xm = x;
        for &i in mirror_x {
            xm[i] = -xm[i];
        }
        e.f(&xm, &mirror_u(u), &mut fm);
        for &i in mirror_x {
            fm[i] = -fm[i];
        }
        with_a.f(&x, &u, &mut fa);
        for i in 0..NX {
            assert!(rel(f[i], fm[i]) < 1e-12, "mirror symmetry, component {i}");
            assert_eq!(f[i], fa[i], "`a` must not enter the dynamics");
        }
    }
}

/// Worst relative energy error over 2 s with u = 0 from `x0` (RK4, h = 5e-4: the truncation
/// error is then ≈1e-10, well below the 1e-9 the tests demand).
fn energy_drift<M, const NX: usize, const NU: usize, const NS: usize>(m: &M, x0: [f64; NX]) -> f64
where
    M: Mechanical<NX, NU, NS>,
{
    let mut x = x0;
    let e0 = m.energy(&x0);
    let scale = e0.abs().max(
        (e0 - m.energy(&{
            let mut z = x0;
            z[4..].iter_mut().for_each(|v| *v = 0.0);
            z
        }))
        .abs(),
    );
    let mut worst: f64 = 0.0;
    for _ in 0..4000 {
        rk4(m, &mut x, &[0.0; NU], 5e-4);
        worst = worst.max((m.energy(&x) - e0).abs() / scale);
    }
    worst
}

/// Upright and hanging linearisations: ±λ (resp. ±iλ) and zeros, with
/// λ² = m_p g l M_x / (I_p M_x − m_p² l²). The pitch/forward block (Φ, w_y, v_x) is taken by
/// central differences of f; the full Jacobian (dual numbers) is checked too.
fn check_eigen<M, const NX: usize, const NU: usize>(m: &M, p: &VehicleParams, mx: f64)
where
    M: Model<NX, NU>,
{
    let ip = p.i2[1] + p.m2 * p.b * p.b;
    let ml = p.m2 * p.b;
    let lam = (ml * p.g * mx / (ip * mx - ml * ml)).sqrt();
    for (phi, hanging) in [(0.0, false), (std::f64::consts::PI, true)] {
        let mut x0 = [0.0; NX];
        x0[0] = phi;
        let u = [0.0; NU];
        let idx = [0, 4, 5];
        let mut block = DMatrix::zeros(3, 3);
        for (bj, &j) in idx.iter().enumerate() {
            let (mut xp, mut xm) = (x0, x0);
            xp[j] += 1e-6;
            xm[j] -= 1e-6;
            let (mut fp, mut fm) = ([0.0; NX], [0.0; NX]);
            m.f(&xp, &u, &mut fp);
            m.f(&xm, &u, &mut fm);
            for (bi, &i) in idx.iter().enumerate() {
                block[(bi, bj)] = (fp[i] - fm[i]) / 2e-6;
            }
        }
        let mut jac = [[0.0; NX]; NX];
        m.jac_x(&x0, &u, &mut jac);
        let full = DMatrix::from_fn(NX, NX, |i, j| jac[i][j]);
        for (ev, tol) in [
            (block.complex_eigenvalues(), 1e-7),
            (full.complex_eigenvalues(), 1e-10),
        ] {
            let mut parts: Vec<f64> = ev
                .iter()
                .map(|z| if hanging { z.im } else { z.re })
                .collect();
            parts.sort_by(f64::total_cmp);
            let n = parts.len();
            assert!(
                rel(parts[n - 1], lam) < tol,
                "{} vs λ = {lam}",
                parts[n - 1]
            );
            assert!(rel(parts[0], -lam) < tol, "{} vs −λ = {}", parts[0], -lam);
            for z in ev.iter() {
                let other = if hanging { z.re } else { z.im };
                assert!(
                    other.abs() < 1e-6 * lam,
                    "pure real (upright) / imaginary (hanging)"
                );
            }
            assert!(parts[1..n - 1].iter().all(|v| v.abs() < 1e-6));
        }
    }
}

fn mirror_vehicle(u: [f64; 2]) -> [f64; 2] {
    [u[0], -u[1]]
}

fn mirror_segway(u: [f64; 2]) -> [f64; 2] {
    [u[1], u[0]]
}

// ---------------------------------------------------------------------------------------------

#[test]
fn jacobians_match_central_differences() {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for p in param_sets() {
        let ms = models(p);
        check_jacobians(&ms.v8, &mut rng);
        check_jacobians(&ms.v7, &mut rng);
        check_jacobians(&ms.s7, &mut rng);
    }
}

#[test]
fn structural_identities_hold() {
    let mut rng = ChaCha8Rng::seed_from_u64(2);
    for p in param_sets() {
        let ms = models(p);
        let pa = VehicleParams { a: 3.7, ..p };
        let ma = models(pa);
        check_identities(&ms.v8, &ma.v8, &[2, 3, 6, 7], mirror_vehicle, &mut rng);
        check_identities(&ms.v7, &ma.v7, &[2, 3, 6], mirror_vehicle, &mut rng);
        check_identities(&ms.s7, &ma.s7, &[2, 3, 6], mirror_segway, &mut rng);
    }
}

#[test]
fn upright_and_hanging_eigenvalues() {
    for p in param_sets() {
        let ms = models(p);
        check_eigen(&ms.v8, &p, p.m1 + p.m2);
        check_eigen(&ms.v7, &p, p.m1 + p.m2);
        check_eigen(&ms.s7, &p, p.m2 + 2.0 * p.m_w + 2.0 * p.j_a / (p.r * p.r));
    }
}

#[test]
fn energy_is_conserved_with_zero_input() {
    let x8 = [1.2, 0.5, -0.3, 0.4, 1.5, 0.8, -0.6, 4.0];
    let x7 = [1.2, 0.5, -0.3, 0.4, 1.5, 0.8, 4.0];
    for p in param_sets() {
        let ms = models(p);
        let d8 = energy_drift(&ms.v8, x8);
        let d7 = energy_drift(&ms.v7, x7);
        let ds = energy_drift(&ms.s7, x7);
        assert!(
            d8 < 1e-9 && d7 < 1e-9 && ds < 1e-9,
            "drift {d8:e} {d7:e} {ds:e}"
        );
    }
}

#[test]
fn energy_change_equals_input_work() {
    for p in param_sets() {
        let m = HandSegway7::new(p);
        let u = [3.0, -1.5];
        let mut x = [0.3, 0.0, 0.0, 0.0, -0.5, 0.4, 1.0];
        let e0 = m.energy(&x);
        // Work ∫ Qᵀp dt by the trapezoid rule on a fine grid; Q is constant for constant u.
        let mut q = [0.0; 3];
        m.input_forces(&x, &u, &mut q);
        let power = |x: &[f64; 7]| q[0] * x[4] + q[1] * x[5] + q[2] * x[6];
        let mut work = 0.0;
        let h = 1e-4;
        for _ in 0..5000 {
            let p0 = power(&x);
            rk4(&m, &mut x, &u, h);
            work += 0.5 * h * (p0 + power(&x));
        }
        let de = m.energy(&x) - e0;
        assert!(
            (de - work).abs() < 1e-6 * (1.0 + work.abs()),
            "ΔE = {de}, W = {work}"
        );

        let m8 = HandVehicle8::new(p);
        let mut x8 = [0.3, 0.0, 0.0, 0.0, -0.5, 0.4, 0.2, 1.0];
        let u8 = [7.0, 2.0];
        let e0 = m8.energy(&x8);
        let mut work = 0.0;
        for _ in 0..5000 {
            let p0 = u8[0] * x8[5] + u8[1] * x8[7];
            rk4(&m8, &mut x8, &u8, h);
            work += 0.5 * h * (p0 + u8[0] * x8[5] + u8[1] * x8[7]);
        }
        let de = m8.energy(&x8) - e0;
        assert!(
            (de - work).abs() < 1e-6 * (1.0 + work.abs()),
            "ΔE = {de}, W = {work}"
        );
    }
}

#[test]
fn vehicle8_conserves_momentum() {
    for p in param_sets() {
        let m = HandVehicle8::new(p);
        let mut x = [1.2, 0.5, -0.3, 0.4, 1.5, 0.8, -0.6, 4.0];
        let h0 = m.momentum(&x);
        for _ in 0..4000 {
            rk4(&m, &mut x, &[0.0; 2], 2.5e-4);
        }
        let h1 = m.momentum(&x);
        for k in 0..3 {
            assert!(
                rel(h0[k], h1[k]) < 1e-9,
                "momentum {k}: {} → {}",
                h0[k],
                h1[k]
            );
        }
    }
}

#[test]
fn planar_motion_stays_planar() {
    let p = load("paper.toml");
    let mut x = [0.7, 0.0, 0.0, 0.0, 1.0, -0.5, 0.0, 0.0];
    let m = HandVehicle8::new(p);
    for _ in 0..500 {
        rk4(&m, &mut x, &[5.0, 0.0], 1e-3);
    }
    assert_eq!([x[2], x[3], x[6], x[7]], [0.0; 4]);
}

/// The constrained equations are the v_y-free rows of the unconstrained ones at v_y = 0, and the
/// Segway's wheels act as a base of mass 2(m_w + J_a/R²) and yaw inertia
/// 2 J_d + (m_w + J_a/R²) c²/2.
#[test]
fn models_are_consistent_with_each_other() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for p in param_sets() {
        let ms = models(p);
        let rolling = p.m_w + p.j_a / (p.r * p.r);
        let as_base = HandVehicle7::new(VehicleParams {
            m1: 2.0 * rolling,
            i1: [0.0, 0.0, 2.0 * p.j_d + 0.5 * rolling * p.c * p.c],
            ..p
        });
        for _ in 0..10 {
            let x7: [f64; 7] = random_state(&mut rng);
            let x8 = [x7[0], x7[1], x7[2], x7[3], x7[4], x7[5], 0.0, x7[6]];
            let (mut m8, mut m7, mut ms7, mut mb) =
                ([[0.0; 4]; 4], [[0.0; 3]; 3], [[0.0; 3]; 3], [[0.0; 3]; 3]);
            ms.v8.mass_matrix(&x8, &mut m8);
            ms.v7.mass_matrix(&x7, &mut m7);
            ms.s7.mass_matrix(&x7, &mut ms7);
            as_base.mass_matrix(&x7, &mut mb);
            let (mut c8, mut c7, mut cs, mut cb) = ([0.0; 4], [0.0; 3], [0.0; 3], [0.0; 3]);
            ms.v8.cp(&x8, &mut c8);
            ms.v7.cp(&x7, &mut c7);
            ms.s7.cp(&x7, &mut cs);
            as_base.cp(&x7, &mut cb);
            let rows = [0, 1, 3];
            for (i7, &i8) in rows.iter().enumerate() {
                assert!(rel(c7[i7], c8[i8]) < 1e-14);
                assert!(rel(cs[i7], cb[i7]) < 1e-14);
                for (j7, &j8) in rows.iter().enumerate() {
                    assert!(rel(m7[i7][j7], m8[i8][j8]) < 1e-14);
                    assert!(rel(ms7[i7][j7], mb[i7][j7]) < 1e-14);
                }
            }
        }
    }
}

/// The gyroscopic-pair mistake conserves energy (so an energy test cannot see it) yet changes the
/// equations; the gravity-sign mistake breaks energy and makes the upright stable.
#[test]
fn mistakes_are_wrong_in_the_documented_way() {
    let x7 = [1.2, 0.5, -0.3, 0.4, 1.5, 0.8, 4.0];
    for p in param_sets() {
        let good = HandVehicle7::new(p);
        let gyro = good.with_mistake(Mistake::DropGyroscopicPair);
        let grav = good.with_mistake(Mistake::FlipGravitySign);
        assert!(energy_drift(&gyro, x7) < 1e-9);
        assert!(energy_drift(&grav, x7) > 1e-3);
        let (mut fg, mut fw) = ([0.0; 7], [0.0; 7]);
        good.f(&x7, &[0.0; 2], &mut fg);
        gyro.f(&x7, &[0.0; 2], &mut fw);
        assert!((fg[5] - fw[5]).abs() > 1e-3 * fg[5].abs());
        assert!((fg[6] - fw[6]).abs() > 1e-3 * fg[6].abs());
        let (mut cg, mut cw) = ([0.0; 3], [0.0; 3]);
        good.cp(&x7, &mut cg);
        gyro.cp(&x7, &mut cw);
        assert_eq!(cg[0], cw[0], "the pitch row is untouched");
        let mut jac = [[0.0; 7]; 7];
        grav.jac_x(&[0.0; 7], &[0.0; 2], &mut jac);
        assert!(
            jac[4][0] < 0.0,
            "flipped gravity makes the upright a centre"
        );

        for m in [Mistake::DropGyroscopicPair, Mistake::FlipGravitySign] {
            let (mut a, mut b) = ([0.0; 8], [0.0; 8]);
            let x8 = [1.2, 0.5, -0.3, 0.4, 1.5, 0.8, -0.6, 4.0];
            HandVehicle8::new(p).f(&x8, &[0.0; 2], &mut a);
            HandVehicle8::new(p)
                .with_mistake(m)
                .f(&x8, &[0.0; 2], &mut b);
            assert_ne!(a, b);
            let (mut a, mut b) = ([0.0; 7], [0.0; 7]);
            HandSegway7::new(p).f(&x7, &[0.0; 2], &mut a);
            HandSegway7::new(p)
                .with_mistake(m)
                .f(&x7, &[0.0; 2], &mut b);
            assert_ne!(a, b);
        }
        assert!(
            energy_drift(
                &HandSegway7::new(p).with_mistake(Mistake::DropGyroscopicPair),
                x7
            ) < 1e-9
        );
    }
}

#[test]
fn non_finite_input_gives_non_finite_output() {
    let m = HandVehicle8::new(load("paper.toml"));
    let mut f = [0.0; 8];
    m.f(
        &[f64::NAN, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0],
        &[0.0; 2],
        &mut f,
    );
    assert!(f.iter().any(|v| v.is_nan()));
    let mut jac = [[0.0; 8]; 8];
    m.jac_x(
        &[0.0, 0.0, 0.0, 0.0, f64::INFINITY, 0.0, 0.0, 0.0],
        &[0.0; 2],
        &mut jac,
    );
    let singular = HandVehicle7::new(VehicleParams::from_array([0.0; 16]));
    let mut f7 = [0.0; 7];
    singular.f(&[0.1; 7], &[1.0; 2], &mut f7);
    assert!(f7[4..].iter().all(|v| !v.is_finite()));
}

#[test]
fn param_array_round_trips() {
    let p = load("segway.toml");
    assert_eq!(VehicleParams::from_array(p.to_array()), p);
    assert_eq!(HandVehicle7::new(p).info().params, &PARAM_NAMES);
}

// ---------------------------------------------------------------------------------------------
// A second, independent route inside the tests: ordinary Lagrange equations in the plain
// coordinates q (with wheel angles for the Segway), the Lagrangian written from N-frame centroid
// velocities, and the nonholonomic constraints enforced by multipliers:
//   M_q q̈ − Aᵀ λ = ∂L/∂q − (∂²L/∂q̇∂q) q̇ + Q_q,   A q̈ = b.
// The accelerations must equal the hand model's ṗ mapped back to q̈. This is what confirms the
// gyroscopic pair (the projection, not substitution) independently of the Poincaré derivation.

/// Pendulum (plus optional base) Lagrangian in N components; q = (Φ, x, y, θ, …).
fn pendulum_lagrangian(p: &VehicleParams, q: &[Dual], qd: &[Dual], base: bool) -> Dual {
    let (sp, cp) = (q[0].sin(), q[0].cos());
    let (st, ct) = (q[3].sin(), q[3].cos());
    let (phid, xd, yd, thd) = (qd[0], qd[1], qd[2], qd[3]);
    // r = (x + b sΦ cθ, y + b sΦ sθ, b cΦ), differentiated by hand.
    let vx = xd + cp * ct * phid * p.b - sp * st * thd * p.b;
    let vy = yd + cp * st * phid * p.b + sp * ct * thd * p.b;
    let vz = -(sp * phid * p.b);
    let (ox, oy, oz) = (-(sp * thd), phid, cp * thd);
    let mut l = (vx * vx + vy * vy + vz * vz) * (0.5 * p.m2)
        + ox * ox * (0.5 * p.i2[0])
        + oy * oy * (0.5 * p.i2[1])
        + oz * oz * (0.5 * p.i2[2])
        - cp * (p.m2 * p.g * p.b);
    if base {
        l = l + (xd * xd + yd * yd) * (0.5 * p.m1) + thd * thd * (0.5 * p.i1[2]);
    }
    l
}

/// Segway Lagrangian; q = (Φ, x, y, θ, ψ_L, ψ_R), ψ the wheel angles relative to A.
fn segway_lagrangian(p: &VehicleParams, q: &[Dual], qd: &[Dual]) -> Dual {
    let (st, ct) = (q[3].sin(), q[3].cos());
    let (xd, yd, thd) = (qd[1], qd[2], qd[3]);
    let h = 0.5 * p.c;
    // Wheel centres (x, y) ± (c/2)(−sθ, cθ).
    let (lx, ly) = (xd - ct * thd * h, yd - st * thd * h);
    let (rx, ry) = (xd + ct * thd * h, yd + st * thd * h);
    pendulum_lagrangian(p, q, qd, false)
        + (lx * lx + ly * ly + rx * rx + ry * ry) * (0.5 * p.m_w)
        + (qd[4] * qd[4] + qd[5] * qd[5]) * (0.5 * p.j_a)
        + thd * thd * p.j_d
}

fn lagrange_accel<const N: usize>(
    lag: &dyn Fn(&[Dual], &[Dual]) -> Dual,
    q: [f64; N],
    qd: [f64; N],
    force: [f64; N],
    a: DMatrix<f64>,
    b: Vec<f64>,
) -> [f64; N] {
    let grad = |q: [f64; N], qd: [f64; N], wrt_qd: bool| -> [f64; N] {
        let mut g = [0.0; N];
        for (j, gj) in g.iter_mut().enumerate() {
            let mut e = [0.0; N];
            e[j] = 1.0;
            let (qq, qv) = if wrt_qd {
                (constant(&q), seed(&qd, &e))
            } else {
                (seed(&q, &e), constant(&qd))
            };
            *gj = lag(&qq, &qv).d;
        }
        g
    };
    let k = b.len();
    let mut sys = DMatrix::zeros(N + k, N + k);
    let mut rhs = nalgebra::DVector::zeros(N + k);
    // ∂L/∂q̇ is linear in q̇: its central difference in q̇ is exact.
    for j in 0..N {
        let (mut up, mut dn) = (qd, qd);
        up[j] += 1.0;
        dn[j] -= 1.0;
        let (gp, gm) = (grad(q, up, true), grad(q, dn, true));
        for i in 0..N {
            sys[(i, j)] = 0.5 * (gp[i] - gm[i]);
        }
    }
    let h = 1e-5;
    let (mut qp, mut qm) = (q, q);
    for j in 0..N {
        qp[j] += h * qd[j];
        qm[j] -= h * qd[j];
    }
    let (gp, gm) = (grad(qp, qd, true), grad(qm, qd, true));
    let dl = grad(q, qd, false);
    for i in 0..N {
        rhs[i] = dl[i] - (gp[i] - gm[i]) / (2.0 * h) + force[i];
    }
    for r in 0..k {
        for j in 0..N {
            sys[(N + r, j)] = a[(r, j)];
            sys[(j, N + r)] = -a[(r, j)];
        }
        rhs[N + r] = b[r];
    }
    let z = sys.lu().solve(&rhs).expect("regular");
    let mut out = [0.0; N];
    for (i, o) in out.iter_mut().enumerate() {
        *o = z[i];
    }
    out
}

#[test]
fn lagrange_multiplier_route_agrees() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for p in param_sets() {
        for _ in 0..10 {
            // vehicle8: no constraint.
            let x: [f64; 8] = random_state(&mut rng);
            let u: [f64; 2] = random_input(&mut rng);
            let (st, ct) = x[3].sin_cos();
            let qd = [x[4], x[5] * ct - x[6] * st, x[5] * st + x[6] * ct, x[7]];
            let q = [x[0], x[1], x[2], x[3]];
            let force = [0.0, u[0] * ct, u[0] * st, u[1]];
            let lag = |q: &[Dual], qd: &[Dual]| pendulum_lagrangian(&p, q, qd, true);
            let qdd = lagrange_accel(&lag, q, qd, force, DMatrix::zeros(0, 4), vec![]);
            let mut f = [0.0; 8];
            HandVehicle8::new(p).f(&x, &u, &mut f);
            let pd = [
                qdd[0],
                qdd[1] * ct + qdd[2] * st + x[7] * x[6],
                -qdd[1] * st + qdd[2] * ct - x[7] * x[5],
                qdd[3],
            ];
            for i in 0..4 {
                assert!(
                    rel(pd[i], f[4 + i]) < 1e-7,
                    "vehicle8 ṗ[{i}]: {} vs {}",
                    pd[i],
                    f[4 + i]
                );
            }

            // vehicle7: the same Lagrangian, no side slip by a multiplier.
            let x7 = [x[0], x[1], x[2], x[3], x[4], x[5], x[7]];
            let qd = [x7[4], x7[5] * ct, x7[5] * st, x7[6]];
            let a = DMatrix::from_row_slice(1, 4, &[0.0, -st, ct, 0.0]);
            let qdd = lagrange_accel(&lag, q, qd, force, a, vec![x7[6] * x7[5]]);
            let pd = [qdd[0], qdd[1] * ct + qdd[2] * st, qdd[3]];
            let mut f = [0.0; 7];
            HandVehicle7::new(p).f(&x7, &u, &mut f);
            for i in 0..3 {
                assert!(
                    rel(pd[i], f[4 + i]) < 1e-7,
                    "vehicle7 ṗ[{i}]: {} vs {}",
                    pd[i],
                    f[4 + i]
                );
            }
            // ... and the mistaken model disagrees.
            HandVehicle7::new(p)
                .with_mistake(Mistake::DropGyroscopicPair)
                .f(&x7, &u, &mut f);
            assert!(rel(pd[1], f[5]) > 1e-6 || rel(pd[2], f[6]) > 1e-6);

            // segway7: wheel angles, rolling and no side slip by multipliers, motor torques on
            // the relative angles ψ − Φ.
            let h = 0.5 * p.c;
            let vxn = x7[5];
            let qd6 = [
                x7[4],
                vxn * ct,
                vxn * st,
                x7[6],
                (vxn - h * x7[6]) / p.r,
                (vxn + h * x7[6]) / p.r,
            ];
            let q6 = [x[0], x[1], x[2], x[3], 0.3, -1.1];
            let force6 = [-(u[0] + u[1]), 0.0, 0.0, 0.0, u[0], u[1]];
            #[rustfmt::skip]
            let a = DMatrix::from_row_slice(3, 6, &[
                0.0, -st, ct, 0.0, 0.0, 0.0,
                0.0, -ct, -st, h, p.r, 0.0,
                0.0, -ct, -st, -h, 0.0, p.r,
            ]);
            let lag6 = |q: &[Dual], qd: &[Dual]| segway_lagrangian(&p, q, qd);
            let qdd = lagrange_accel(&lag6, q6, qd6, force6, a, vec![vxn * x7[6], 0.0, 0.0]);
            let pd = [qdd[0], qdd[1] * ct + qdd[2] * st, qdd[3]];
            HandSegway7::new(p).f(&x7, &u, &mut f);
            for i in 0..3 {
                assert!(
                    rel(pd[i], f[4 + i]) < 1e-7,
                    "segway7 ṗ[{i}]: {} vs {}",
                    pd[i],
                    f[4 + i]
                );
            }
        }
    }
}
