//! Linear analysis and tuning of the pitch loop (issue 6): linearisation, Routh–Hurwitz,
//! margins against closed forms, LQR, and the Clarabel tuner with its independent check.
//!
//! The vehicle here is a hand-written nonlinear cart–pendulum with the study's values
//! (m1 = 115, m2 = 8, b = 0.55, I2_yy = 0.81, g = 9.81, so M_x = 123), which is what every twv
//! vehicle reduces to in the plane.

use nalgebra::{Complex, DMatrix};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use twv_analysis::linear::{
    analyse_pitch, eigenvalues, linearize, loop_margins, loop_response, lqr, modes, solve_care,
    CareStatus, CartPendulum, GridOptions, HiddenKind, LinearError, LoopOptions, ModeKind,
    OperatingPoint, PidGains, PitchLoop,
};
use twv_analysis::tune::{tune, Objective, Spec, SpecError, TuneError, TuneOptions, TuneStatus};
use twv_model::{Model, ModelInfo};

const M1: f64 = 115.0;
const M2: f64 = 8.0;
const B: f64 = 0.55;
const I2_YY: f64 = 0.81;
const G: f64 = 9.81;

fn paper() -> CartPendulum {
    CartPendulum::from_vehicle(M1, M2, B, I2_YY, G).unwrap()
}

/// Nonlinear cart–pendulum, state (Φ, x, w_y, v_x), input F1; Jacobians by central
/// differences (the closed-form check below tolerates their 1e-9 error).
struct Cart(CartPendulum);

const STATES: [&str; 4] = ["phi", "x", "w_y", "v_x"];
const H: f64 = 1e-6;

impl Model<4, 1> for Cart {
    fn info(&self) -> ModelInfo {
        ModelInfo {
            name: "cart",
            ir_hash: "",
            states: &STATES,
            inputs: &["F1"],
            params: &[],
        }
    }

    fn f(&self, x: &[f64; 4], u: &[f64; 1], out: &mut [f64; 4]) {
        let p = &self.0;
        let ml = p.m_p * p.l;
        let (s, c) = x[0].sin_cos();
        // [I_p, ml c; ml c, M_x] [Φ̈; v̇_x] = [ml g s; F + ml s Φ̇²]
        let det = p.i_p() * p.m_x - (ml * c).powi(2);
        let r1 = ml * p.g * s;
        let r2 = u[0] + ml * s * x[2] * x[2];
        out[0] = x[2];
        out[1] = x[3];
        out[2] = (p.m_x * r1 - ml * c * r2) / det;
        out[3] = (p.i_p() * r2 - ml * c * r1) / det;
    }

    fn jac_x(&self, x: &[f64; 4], u: &[f64; 1], out: &mut [[f64; 4]; 4]) {
        for j in 0..4 {
            let (mut xp, mut xm) = (*x, *x);
            xp[j] += H;
            xm[j] -= H;
            let (mut fp, mut fm) = ([0.0; 4], [0.0; 4]);
            self.f(&xp, u, &mut fp);
            self.f(&xm, u, &mut fm);
            for i in 0..4 {
                out[i][j] = (fp[i] - fm[i]) / (2.0 * H);
            }
        }
    }

    fn jac_u(&self, x: &[f64; 4], u: &[f64; 1], out: &mut [[f64; 1]; 4]) {
        let (mut fp, mut fm) = ([0.0; 4], [0.0; 4]);
        self.f(x, &[u[0] + H], &mut fp);
        self.f(x, &[u[0] - H], &mut fm);
        for i in 0..4 {
            out[i][0] = (fp[i] - fm[i]) / (2.0 * H);
        }
    }

    fn jac_x_colind(&self) -> &[usize] {
        &[0, 4, 8, 12, 16]
    }

    fn jac_x_row(&self) -> &[usize] {
        &[0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3]
    }

    fn jac_x_sparse(&self, x: &[f64; 4], u: &[f64; 1], values: &mut [f64]) {
        let mut j = [[0.0; 4]; 4];
        self.jac_x(x, u, &mut j);
        for (k, v) in values.iter_mut().enumerate().take(16) {
            *v = j[k % 4][k / 4];
        }
    }

