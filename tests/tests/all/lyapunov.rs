//! Integrators and Lyapunov spectra on reference systems with known answers.
//!
//! The test models are tiny hand-written `twv_model::Model`s (an `Explicit` system wrapped in
//! `Ode`); the generated explicit-ODE models will replace them.

use std::time::Instant;

use twv_analysis::integrate::{
    ClosedLoop, Dopri5, DopriOptions, IntegrateError, LinearStateFeedback, OpenLoop, Rk4, Stepper,
    StopReason, VarState, VectorField,
};
use twv_analysis::lyapunov::{
    lyapunov_spectrum, Classification, InitialBasis, IntegratorChoice, LyapunovError,
    LyapunovResult, LyapunovSettings,
};
use twv_model::{Model, ModelInfo};

// ---------------------------------------------------------------------------------------------
// Test models

/// An explicit system ẋ = f(x, u) with dense Jacobians; `Ode` turns it into a `Model`.
trait Explicit<const N: usize, const NU: usize> {
    fn f(&self, x: &[f64; N], u: &[f64; NU]) -> [f64; N];
    fn jac_x(&self, x: &[f64; N], u: &[f64; NU]) -> [[f64; N]; N];
    fn jac_u(&self, _x: &[f64; N], _u: &[f64; NU]) -> [[f64; NU]; N] {
        [[0.0; NU]; N]
    }
}

/// A `Model` from an `Explicit` system (dense sparsity pattern; J·w by a dense product).
struct Ode<S> {
    sys: S,
    colind: Vec<usize>,
    row: Vec<usize>,
}

impl<S> Ode<S> {
    fn new<const N: usize>(sys: S) -> Self {
        Self {
            sys,
            colind: (0..=N).map(|j| j * N).collect(),
            row: (0..N * N).map(|k| k % N).collect(),
        }
    }
}

impl<S: Explicit<N, NU>, const N: usize, const NU: usize> Model<N, NU> for Ode<S> {
    fn info(&self) -> ModelInfo {
        ModelInfo {
            name: "test",
            ir_hash: "",
            states: &[],
            inputs: &[],
            params: &[],
        }
    }
    fn f(&self, x: &[f64; N], u: &[f64; NU], out: &mut [f64; N]) {
        *out = self.sys.f(x, u);
    }
    fn jac_x(&self, x: &[f64; N], u: &[f64; NU], out: &mut [[f64; N]; N]) {
        *out = self.sys.jac_x(x, u);
    }
    fn jac_u(&self, x: &[f64; N], u: &[f64; NU], out: &mut [[f64; NU]; N]) {
        *out = self.sys.jac_u(x, u);
    }
    fn jac_x_colind(&self) -> &[usize] {
        &self.colind
    }
    fn jac_x_row(&self) -> &[usize] {
        &self.row
    }
    fn jac_x_sparse(&self, x: &[f64; N], u: &[f64; NU], values: &mut [f64]) {
        let j = self.sys.jac_x(x, u);
        for (k, v) in values.iter_mut().enumerate().take(N * N) {
            *v = j[k % N][k / N];
        }
    }
    fn f_jw<const K: usize>(
        &self,
        x: &[f64; N],
        u: &[f64; NU],
        w: &[[f64; N]; K],
        f: &mut [f64; N],
        out: &mut [[f64; N]; K],
    ) {
        *f = self.sys.f(x, u);
        let j = self.sys.jac_x(x, u);
        for (o, wk) in out.iter_mut().zip(w) {
            for (oi, ji) in o.iter_mut().zip(&j) {
                *oi = ji.iter().zip(wk).map(|(a, b)| a * b).sum();
            }
        }
    }
}

// The validation systems are the shipped explicit-ODE models, through the same pipeline as the
// vehicles (modeling -> IR -> generated code): twv_generated::{Lorenz, HenonHeiles}.

fn hh_energy(s: &[f64; 4]) -> f64 {
    let [x, y, px, py] = *s;
    0.5 * (px * px + py * py) + 0.5 * (x * x + y * y) + x * x * y - y * y * y / 3.0
}

/// An unstable linear chain with one input: ẋ = A x + B u, A in companion form with
/// characteristic polynomial s³ − 0.5 s² + 2 s − 1, B = e₃.
struct Chain;
const CHAIN_A: [[f64; 3]; 3] = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, -2.0, 0.5]];
impl Explicit<3, 1> for Chain {
    fn f(&self, x: &[f64; 3], u: &[f64; 1]) -> [f64; 3] {
        let ax = CHAIN_A.map(|r| r.iter().zip(x).map(|(a, b)| a * b).sum::<f64>());
        [ax[0], ax[1], ax[2] + u[0]]
    }
    fn jac_x(&self, _: &[f64; 3], _: &[f64; 1]) -> [[f64; 3]; 3] {
        CHAIN_A
    }
    fn jac_u(&self, _: &[f64; 3], _: &[f64; 1]) -> [[f64; 1]; 3] {
        [[0.0], [0.0], [1.0]]
    }
}

/// ẋ = s x²: x(t) = x0 / (1 − s x0 t), tangent w(t) = w0 / (1 − s x0 t)².
struct Riccati(f64);
impl Explicit<1, 0> for Riccati {
    fn f(&self, x: &[f64; 1], _: &[f64; 0]) -> [f64; 1] {
        [self.0 * x[0] * x[0]]
    }
    fn jac_x(&self, x: &[f64; 1], _: &[f64; 0]) -> [[f64; 1]; 1] {
        [[2.0 * self.0 * x[0]]]
    }
}

/// The harmonic oscillator q̈ = −q: a rotation, also for the tangents.
struct Oscillator;
impl Explicit<2, 0> for Oscillator {
    fn f(&self, x: &[f64; 2], _: &[f64; 0]) -> [f64; 2] {
        [x[1], -x[0]]
    }
    fn jac_x(&self, _: &[f64; 2], _: &[f64; 0]) -> [[f64; 2]; 2] {
        [[0.0, 1.0], [-1.0, 0.0]]
    }
}

/// Rössler's hyperchaotic system (Rössler 1979), a = 0.25, b = 3, c = 0.5, d = 0.05:
/// ẋ = −y − z, ẏ = x + a y + w, ż = b + x z, ẇ = −c z + d w. Two positive exponents
/// (≈ 0.11 and 0.02), one zero and one strongly negative (≈ −25).
struct HyperRossler;
impl Explicit<4, 0> for HyperRossler {
    fn f(&self, s: &[f64; 4], _: &[f64; 0]) -> [f64; 4] {
        let [x, y, z, w] = *s;
        [-y - z, x + 0.25 * y + w, 3.0 + x * z, -0.5 * z + 0.05 * w]
    }
    fn jac_x(&self, s: &[f64; 4], _: &[f64; 0]) -> [[f64; 4]; 4] {
        let [x, _, z, _] = *s;
        [
            [0.0, -1.0, -1.0, 0.0],
            [1.0, 0.25, 0.0, 1.0],
            [z, 0.0, x, 0.0],
            [0.0, 0.0, -0.5, 0.05],
        ]
    }
}

// ---------------------------------------------------------------------------------------------
// Helpers

fn settings(h: f64, t_sample: f64, iterations: usize, transient: f64) -> LyapunovSettings {
    LyapunovSettings {
        t_sample,
        iterations,
        transient,
        integrator: IntegratorChoice::Rk4 { h },
        ..LyapunovSettings::default()
    }
}

fn max_abs(r: &LyapunovResult) -> f64 {
    r.exponents.iter().fold(0.0f64, |m, l| m.max(l.abs()))
}

/// Σλ = ⟨tr J⟩ relative to the largest |λ|.
fn assert_trace_identity(r: &LyapunovResult, tol: f64, what: &str) {
    let m = r.mean_trace.expect("trace check on");
    let rel = (r.sum - m).abs() / max_abs(r);
    println!(
        "{what}: Σλ = {:.12}, ⟨tr J⟩ = {m:.12}, rel. diff {rel:.2e}",
        r.sum
    );
    assert!(
        rel < tol,
        "{what}: Σλ − ⟨tr J⟩ = {} (rel {rel:e})",
        r.sum - m
    );
}