    fn f_jw<const K: usize>(
        &self,
        x: &[f64; 4],
        u: &[f64; 1],
        w: &[[f64; 4]; K],
        f: &mut [f64; 4],
        out: &mut [[f64; 4]; K],
    ) {
        self.f(x, u, f);
        let mut j = [[0.0; 4]; 4];
        self.jac_x(x, u, &mut j);
        for k in 0..K {
            for i in 0..4 {
                out[k][i] = (0..4).map(|c| j[i][c] * w[k][c]).sum();
            }
        }
    }
}

/// The pitch loop from the closed-form matrices (exact, so margins can be checked to 1e-6).
fn pitch_loop() -> PitchLoop {
    let (a, b) = paper().matrices();
    PitchLoop::new(&a, &b, &[1.0], &CartPendulum::state_names()).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

#[test]
fn linearisation_matches_the_closed_form_and_names_the_drift() {
    let cp = paper();
    let lin = linearize(&Cart(cp), &OperatingPoint::Upright, &[0.0]).unwrap();
    let (a, b) = lin.dynamic();
    let (a_ref, b_ref) = cp.matrices();
    assert!((&a - &a_ref).amax() < 1e-7 * a_ref.amax(), "{a} vs {a_ref}");
    assert!((&b - &b_ref).amax() < 1e-7 * b_ref.amax());
    assert_eq!(lin.residual, 0.0);

    let lambda = cp.lambda_sq().sqrt();
    let eig = eigenvalues(&a).unwrap();
    assert!(rel(eig[0].re, lambda) < 1e-7 && eig[0].im == 0.0);
    assert!(rel(eig[3].re, -lambda) < 1e-7);
    let names = lin.states.clone();
    let m = modes(&a, &names).unwrap();
    let drift: Vec<_> = m.iter().filter(|m| m.kind == ModeKind::Drift).collect();
    assert_eq!(drift.len(), 2, "{m:?}");
    for d in drift {
        let mut s = d.states.clone();
        s.sort();
        assert_eq!(s, ["v_x", "x"], "{d:?}");
    }

    // Hanging: ±iλ (the linearisation flips the sign of gravity).
    let hang = linearize(&Cart(cp), &OperatingPoint::Hanging, &[0.0]).unwrap();
    let (ah, _) = hang.dynamic();
    let m = modes(&ah, &names).unwrap();
    let osc: Vec<_> = m.iter().filter(|m| m.kind == ModeKind::Marginal).collect();
    assert_eq!(osc.len(), 2, "{m:?}");
    assert!(rel(osc[0].eigenvalue.im.abs(), lambda) < 1e-6);

    // The model-built loop agrees with the closed-form one.
    let from_model = PitchLoop::from_linearization(&lin, &[1.0]).unwrap();
    let g = PidGains::pd(3860.0, 1980.0);
    let l1 = from_model.loop_delay_free(&g, 0.0, 2.0).unwrap();
    let l2 = pitch_loop().loop_delay_free(&g, 0.0, 2.0).unwrap();
    assert!((l1 - l2).norm() < 1e-7 * l2.norm());
}

#[test]
fn closed_loop_stability_agrees_with_routh_hurwitz_for_500_random_gains() {
    let cp = paper();
    let lp = pitch_loop();
    let mxg = cp.m_x * cp.g;
    let mut rng = ChaCha8Rng::seed_from_u64(6);
    let mut checked = 0;
    let mut stable = 0;
    while checked < 500 {
        let kp = rng.gen_range(0.0..3.0 * mxg);
        let kd = rng.gen_range(-300.0..3000.0);
        let ki = if rng.gen_bool(0.5) {
            0.0
        } else {
            rng.gen_range(-50.0..1.5 * cp.ki_limit(kp, kd).max(100.0))
        };
        let g = PidGains { kp, ki, kd };
        // Skip the measure-zero neighbourhood of the boundary, where a verdict is rounding.
        let near = |x: f64, b: f64| (x - b).abs() <= 1e-6 * b.abs().max(1.0);
        if near(kp, mxg)
            || near(kd, 0.0)
            || (ki != 0.0 && (near(ki, 0.0) || near(ki, cp.ki_limit(kp, kd))))
        {
            continue;
        }
        let cl = lp.closed_loop(&g, &LoopOptions::default()).unwrap();
        assert_eq!(
            cl.stable,
            cp.routh_hurwitz_stable(&g),
            "{g:?}: {:?}",
            cl.loop_eigenvalues
        );
        // x and v_x are invisible to the loop: the uncontrolled drift, two zero eigenvalues.
        assert_eq!(cl.hidden.len(), 1);
        let h = &cl.hidden[0];
        assert_eq!(h.kind, HiddenKind::Unobservable);
        // A Jordan pair: its zero eigenvalues come out of QR perturbed by about √ε.
        assert!(h.eigenvalues.iter().all(|e| e.norm() < 1e-6));
        let mut names = h.states.clone();
        names.sort();
        assert_eq!(names, ["v_x", "x"]);
        assert_eq!(cl.all_eigenvalues.len(), 4 + usize::from(ki != 0.0));
        stable += usize::from(cl.stable);
        checked += 1;
    }
    assert!(
        stable > 50 && stable < 450,
        "both verdicts exercised: {stable}"
    );
}

#[test]
fn margins_match_closed_forms() {
    let s = |w: f64| Complex::new(0.0, w);
    let grid = GridOptions::around(&[1.0]);

    // L = 1/(s(s+1)): ω_c² = (√5 − 1)/2, PM = 90° − atan ω_c; |S − ½|² peaks at ω = 1 with
    // value (1 + 4)/4, so α = 2/√5; no phase crossover: gain margins (0, ∞).
    let l = |w: f64| (w != 0.0).then(|| (s(w) * (s(w) + 1.0)).inv());
    let m = loop_margins(&l, 0.0, true, &grid);
    let wc = ((5f64.sqrt() - 1.0) / 2.0).sqrt();
    assert_eq!(m.gain_crossovers.len(), 1);
    assert!(rel(m.gain_crossovers[0], wc) < 1e-9);
    assert!(rel(m.phase_margin_deg, 90.0 - wc.atan().to_degrees()) < 1e-9);
    assert!(rel(m.disk.alpha, 2.0 / 5f64.sqrt()) < 1e-9, "{:?}", m.disk);
    assert!(rel(m.disk.frequency, 1.0) < 1e-5);
    assert!(
        rel(
            m.disk.phase_deg,
            2.0 * (1.0 / 5f64.sqrt()).atan().to_degrees()
        ) < 1e-9
    );
    assert!(m.gain_margin_upper.is_infinite() && m.gain_margin_lower == 0.0);

    // L = 2/(s+1)³: phase crossover at √3 with |L| = 1/4 (GM 4); |L| = 1 at
    // ω_c = √(2^{2/3} − 1), PM = 180° − 3 atan ω_c; delay margin PM/ω_c.
    let l = |w: f64| Some((s(w) + 1.0).powi(3).inv() * 2.0);
    let m = loop_margins(&l, 0.0, true, &grid);
    assert!(rel(m.gain_margin_upper, 4.0) < 1e-9);
    assert!(rel(m.phase_crossovers[0], 3f64.sqrt()) < 1e-9);
    let wc = (2f64.powf(2.0 / 3.0) - 1.0).sqrt();
    let pm = 180.0 - 3.0 * wc.atan().to_degrees();
    assert!(rel(m.phase_margin_deg, pm) < 1e-9);
    assert!(rel(m.delay_margin, pm.to_radians() / wc) < 1e-9);

    // The same loop with a delay: stable just below the delay margin, unstable just above.
    let dm = pm.to_radians() / wc;
    assert!(loop_margins(&l, 0.99 * dm, true, &grid).stable);
    assert!(!loop_margins(&l, 1.01 * dm, true, &grid).stable);
}

/// The study's PD (Kp = 3860, Kd = 1980) on the paper vehicle: closed forms for every margin.
#[test]
fn study_pd_is_stabilising_with_closed_form_margins() {
    let cp = paper();
    let g = PidGains::pd(3860.0, 1980.0);
    let mxg = cp.m_x * cp.g;
    assert!(g.kp > mxg && rel(mxg, 1206.63) < 1e-12);
    let lp = pitch_loop();
    let an = analyse_pitch(&lp, &g, &LoopOptions::default()).unwrap();
    assert!(an.closed_loop.stable && an.margins.stable);
    assert!(an.closed_loop.spectral_abscissa < 0.0);

    // L(jω) = −c (Kp + j Kd ω)/(ω² + λ²), c = m_p l/Δ.
    let c = cp.m_p * cp.l / cp.delta();
    let a = cp.lambda_sq();
    let m = &an.margins;
    assert!(rel(m.gain_margin_lower, mxg / g.kp) < 1e-9, "{m:?}");
    assert!(m.gain_margin_upper.is_infinite());
    // |L| = 1: u² + (2a − c²Kd²) u + a² − c²Kp² = 0, u = ω².
    let (bq, cq) = (2.0 * a - (c * g.kd).powi(2), a * a - (c * g.kp).powi(2));
    let wc = ((-bq + (bq * bq - 4.0 * cq).sqrt()) / 2.0).sqrt();
    assert!(rel(m.phase_margin_frequency, wc) < 1e-9);
    assert!(rel(m.phase_margin_deg, (g.kd * wc / g.kp).atan().to_degrees()) < 1e-9);
    // |S − ½|² = ¼ r, r = 1 + 4p v/((p − v)² + d(v − a)), v = ω² + a, maximised at
    // v = √(p² − d a) when that exceeds a, else at DC.
    let (p, d) = (c * g.kp, (c * g.kd).powi(2));
    let v = (p * p - d * a).max(a * a).sqrt();
    let r = 1.0 + 4.0 * p * v / ((p - v).powi(2) + d * (v - a));
    assert!(rel(m.disk.alpha, 2.0 / r.sqrt()) < 1e-9, "{:?}", m.disk);
    println!(
        "study PD: GM_low = {:.6} ({:.3} dB), PM = {:.4} deg at {:.4} rad/s, delay margin {:.5} s, \
         disk alpha = {:.6}, DGM = [{:.4}, {:.4}], DPM = {:.4} deg at {} rad/s, Ms = {:.4}; poles {:?}",
        m.gain_margin_lower,
        20.0 * m.gain_margin_lower.log10(),
        m.phase_margin_deg,
        m.phase_margin_frequency,
        m.delay_margin,
        m.disk.alpha,
        m.disk.gain_low,
        m.disk.gain_high,
        m.disk.phase_deg,
        m.disk.frequency,
        m.peak_sensitivity,
        an.closed_loop.loop_eigenvalues
    );
}

/// A delay spins L's phase at ωT. Below the delay-free loop's delay margin the loop stays
/// stable with that margin less the delay; at or above it, and for a delay of hours (which once
/// made the margins resolve L on hundreds of millions of frequencies, minutes and gigabytes),
/// the loop is unstable at once, with the delay-free gain crossovers and no phase crossover.
#[test]
fn a_delay_beyond_the_delay_margin_is_unstable_without_resolving_the_spinning_phase() {
    let lp = pitch_loop();
    let g = PidGains::pd(3860.0, 1980.0);
    let free = analyse_pitch(&lp, &g, &LoopOptions::default())
        .unwrap()
        .margins;
    assert!(free.stable && free.delay_margin.is_finite() && free.delay_margin > 0.0);
    let with = |delay: f64| {
        analyse_pitch(&lp, &g, &LoopOptions { lag: 0.0, delay })
            .unwrap()
            .margins
    };
    let below = with(0.9 * free.delay_margin);
    assert!(below.stable, "{below:?}");
    assert!(
        rel(below.delay_margin, 0.1 * free.delay_margin) < 1e-6,
        "{below:?}"
    );
    for delay in [1.1 * free.delay_margin, 7541.05, 3.6e6] {
        let m = with(delay);
        assert!(!m.stable && m.delay_margin == 0.0, "delay {delay}: {m:?}");
        assert_eq!(m.gain_crossovers, free.gain_crossovers, "delay {delay}");
        assert!(m.phase_crossovers.is_empty() && m.peak_sensitivity.is_infinite());
        assert_eq!(m.disk.alpha, 0.0);
    }
}

#[test]
fn lqr_solves_the_riccati_equation_and_stabilises() {
    // Scalar: ẋ = x + u, q = r = 1: P = 1 + √2.
    let one = DMatrix::from_element(1, 1, 1.0);
    let sol = solve_care(&one, &one, &one, &one).unwrap();
    assert_eq!(sol.status, CareStatus::Solved);
    assert!(rel(sol.p[(0, 0)], 1.0 + 2f64.sqrt()) < 1e-12);

    // The cart–pendulum, all four states weighted.
    let (a, b) = paper().matrices();
    let q = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&[
        100.0, 1.0, 10.0, 1.0,
    ]));
    let r = DMatrix::from_element(1, 1, 1e-4);
    let k = lqr(&a, &b, &q, &r).unwrap();
    assert_eq!(k.status, CareStatus::Solved);
    assert!(k.residual <= 1e-9, "residual {}", k.residual);
    assert!(k.spectral_abscissa < 0.0);
    println!(
        "cart-pendulum LQR: K = {}, residual {:.2e}, poles {:?}",
        k.k, k.residual, k.closed_loop_eigenvalues
    );

    // An unstable mode the input cannot reach: no stabilising solution, reported as a status.
    let a = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&[1.0, 2.0]));
    let b = DMatrix::from_column_slice(2, 1, &[1.0, 0.0]);
    let sol = solve_care(&a, &b, &DMatrix::identity(2, 2), &one).unwrap();
    assert_eq!(sol.status, CareStatus::NoStabilisingSolution);
}

#[test]
fn bad_input_is_a_typed_error() {
    let lp = pitch_loop();
    let nan = PidGains::pd(f64::NAN, 1.0);
    assert!(matches!(
        lp.closed_loop(&nan, &LoopOptions::default()),
        Err(LinearError::NonFinite { .. })
    ));
    let lag = LoopOptions {
        lag: -0.1,
        delay: 0.0,
    };
    assert!(matches!(
        lp.closed_loop(&PidGains::pd(1.0, 1.0), &lag),
        Err(LinearError::Negative { .. })
    ));
    let (a, b) = paper().matrices();
    assert!(matches!(
        PitchLoop::new(&a, &b, &[1.0, 2.0], &CartPendulum::state_names()),
        Err(LinearError::Dimension { .. })
    ));
    let r = DMatrix::from_element(1, 1, -1.0);
    assert!(matches!(
        lqr(&a, &b, &DMatrix::identity(4, 4), &r),
        Err(LinearError::Weight { .. })
    ));
}

/// The independent check, redone here from scratch: eigenvalues and dense-grid margins.
fn check_independently(lp: &PitchLoop, g: &PidGains, opts: &LoopOptions, dpm: f64) {
    let an = analyse_pitch(lp, g, opts).unwrap();
    assert!(
        an.closed_loop.loop_eigenvalues.iter().all(|e| e.re < 0.0),
        "{g:?}"
    );
    assert!(an.margins.stable);
    assert!(
        an.margins.disk.phase_deg >= dpm,
        "{g:?}: {:?}",
        an.margins.disk
    );
}