/// Real parts of the eigenvalues of the 2×2 matrix [[a, b], [c, d]].
fn real_parts_2x2(a: f64, b: f64, c: f64, d: f64) -> [f64; 2] {
    let (tr, det) = (a + d, a * d - b * c);
    let disc = tr * tr / 4.0 - det;
    if disc >= 0.0 {
        [tr / 2.0 + disc.sqrt(), tr / 2.0 - disc.sqrt()]
    } else {
        [tr / 2.0; 2]
    }
}

// ---------------------------------------------------------------------------------------------
// Lyapunov spectra

#[test]
fn lorenz_spectrum_matches_reference() {
    let model = twv_generated::Lorenz::with_defaults();
    let field = OpenLoop::new(&model, []);
    // h = 5e-3 keeps the test fast in the unoptimised test profile; the RK4 bias on λ1 is
    // ~1e-3 here, below the batch-means error (~4e-3 over 2000 s). The Σλ = ⟨tr J⟩ identity
    // (an O(h⁴) statement) is checked at h = 1e-3 in `sum_is_independent_of_the_initial_basis`.
    let s = settings(5e-3, 0.1, 20_000, 50.0);
    let start = Instant::now();
    let r = lyapunov_spectrum::<_, 3, 3>(&field, &[1.0, 1.0, 20.0], &s).unwrap();
    println!(
        "Lorenz ({:.2?}): {}",
        start.elapsed(),
        serde_json::to_string(&r).unwrap()
    );
    let reference = [0.9056, 0.0, -14.5723];
    for ((l, e), l_ref) in r.exponents.iter().zip(&r.stderr).zip(reference) {
        assert!((l - l_ref).abs() < 0.01, "{l} ± {e} vs {l_ref}");
    }
    assert!(r.trace_residual().unwrap() < 1e-6);
    assert_eq!(r.classification, Classification::Positive { positive: 1 });
    let ky = r.kaplan_yorke.unwrap();
    assert!((ky - 2.062).abs() < 0.002, "Kaplan–Yorke {ky}");
}

/// A hyperchaotic system is called hyperchaotic: its two small positive exponents are judged
/// by their own errors, not against the large negative one (which once made a 1 %-of-max|λ|
/// zero band swallow them). With a horizon too short to resolve λ2 the verdict says so instead.
#[test]
fn hyper_rossler_is_hyperchaotic() {
    let model = Ode::new::<4>(HyperRossler);
    let field = OpenLoop::new(&model, []);
    let x0 = [-10.0, -6.0, 0.0, 10.1];
    let s = settings(5e-3, 0.1, 50_000, 200.0);
    let r = lyapunov_spectrum::<_, 4, 4>(&field, &x0, &s).unwrap();
    println!(
        "hyper-Rössler over 5000 s: {}",
        serde_json::to_string(&r).unwrap()
    );
    assert!((r.exponents[0] - 0.11).abs() < 0.02, "{:?}", r.exponents);
    assert!((r.exponents[1] - 0.02).abs() < 0.01, "{:?}", r.exponents);
    assert!(r.exponents[3] < -20.0, "{:?}", r.exponents);
    assert_eq!(r.classification, Classification::Positive { positive: 2 });
    assert!(r.classification.to_string().contains("hyperchaotic"));
    // RK4 at h = 5e-3 against the −24 /s direction: the identity holds to O(h⁴), ~1e-4 here.
    assert_trace_identity(&r, 3e-4, "hyper-Rössler");
    // 20 s: λ2 cannot be told from zero yet, and the verdict does not pretend it can.
    let short =
        lyapunov_spectrum::<_, 4, 4>(&field, &x0, &settings(5e-3, 0.1, 200, 200.0)).unwrap();
    assert_ne!(
        short.classification,
        Classification::Positive { positive: 2 }
    );
}