#[test]
fn tuned_pd_meets_dpm_45_by_the_independent_check() {
    let lp = pitch_loop();
    let cp = paper();
    let spec: Spec = "dpm>=45".parse().unwrap();
    let res = tune(&lp, &spec, &TuneOptions::default()).unwrap();
    assert_eq!(res.status, TuneStatus::Solved, "{res:?}");
    let cert = res.certificate.as_ref().unwrap();
    assert!(cert.meets_spec);
    let g = cert.gains;
    check_independently(&lp, &g, &LoopOptions::default(), 45.0);
    assert!(cp.routh_hurwitz_stable(&g));
    // Minimum-gain design: the margin constraint is active (not far above 45°).
    let dpm = cert.analysis.margins.disk.phase_deg;
    assert!(dpm < 45.5, "{dpm}");
    println!(
        "tuned PD for dpm>=45 (min gain): Kp = {:.2}, Kd = {:.2}, DPM = {:.4} deg, DGM = {:.4}, \
         PM = {:.2} deg, {} subproblems",
        g.kp,
        g.kd,
        dpm,
        cert.analysis.margins.disk.gain_high,
        cert.analysis.margins.phase_margin_deg,
        res.iterations
    );

    // With the study's gains as the target: they already meet it, so they come back.
    let study = PidGains::pd(3860.0, 1980.0);
    let opts = TuneOptions {
        target: Some(study),
        ..TuneOptions::default()
    };
    let res = tune(&lp, &spec, &opts).unwrap();
    let g = res.certificate.unwrap().gains;
    assert!(
        rel(g.kp, study.kp) < 1e-4 && rel(g.kd, study.kd) < 1e-4,
        "{g:?}"
    );

    // A target that violates the spec (too little damping) is moved to meet it.
    let opts = TuneOptions {
        target: Some(PidGains::pd(3860.0, 400.0)),
        ..TuneOptions::default()
    };
    let res = tune(&lp, &spec, &opts).unwrap();
    assert_eq!(res.status, TuneStatus::Solved);
    let g = res.certificate.unwrap().gains;
    check_independently(&lp, &g, &LoopOptions::default(), 45.0);
    println!(
        "nearest to (3860, 400) with dpm>=45: Kp = {:.2}, Kd = {:.2}",
        g.kp, g.kd
    );
}

/// Φ̈ = −4 Φ − F (a pendulum hanging below its hinge, undamped; the base's force tilts it
/// back, as in the study's vehicle): its poles ±2j lie exactly on the tuner's reference
/// frequency, where the plant is infinite; the gain scales come from another frequency and the
/// design proceeds.
#[test]
fn an_undamped_pole_at_the_reference_frequency_still_tunes() {
    let a = DMatrix::from_row_slice(2, 2, &[0.0, 1.0, -4.0, 0.0]);
    let b = DMatrix::from_row_slice(2, 1, &[0.0, -1.0]);
    let states = ["phi".to_string(), "w_y".to_string()];
    let lp = PitchLoop::new(&a, &b, &[1.0], &states).unwrap();
    assert!(
        lp.gain_basis(0.0, 2.0).is_none(),
        "the plant is infinite at its pole"
    );
    let spec: Spec = "dpm>=45".parse().unwrap();
    let res = tune(&lp, &spec, &TuneOptions::default()).unwrap();
    assert_eq!(res.status, TuneStatus::Solved, "{res:?}");
    let g = res.certificate.as_ref().unwrap().gains;
    check_independently(&lp, &g, &LoopOptions::default(), 45.0);
}

#[test]
fn tuned_pid_with_actuator_lag_and_delay_meets_its_spec() {
    let lp = pitch_loop();
    let spec: Spec = "dpm>=40,dgm>=6dB".parse().unwrap();
    let loop_options = LoopOptions {
        lag: 0.02,
        delay: 0.01,
    };
    let opts = TuneOptions {
        pid: true,
        loop_options,
        ..TuneOptions::default()
    };
    let res = tune(&lp, &spec, &opts).unwrap();
    assert!(
        matches!(res.status, TuneStatus::Solved | TuneStatus::IterationLimit),
        "{res:?}"
    );
    let cert = res.certificate.unwrap();
    assert!(cert.meets_spec && cert.gains.ki > 0.0);
    check_independently(&lp, &cert.gains, &loop_options, 40.0);
    assert!(cert.analysis.margins.disk.gain_high >= 10f64.powf(6.0 / 20.0) * (1.0 - 1e-9));
    println!(
        "tuned PID (lag 20 ms, delay 10 ms, max Ki): {:?}, margins {:?}",
        cert.gains, cert.analysis.margins.disk
    );
}