#[test]
fn henon_heiles_exponents_pair_and_sum_to_zero() {
    let model = twv_generated::HenonHeiles::with_defaults();
    let field = OpenLoop::new(&model, []);
    // x = 0, y = −0.15, py = 0 in the chaotic sea at E = 1/8; px from the energy.
    let (x, y, py): (f64, f64, f64) = (0.0, -0.15, 0.0);
    let e = 0.125;
    let px = (2.0 * e - y * y - py * py + 2.0 * y * y * y / 3.0 - x * x - 2.0 * x * x * y).sqrt();
    let x0 = [x, y, px, py];
    assert!((hh_energy(&x0) - e).abs() < 1e-15);
    let s = settings(1e-2, 1.0, 2_500, 0.0);
    let r = lyapunov_spectrum::<_, 4, 4>(&field, &x0, &s).unwrap();
    println!("Hénon–Heiles: {}", serde_json::to_string(&r).unwrap());
    let l = &r.exponents;
    assert!(r.sum.abs() < 1e-8 * max_abs(&r), "Σλ = {}", r.sum);
    assert!((l[0] + l[3]).abs() < 1e-3, "λ1 + λ4 = {}", l[0] + l[3]);
    assert!((l[1] + l[2]).abs() < 1e-3, "λ2 + λ3 = {}", l[1] + l[2]);
    assert!(l[0] > 0.03, "chaotic orbit expected: λ1 = {}", l[0]);
    assert_trace_identity(&r, 1e-8, "Hénon–Heiles");
    // RK4 is not symplectic, but at h = 0.01 the energy drift stays small.
    let xf: [f64; 4] = r.details.final_state.clone().try_into().unwrap();
    let drift = (hh_energy(&xf) - e).abs();
    println!("energy drift {drift:e}");
    assert!(drift < 1e-6);
}

#[test]
fn spectrum_is_invariant_to_the_qr_interval() {
    let model = twv_generated::Lorenz::with_defaults();
    let field = OpenLoop::new(&model, []);
    let x0 = [1.0, 1.0, 20.0];
    let base = lyapunov_spectrum::<_, 3, 3>(&field, &x0, &settings(1e-3, 0.1, 100, 0.0)).unwrap();
    for (t_sample, iterations) in [(0.05, 200), (0.02, 500), (0.2, 50)] {
        let r =
            lyapunov_spectrum::<_, 3, 3>(&field, &x0, &settings(1e-3, t_sample, iterations, 0.0))
                .unwrap();
        for (a, b) in r.exponents.iter().zip(&base.exponents) {
            assert!(
                (a - b).abs() < 1e-11 * max_abs(&base),
                "T = {t_sample}: {a} vs {b}"
            );
        }
    }
}

#[test]
fn lorenz_origin_gives_real_parts_of_eigenvalues() {
    let model = twv_generated::Lorenz::with_defaults();
    let field = OpenLoop::new(&model, []);
    let s = settings(1e-3, 0.1, 100, 5.0);
    let r = lyapunov_spectrum::<_, 3, 3>(&field, &[0.0; 3], &s).unwrap();
    let [sigma, rho, beta] = twv_generated::Lorenz::DEFAULTS;
    let [l1, l3] = real_parts_2x2(-sigma, sigma, rho, -1.0);
    let expected = [l1, -beta, l3];
    println!("Lorenz origin: {:?} vs {expected:?}", r.exponents);
    for (l, e) in r.exponents.iter().zip(expected) {
        assert!((l - e).abs() < 1e-6, "{l} vs {e}");
    }
    assert_trace_identity(&r, 1e-8, "Lorenz origin");
    assert_eq!(
        r.classification,
        Classification::Equilibrium { unstable: 1 }
    );
}