#[test]
fn an_impossible_spec_is_reported_infeasible_with_the_best_margin() {
    let lp = pitch_loop();
    let spec: Spec = "dpm>=89.9".parse().unwrap();
    let loop_options = LoopOptions {
        lag: 0.0,
        delay: 0.2,
    };
    let opts = TuneOptions {
        loop_options,
        ..TuneOptions::default()
    };
    let res = tune(&lp, &spec, &opts).unwrap();
    assert_eq!(res.status, TuneStatus::Infeasible);
    assert!(res.best_fraction < 1.0);
    if let Some(c) = &res.certificate {
        let d = c.analysis.margins.disk.phase_deg;
        assert!(
            c.analysis.margins.stable && d < 89.9 && d >= 89.9 * res.best_fraction * (1.0 - 1e-9)
        );
        println!(
            "dpm>=89.9 with a 0.2 s delay: infeasible; best found DPM = {d:.3} deg with {:?}",
            c.gains
        );
    }
}

#[test]
fn bad_tuner_input_is_a_typed_error() {
    assert!(matches!(
        "pm>=45".parse::<Spec>(),
        Err(SpecError::Unsupported(_))
    ));
    assert!(matches!(
        "dpm>=95".parse::<Spec>(),
        Err(SpecError::Range { .. })
    ));
    assert!(matches!(
        "dpm>45".parse::<Spec>(),
        Err(SpecError::Syntax(_))
    ));
    assert!(matches!(
        "dpm>=NaN".parse::<Spec>(),
        Err(SpecError::Syntax(_))
    ));
    let spec: Spec = "dgm>=6dB, ms<=1.5".parse().unwrap();
    assert_eq!(spec.requirements.len(), 2);
    let lp = pitch_loop();
    let bad = TuneOptions {
        loop_options: LoopOptions {
            lag: -1.0,
            delay: 0.0,
        },
        ..TuneOptions::default()
    };
    assert!(matches!(
        tune(&lp, &spec, &bad),
        Err(TuneError::Linear(LinearError::Negative { .. }))
    ));
    let bad = TuneOptions {
        objective: Some(Objective::MaxIntegral),
        ..TuneOptions::default()
    };
    assert!(matches!(
        tune(&lp, &spec, &bad),
        Err(TuneError::Option { .. })
    ));
}

/// Every disk margin the loop can reach is found with gains of the order the spec needs, and
/// the status, the certificate and its `meets_spec` agree (a 60° spec once came back
/// "infeasible" with a certificate of 89° and gains of 2·10⁵). The minimum-gain objective keeps
/// the margin constraint active.
#[test]
fn reachable_disk_margins_are_solved_with_small_gains() {
    let lp = pitch_loop();
    for spec in [
        "dpm>=30",
        "dpm>=45",
        "dpm>=60",
        "dpm>=70",
        "dpm>=75",
        "dgm>=6dB",
        "dgm>=10dB",
        "dgm>=14dB",
        "dgm>=20dB",
        "dpm>=60,dgm>=6dB",
    ] {
        let s: Spec = spec.parse().unwrap();
        let res = tune(&lp, &s, &TuneOptions::default()).unwrap();
        let cert = res.certificate.as_ref().expect("a certificate");
        println!(
            "{spec}: {:?} after {}, Kp = {:.1}, Kd = {:.1}, dpm {:.2}, dgm {:.3}",
            res.status,
            res.iterations,
            cert.gains.kp,
            cert.gains.kd,
            cert.analysis.margins.disk.phase_deg,
            cert.analysis.margins.disk.gain_high
        );
        assert_eq!(res.status, TuneStatus::Solved, "{spec}");
        assert!(cert.meets_spec, "{spec}");
        // Active constraint: the margin is met, not exceeded by much.
        let m = &cert.analysis.margins.disk;
        let slack = s.requirements.iter().map(|r| match *r {
            twv_analysis::tune::Requirement::DiskPhase { deg } => m.phase_deg / deg - 1.0,
            twv_analysis::tune::Requirement::DiskGain { factor } => m.gain_high / factor - 1.0,
            _ => 0.0,
        });
        assert!(slack.fold(f64::INFINITY, f64::min) < 0.02, "{spec}: {m:?}");
        assert!(
            cert.gains.kp < 5e4 && cert.gains.kd < 2e4,
            "{spec}: {:?}",
            cert.gains
        );
    }
}