#[test]
fn linear_state_feedback_gives_closed_loop_eigenvalues() {
    let model = Ode::new::<3>(Chain);
    // A − BK has the characteristic polynomial (s + 1)(s + 2)(s + 3) = s³ + 6s² + 11s + 6.
    let law = LinearStateFeedback {
        u0: [0.0],
        x_ref: [0.0; 3],
        gain: [[1.0 + 6.0, -2.0 + 11.0, 0.5 + 6.0]],
    };
    let field = ClosedLoop::new(&model, law);
    let mut a_cl = [[0.0; 3]; 3];
    field.jacobian(0.0, &[0.0; 3], &mut a_cl);
    assert_eq!(a_cl[2], [-6.0, -11.0, -6.0]);
    assert_eq!(field.trace_jacobian(0.0, &[0.3, 0.2, 0.1]), -6.0);
    // The transient aligns the basis with the eigen-directions: the misalignment decays like
    // e^{−(gap) t} with gap 1 here, so 30 s leave ~1e-13.
    let s = settings(1e-3, 0.1, 100, 30.0);
    let r = lyapunov_spectrum::<_, 3, 3>(&field, &[1.0, 0.0, 0.0], &s).unwrap();
    println!("closed loop: {:?}", r.exponents);
    for (l, e) in r.exponents.iter().zip([-1.0, -2.0, -3.0]) {
        assert!((l - e).abs() < 1e-6, "{l} vs {e}");
    }
    assert_trace_identity(&r, 1e-8, "closed loop");
    // After the 30 s transient the orbit has reached the origin (‖x‖ ~ 1e-13).
    assert_eq!(
        r.classification,
        Classification::Equilibrium { unstable: 0 }
    );
    // The open loop is unstable: s³ − 0.5 s² + 2 s − 1 = (s − 0.5)(s² + 2); its largest
    // exponent (K = 1) is 0.5.
    let open = OpenLoop::new(&model, [0.0]);
    let r = lyapunov_spectrum::<_, 3, 1>(&open, &[1.0, 0.0, 0.0], &s).unwrap();
    assert!((r.exponents[0] - 0.5).abs() < 1e-6, "{}", r.exponents[0]);
}

/// A dynamic controller through the same seam (the recipe in `integrate::field`): the chain
/// under u = −k·x − kz·z with the integral state ż = x₁, as a 4-state augmented field.
struct ChainPi<'a, M> {
    model: &'a M,
    k: [f64; 3],
    kz: f64,
}

impl<M: Model<3, 1>> VectorField<4> for ChainPi<'_, M> {
    fn eval<const K: usize>(
        &self,
        _t: f64,
        xa: &[f64; 4],
        w: &[[f64; 4]; K],
        f: &mut [f64; 4],
        jw: &mut [[f64; 4]; K],
    ) {
        let (x, z) = ([xa[0], xa[1], xa[2]], xa[3]);
        let u = [-self.k.iter().zip(&x).map(|(k, x)| k * x).sum::<f64>() - self.kz * z];
        let wx: [[f64; 3]; K] = w.map(|wk| [wk[0], wk[1], wk[2]]);
        let (mut fx, mut jwx) = ([0.0; 3], [[0.0; 3]; K]);
        self.model.f_jw(&x, &u, &wx, &mut fx, &mut jwx);
        let mut b = [[0.0; 1]; 3];
        self.model.jac_u(&x, &u, &mut b);
        *f = [fx[0], fx[1], fx[2], x[0]];
        for ((out, wk), jx) in jw.iter_mut().zip(w).zip(&jwx) {
            // du = k_x w_x + k_z w_z
            let du = -self.k.iter().zip(wk).map(|(k, w)| k * w).sum::<f64>() - self.kz * wk[3];
            for i in 0..3 {
                out[i] = jx[i] + b[i][0] * du;
            }
            out[3] = wk[0];
        }
    }
}

#[test]
fn dynamic_controller_through_an_augmented_field() {
    let model = Ode::new::<3>(Chain);
    // s⁴ − (0.5 − k3) s³ + (2 + k2) s² + (k1 − 1) s + kz = (s + 1)(s + 2)(s + 3)(s + 4).
    let field = ChainPi {
        model: &model,
        k: [51.0, 33.0, 10.5],
        kz: 24.0,
    };
    let s = settings(1e-3, 0.1, 100, 40.0);
    let r = lyapunov_spectrum::<_, 4, 4>(&field, &[1.0, 0.0, 0.0, 0.0], &s).unwrap();
    println!("PI loop: {:?}", r.exponents);
    for (l, e) in r.exponents.iter().zip([-1.0, -2.0, -3.0, -4.0]) {
        assert!((l - e).abs() < 1e-6, "{l} vs {e}");
    }
    // The default trace (from the unit-vector Jacobian) works for a field without its own.
    assert_trace_identity(&r, 1e-8, "PI loop");
}