/// The frequency response the Bode and Nyquist figures draw is the closed form
/// L(jω) = −c (Kp + j Kd ω)/(ω² + λ²) at every point, its phase is continuous, and the Nyquist
/// criterion read off it — half-turns of 1 + L as ω runs over the grid, against the plant's one
/// unstable pole — agrees with the closed-loop eigenvalues for stabilising and non-stabilising
/// gains alike (two independent paths to the same verdict).
#[test]
fn frequency_response_is_the_closed_form_and_its_nyquist_count_matches_the_eigenvalues() {
    let cp = paper();
    let (c, a) = (cp.m_p * cp.l / cp.delta(), cp.lambda_sq());
    let lp = pitch_loop();
    let mxg = cp.m_x * cp.g;
    let opts = LoopOptions::default();
    let mut verdicts = Vec::new();
    for (kp, kd) in [
        (3860.0, 1980.0),
        (2958.2, 675.8),
        (1.5 * mxg, 50.0),
        (0.8 * mxg, 1980.0),
        (0.3 * mxg, 400.0),
    ] {
        let g = PidGains::pd(kp, kd);
        let an = analyse_pitch(&lp, &g, &opts).unwrap();
        let r = loop_response(&lp, &g, &opts, &an, 2000).unwrap();
        assert_eq!(r.w.len(), 2000);
        assert_eq!(r.gain_crossovers, an.margins.gain_crossovers);
        for i in 0..r.w.len() {
            let w = r.w[i];
            let exact = -Complex::new(c * kp, c * kd * w) / (w * w + a);
            let got = Complex::new(r.re[i], r.im[i]);
            assert!(
                (got - exact).norm() <= 1e-12 * exact.norm(),
                "{w}: {got} vs {exact}"
            );
            assert!((r.magnitude_db[i] - 20.0 * exact.norm().log10()).abs() < 1e-9);
            let wrapped = (r.phase_deg[i] - exact.arg().to_degrees()) / 360.0;
            assert!((wrapped - wrapped.round()).abs() < 1e-9);
            if i > 0 {
                assert!(
                    (r.phase_deg[i] - r.phase_deg[i - 1]).abs() < 30.0,
                    "jump at {w}"
                );
                assert!(r.w[i] > r.w[i - 1]);
            }
        }
        // A stable loop's L stays outside its disk margin's exclusion disk and touches it
        // (to the grid's resolution) where the margin is attained: the golden-section search
        // of the margins and the response grid agree.
        if let Some(d) = &r.disk {
            let gap = (0..r.w.len())
                .map(|i| Complex::new(r.re[i] - d.center, r.im[i]).norm() - d.radius)
                .fold(f64::INFINITY, f64::min);
            assert!(
                gap > -1e-9 * d.radius && gap < 1e-3 * d.radius,
                "gap {gap}, {d:?}"
            );
            assert!(d.center - d.radius < -1.0 && -1.0 < d.center + d.radius);
        } else {
            assert!(!an.closed_loop.stable);
        }
        // Half-turns of 1 + L for ω from 0⁺ to ∞; the mirror image doubles them.
        let turn: f64 = (1..r.w.len())
            .map(|i| {
                let p = Complex::new(1.0 + r.re[i - 1], r.im[i - 1]);
                let q = Complex::new(1.0 + r.re[i], r.im[i]);
                (q / p).arg()
            })
            .sum();
        let encirclements = (turn / std::f64::consts::PI).round() as i64;
        let unstable_poles = lp
            .plant()
            .poles()
            .unwrap()
            .iter()
            .filter(|p| p.re > 0.0)
            .count();
        assert_eq!(unstable_poles, 1);
        let nyquist_stable = encirclements == unstable_poles as i64;
        assert_eq!(nyquist_stable, an.closed_loop.stable, "Kp {kp}, Kd {kd}");
        verdicts.push(nyquist_stable);
    }
    assert_eq!(verdicts, [true, true, true, false, false]);
}