#[test]
fn sum_is_independent_of_the_initial_basis() {
    let model = twv_generated::Lorenz::with_defaults();
    let field = OpenLoop::new(&model, []);
    let x0 = [1.0, 1.0, 20.0];
    let mut s = LyapunovSettings::preset_paper();
    let a = lyapunov_spectrum::<_, 3, 3>(&field, &x0, &s).unwrap();
    s.basis = InitialBasis::Random { seed: 7 };
    let b = lyapunov_spectrum::<_, 3, 3>(&field, &x0, &s).unwrap();
    assert!((a.sum - b.sum).abs() < 1e-12 * max_abs(&a));
    assert_eq!(a.mean_trace, b.mean_trace);
    assert_trace_identity(&a, 1e-8, "Lorenz, paper preset");
}

#[test]
fn dopri_spectrum_agrees_with_rk4() {
    let model = twv_generated::Lorenz::with_defaults();
    let field = OpenLoop::new(&model, []);
    let x0 = [1.0, 1.0, 20.0];
    let rk4 = lyapunov_spectrum::<_, 3, 3>(&field, &x0, &settings(1e-4, 0.1, 20, 0.0)).unwrap();
    for tangent_error_control in [false, true] {
        let s = LyapunovSettings {
            iterations: 20,
            integrator: IntegratorChoice::Dopri(DopriOptions {
                rtol: 1e-11,
                atol: 1e-11,
                tangent_error_control,
                ..DopriOptions::default()
            }),
            ..LyapunovSettings::default()
        };
        let r = lyapunov_spectrum::<_, 3, 3>(&field, &x0, &s).unwrap();
        for (a, b) in r.exponents.iter().zip(&rk4.exponents) {
            assert!((a - b).abs() < 1e-6, "{a} vs {b}");
        }
        assert_trace_identity(&r, 1e-8, "Lorenz, dopri");
    }
}

#[test]
fn result_serialises_to_the_cli_json_and_running_csv() {
    let model = twv_generated::Lorenz::with_defaults();
    let field = OpenLoop::new(&model, []);
    let r =
        lyapunov_spectrum::<_, 3, 2>(&field, &[1.0, 1.0, 20.0], &LyapunovSettings::preset_paper())
            .unwrap();
    let v: serde_json::Value = serde_json::to_value(&r).unwrap();
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    let mut expected = [
        "exponents",
        "stderr",
        "significance",
        "zero_floor",
        "signs",
        "sum",
        "mean_trace",
        "kaplan_yorke",
        "classification",
        "t_total",
    ];
    expected.sort();
    let mut keys_sorted = keys.clone();
    keys_sorted.sort();
    assert_eq!(keys_sorted, expected);
    assert!(v["classification"]["text"].is_string());
    assert_eq!(v["signs"].as_array().unwrap().len(), 2);
    assert!((r.t_total - 10.0).abs() < 1e-12);
    // A partial spectrum whose sum stays positive cannot fix the Kaplan–Yorke dimension.
    assert!(r.exponents[0] >= r.exponents[1]);
    let mut csv = Vec::new();
    r.running.write_csv(&mut csv).unwrap();
    let csv = String::from_utf8(csv).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "t,lambda1,lambda2,sum,mean_trace");
    assert_eq!(lines.len(), 101);
    let last: Vec<f64> = lines[100].split(',').map(|x| x.parse().unwrap()).collect();
    assert_eq!(last[1], r.exponents[0]);
    assert_eq!(last[2], r.exponents[1]);
}

#[test]
fn settings_are_validated() {
    let bad = [
        LyapunovSettings {
            t_sample: 0.0,
            ..LyapunovSettings::default()
        },
        LyapunovSettings {
            iterations: 0,
            ..LyapunovSettings::default()
        },
        LyapunovSettings {
            integrator: IntegratorChoice::Rk4 { h: 0.5 },
            ..LyapunovSettings::default()
        },
        LyapunovSettings {
            batches: 1,
            ..LyapunovSettings::default()
        },
        LyapunovSettings {
            transient: f64::NAN,
            ..LyapunovSettings::default()
        },
    ];
    for s in bad {
        assert!(s.validate().is_err(), "{s:?}");
    }
    let p = LyapunovSettings::preset_paper();
    p.validate().unwrap();
    assert_eq!((p.t_sample, p.iterations), (0.1, 100));
    assert_eq!(p.integrator, IntegratorChoice::Rk4 { h: 1e-3 });
    // Settings round-trip through JSON (a `--params`-style file).
    let json = serde_json::to_string(&p).unwrap();
    let back: LyapunovSettings = serde_json::from_str(&json).unwrap();
    assert_eq!(back, p);
    let d: LyapunovSettings = serde_json::from_str(
        r#"{"integrator": {"kind": "dopri", "rtol": 1e-9, "tangent_error_control": true}}"#,
    )
    .unwrap();
    let IntegratorChoice::Dopri(o) = d.integrator else {
        panic!("{d:?}")
    };
    assert_eq!(
        (o.rtol, o.atol, o.tangent_error_control),
        (1e-9, 1e-12, true)
    );
    assert!(serde_json::from_str::<LyapunovSettings>(r#"{"t_sampel": 0.1}"#).is_err());
}

// ---------------------------------------------------------------------------------------------
// Integrators

/// RK4 global error at t = 1 on ẋ = −x², x0 = 1 (state and tangent), with step h.
fn rk4_riccati_error(h: f64) -> f64 {
    let model = Ode::new::<1>(Riccati(-1.0));
    let mut s = Rk4::new(OpenLoop::new(&model, []), 0.0, [1.0], [[1.0]], h, false).unwrap();
    s.advance_to(1.0).unwrap();
    assert_eq!(s.t(), 1.0);
    let y = s.state();
    (y.x[0] - 0.5).abs().max((y.w[0][0] - 0.25).abs())
}

#[test]
fn rk4_is_fourth_order() {
    let (e1, e2, e3) = (
        rk4_riccati_error(0.1),
        rk4_riccati_error(0.05),
        rk4_riccati_error(0.025),
    );
    println!(
        "RK4 errors {e1:e} {e2:e} {e3:e}, ratios {} {}",
        e1 / e2,
        e2 / e3
    );
    assert!((e1 / e2 - 16.0).abs() < 1.0, "ratio {}", e1 / e2);
    assert!((e2 / e3 - 16.0).abs() < 0.5, "ratio {}", e2 / e3);
}

#[test]
fn dopri_error_is_proportional_to_tolerance_and_dense_output_is_accurate() {
    let model = Ode::new::<2>(Oscillator);
    let t_end = 20.0;
    let mut errors = Vec::new();
    for tol in [1e-5, 1e-7, 1e-9] {
        let opts = DopriOptions {
            rtol: tol,
            atol: tol,
            tangent_error_control: true,
            ..DopriOptions::default()
        };
        let w0 = [[1.0, 0.0], [0.0, 1.0]];
        let mut s =
            Dopri5::new(OpenLoop::new(&model, []), 0.0, [1.0, 0.0], w0, opts, true).unwrap();
        s.set_stop_time(t_end).unwrap();
        let mut dense_err = 0.0f64;
        let mut out = VarState::ZERO;
        loop {
            let reason = s.step().unwrap();
            // Dense output in the middle of the step against the exact rotation.
            let (t0, t1) = s.last_step().unwrap();
            let t_mid = 0.5 * (t0 + t1);
            s.interpolate(t_mid, &mut out).unwrap();
            dense_err = dense_err.max((out.x[0] - t_mid.cos()).abs());
            dense_err = dense_err.max((out.w[1][0] - t_mid.sin()).abs());
            if reason == StopReason::StopTimeReached {
                break;
            }
        }
        assert_eq!(s.t(), t_end);
        let y = s.state();
        let err = (y.x[0] - t_end.cos())
            .abs()
            .max((y.x[1] + t_end.sin()).abs())
            .max((y.w[0][1] + t_end.sin()).abs());
        // tr J = 0 exactly, so the quadrature stays 0.
        assert_eq!(y.trace_integral, 0.0);
        println!(
            "dopri tol {tol:e}: error {err:e}, dense {dense_err:e}, steps {}",
            s.steps()
        );
        assert!(
            err < 100.0 * tol && err > 0.01 * tol,
            "tol {tol}: error {err}"
        );
        assert!(
            dense_err < 100.0 * tol,
            "tol {tol}: dense error {dense_err}"
        );
        errors.push(err);
    }
    // Proportionality: a 100× tighter tolerance gives a 100× (within a factor 3) smaller error.
    for pair in errors.windows(2) {
        let ratio = pair[0] / pair[1];
        assert!((30.0..300.0).contains(&ratio), "error ratio {ratio}");
    }
}

#[test]
fn blow_up_is_a_typed_error() {
    // ẋ = x², x0 = 1 reaches infinity at t = 1.
    let model = Ode::new::<1>(Riccati(1.0));
    let mut rk4 = Rk4::new(OpenLoop::new(&model, []), 0.0, [1.0], [[1.0]], 0.01, false).unwrap();
    match rk4.advance_to(2.0) {
        Err(IntegrateError::BlowUp { t, x, .. }) => {
            assert!(t > 0.9 && t < 1.1, "t = {t}");
            assert!(x[0].is_finite());
        }
        other => panic!("expected a blow-up, got {other:?}"),
    }
    let mut dopri = Dopri5::new(
        OpenLoop::new(&model, []),
        0.0,
        [1.0],
        [[1.0]],
        DopriOptions::default(),
        false,
    )
    .unwrap();
    match dopri.advance_to(2.0) {
        Err(IntegrateError::StepSizeUnderflow { t, x, .. }) => {
            assert!((t - 1.0).abs() < 1e-3, "t = {t}");
            assert!(x[0] > 1e3 && x[0].is_finite());
        }
        other => panic!("expected step-size underflow, got {other:?}"),
    }
    let err = lyapunov_spectrum::<_, 1, 1>(
        OpenLoop::new(&model, []),
        &[1.0],
        &LyapunovSettings::preset_paper(),
    )
    .unwrap_err();
    assert!(matches!(
        err,
        LyapunovError::Integrate(IntegrateError::BlowUp { .. })
    ));
    println!("{err}");
    // Non-finite initial state.
    assert!(matches!(
        Rk4::new(
            OpenLoop::new(&model, []),
            0.0,
            [f64::NAN],
            [[1.0]],
            0.01,
            false
        ),
        Err(IntegrateError::NonFiniteInitial { .. })
    ));
}

/// The unforced vehicle8 is integrable (energy, planar momentum and angular momentum are
/// conserved): its finite-time exponents are transients that shrink like 1/T as the horizon T
/// grows, whatever the initial basis. The study's "three positive exponents" at T = 10 s are
/// such transients.
#[test]
fn unforced_vehicle8_exponents_shrink_with_the_horizon() {
    let model = twv_generated::Vehicle8::with_defaults();
    let field = OpenLoop::new(&model, [0.0, 0.0]);
    let x0 = [0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    let largest = |iterations: usize, basis: InitialBasis| {
        let s = LyapunovSettings {
            basis,
            ..settings(1e-2, 0.1, iterations, 0.0)
        };
        let r = lyapunov_spectrum::<_, 8, 8>(&field, &x0, &s).unwrap();
        // At h = 0.01 the identity holds to ~1e-8 absolute (RK4's O(h⁴)), which does not shrink
        // with the horizon while the exponents do: relative 1e-5 at T = 1000 s.
        assert_trace_identity(&r, 1e-5, "vehicle8, h = 0.01");
        max_abs(&r)
    };
    for basis in [InitialBasis::Identity, InitialBasis::Random { seed: 1 }] {
        let l: Vec<f64> = [100, 1_000, 10_000]
            .iter()
            .map(|&k| largest(k, basis))
            .collect();
        println!("vehicle8 max |λ| at T = 10, 100, 1000 s ({basis:?}): {l:?}");
        assert!(l[0] > 0.1, "a visible finite-time transient at 10 s: {l:?}");
        assert!(
            l[1] < 0.3 * l[0] && l[2] < 0.3 * l[1],
            "shrinks ~1/T: {l:?}"
        );
        assert!(l[2] < 0.02, "all exponents near zero at 1000 s: {l:?}");
    }
}
