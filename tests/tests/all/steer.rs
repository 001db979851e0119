//! Balancing the bicycle by steering (`twv steer`, `ride --steer-gains`): the steer loop's
//! closed-loop eigenvalues against the published linear benchmark equations with the feedback
//! substituted (a second, independent path), the nonlinear closed loop's Jacobian at straight
//! running against the linear loop, a tuned schedule whose certificates and nonlinear checks
//! hold at every speed, an infeasible spec that flips when loosened, and bad input.

use std::path::PathBuf;

use nalgebra::{Complex, DMatrix};
use serde_json::Value;
use twv_analysis::api::{steady_state, steer, steer_loop, Silent, SteerLoopSettings, SteerVerdict};
use twv_analysis::control::steer::{SteerLaw, SteerSettings};
use twv_analysis::integrate::{ClosedLoop, VectorField};
use twv_analysis::linear::modes::eigenvalues;
use twv_analysis::linear::SteerGains;
use twv_analysis::model::{ModelSpec, ResolvedModel};
use twv_analysis::tune::steer::{tune_steer, SteerTuneOptions};
use twv_analysis::tune::TuneStatus;
use twv_ir::Interpreted;
use twv_model::Model;

pub(crate) fn bicycle() -> ResolvedModel {
    ModelSpec::shipped("whipple").resolve().unwrap()
}

/// Meijaard et al. (2007), eq. (5.4): M, C1, K0 (without g), K2 at the benchmark parameters.
pub(crate) fn benchmark() -> [DMatrix<f64>; 4] {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/meijaard2007.json");
    let v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    ["M", "C1", "K0", "K2"].map(|k| {
        let rows: Vec<Vec<f64>> = serde_json::from_value(v[k].clone()).unwrap();
        DMatrix::from_fn(2, 2, |i, j| rows[i][j])
    })
}

/// The closed loop of the benchmark equations M q̈ + v C1 q̇ + (g K0 + v² K2) q = (0, T_δ),
/// T_δ = K (φ, δ, φ̇, δ̇), as a first-order matrix.
pub(crate) fn benchmark_closed_loop(v: f64, g: &SteerGains) -> DMatrix<f64> {
    let [m, c1, k0, k2] = benchmark();
    let minv = m.try_inverse().unwrap();
    let stiffness = -&minv * (k0 * 9.81 + k2 * (v * v));
    let damping = -&minv * (c1 * v);
    let mut a = DMatrix::zeros(4, 4);
    a[(0, 2)] = 1.0;
    a[(1, 3)] = 1.0;
    a.view_mut((2, 0), (2, 2)).copy_from(&stiffness);
    a.view_mut((2, 2), (2, 2)).copy_from(&damping);
    for i in 0..2 {
        for (j, k) in g.row().iter().enumerate() {
            a[(2 + i, j)] += minv[(i, 1)] * k;
        }
    }
    a
}

pub(crate) fn sorted(mut e: Vec<Complex<f64>>) -> Vec<Complex<f64>> {
    e.sort_by(|a, b| a.re.total_cmp(&b.re).then(a.im.total_cmp(&b.im)));
    e
}

pub(crate) const GAINS: [SteerGains; 2] = [
    SteerGains {
        k_phi: 74.7,
        k_delta: -53.7,
        k_phi_dot: 24.0,
        k_delta_dot: -9.13,
    },
    SteerGains {
        k_phi: 12.0,
        k_delta: -20.0,
        k_phi_dot: 2.5,
        k_delta_dot: -2.2,
    },
];

#[test]
fn closed_loop_eigenvalues_are_the_benchmark_equations_with_the_feedback_substituted() {
    let model = bicycle();
    for v in [0.5, 2.0, 4.5, 6.0, 9.0] {
        let lp = steer_loop(&model, v).unwrap();
        for g in &GAINS {
            let ours = sorted(lp.closed_loop(g).unwrap().eigenvalues);
            let theirs = sorted(eigenvalues(&benchmark_closed_loop(v, g)).unwrap());
            for (a, b) in ours.iter().zip(&theirs) {
                // The published matrices carry 13-15 significant digits.
                assert!(
                    (a - b).norm() <= 1e-10 * b.norm().max(1.0),
                    "at {v} m/s with {g:?}: {a} against the benchmark's {b}"
                );
            }
        }
    }
}

#[test]
fn the_nonlinear_closed_loop_linearised_at_straight_running_is_the_linear_loop() {
    let model = bicycle();
    let bike = Interpreted::<9, 4>::new(&model.ir, &model.params).unwrap();
    let info = bike.info();
    let modes: Vec<String> = ["phi", "delta", "w_phi", "w_delta"]
        .map(String::from)
        .to_vec();
    let index: Vec<usize> = modes
        .iter()
        .map(|m| model.state_index(m).unwrap())
        .collect();
    for v in [2.0, 5.0] {
        let settings = SteerSettings {
            gains: GAINS[0],
            saturation: Some(50.0),
            rate_filter: None,
        };
        let law = SteerLaw::<9, 4>::new(
            "whipple",
            info.states,
            info.inputs,
            &modes,
            &settings,
            [0.0; 4],
        )
        .unwrap();
        let field = ClosedLoop::new(&bike, law);
        let x: [f64; 9] = steady_state(&model, v).unwrap().try_into().unwrap();
        let mut jac = [[0.0; 9]; 9];
        field.jacobian(0.0, &x, &mut jac);
        let linear = steer_loop(&model, v).unwrap().closed_loop_matrix(&GAINS[0]);
        for (i, &r) in index.iter().enumerate() {
            for (j, &c) in index.iter().enumerate() {
                let (a, b) = (jac[r][c], linear[(i, j)]);
                assert!(
                    (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                    "∂f_{}/∂{} at {v} m/s: {a} against {b}",
                    modes[i],
                    modes[j]
                );
            }
        }
    }
}

#[test]
fn a_tuned_schedule_meets_the_spec_and_recovers_at_every_speed() {
    let model = bicycle();
    let s = SteerLoopSettings {
        lo: 1.0,
        hi: 8.0,
        step: 1.0,
        ..SteerLoopSettings::default()
    };
    let r = steer(&model, &s, &Silent).unwrap();
    assert_eq!(r.verdict, SteerVerdict::Met, "{}", r.summary());
    for p in &r.points {
        let c = p.certificate.as_ref().unwrap();
        assert!(
            c.meets_spec && c.analysis.closed_loop.stable,
            "{} m/s",
            p.speed
        );
        assert!(c.analysis.margins.disk.phase_deg >= 45.0 * (1.0 - 1e-9));
        // Independently of the certificate: the closed loop's eigenvalues decay.
        assert!(c.analysis.closed_loop.spectral_abscissa < 0.0);
        let ride = p.ride.unwrap();
        assert!(ride.peak.unwrap() > 0.0 && ride.final_value.unwrap() < 0.1 * ride.peak.unwrap());
    }
    // Below the weave speed the bicycle is unstable unsteered, above it self-stable: the
    // schedule spans both, and its gains change continuously (less than their size from one
    // metre per second to the next).
    assert!(!r.points[0].self_stable && r.points[4].self_stable);
    assert!(r.largest_step < 1.0, "{}", r.largest_step);
}

#[test]
fn an_infeasible_spec_is_reported_with_its_best_fraction_and_flips_when_loosened() {
    let model = bicycle();
    let lp = steer_loop(&model, 0.5).unwrap();
    let tight = SteerTuneOptions {
        max_gain_factor: 2.0,
        ..SteerTuneOptions::default()
    };
    let never = || false;
    let strict = tune_steer(&lp, &"dpm>=60".parse().unwrap(), &tight, &never).unwrap();
    assert_eq!(strict.status, TuneStatus::Infeasible);
    assert!(!strict.met() && strict.best_fraction > 0.0 && strict.best_fraction < 1.0);
    let c = strict.certificate.as_ref().unwrap();
    assert!(!c.meets_spec && c.analysis.margins.disk.phase_deg < 60.0);
    let loose = tune_steer(&lp, &"dpm>=30".parse().unwrap(), &tight, &never).unwrap();
    assert!(loose.met(), "{:?}", loose.status);
    assert!(loose.certificate.unwrap().analysis.margins.disk.phase_deg >= 30.0 * (1.0 - 1e-9));
}

#[test]
fn destabilising_gains_get_a_computed_verdict_and_bad_input_one_line() {
    let model = bicycle();
    let s = SteerLoopSettings {
        lo: 2.0,
        hi: 6.0,
        step: 2.0,
        gains: Some(SteerGains {
            k_phi: -50.0,
            ..SteerGains::default()
        }),
        ..SteerLoopSettings::default()
    };
    let r = steer(&model, &s, &Silent).unwrap();
    assert_eq!(r.verdict, SteerVerdict::NotMet);
    for p in &r.points {
        let c = p.certificate.as_ref().unwrap();
        assert!(!c.analysis.closed_loop.stable && !p.met, "{} m/s", p.speed);
    }
    let error =
        |s: SteerLoopSettings, m: &ResolvedModel| steer(m, &s, &Silent).unwrap_err().to_string();
    let negative = error(
        SteerLoopSettings {
            lo: -1.0,
            ..SteerLoopSettings::default()
        },
        &model,
    );
    assert!(
        negative.contains("speed") && negative.contains("≥ 0"),
        "{negative}"
    );
    let vehicle = ModelSpec::shipped("vehicle8").resolve().unwrap();
    let no_steer = error(SteerLoopSettings::default(), &vehicle);
    assert!(
        no_steer.contains("T_delta") && !no_steer.contains('\n'),
        "{no_steer}"
    );
    let nan = error(
        SteerLoopSettings {
            gains: Some(SteerGains {
                k_phi: f64::NAN,
                ..SteerGains::default()
            }),
            ..SteerLoopSettings::default()
        },
        &model,
    );
    assert!(nan.contains("k_phi"), "{nan}");
    let force = error(
        SteerLoopSettings {
            spec: "force<=100".parse().unwrap(),
            ..SteerLoopSettings::default()
        },
        &model,
    );
    assert!(force.contains("force"), "{force}");
}

/// `lyap` of the steered bicycle from straight running at 3 m/s: the orbit is the steady
/// motion itself, so the Lyapunov exponents are the real parts of the closed loop's
/// eigenvalues — the four of the lean-and-steer loop (a pair's real part twice) and 0 for
/// every other direction (position, heading, wheel angles, speed: no restoring force) — and
/// unsteered the same holds with the open loop's eigenvalues, one of them > 0.
/// Spectrum settings for a steady motion: RK4 at 10 ms, a 10 s transient, then `seconds` of
/// averaging sampled every 0.1 s.
pub(crate) fn averaged_over(seconds: f64) -> twv_analysis::lyapunov::LyapunovSettings {
    use twv_analysis::lyapunov::{IntegratorChoice, LyapunovSettings};
    LyapunovSettings {
        t_sample: 0.1,
        iterations: (seconds / 0.1).round() as usize,
        transient: 10.0,
        integrator: IntegratorChoice::Rk4 { h: 0.01 },
        record_running: false,
        trace_check: false,
        ..LyapunovSettings::preset_paper()
    }
}

#[test]
fn the_steered_bicycles_lyapunov_spectrum_is_its_closed_loop_eigenvalues() {
    use twv_analysis::api::{spectrum, SpectrumSettings};
    let bike = bicycle();
    // Lean-rate feedback alone: at 3 m/s the benchmark bicycle needs about 8 N m s/rad.
    let g = SteerGains {
        k_phi_dot: 15.0,
        ..SteerGains::default()
    };
    let lp = steer_loop(&bike, 3.0).unwrap();
    for gains in [Some(g), None] {
        let eig = match gains {
            Some(g) => lp.closed_loop(&g).unwrap().eigenvalues,
            None => lp.open_loop_eigenvalues().unwrap(),
        };
        let s = SpectrumSettings {
            speed: Some(3.0),
            steer: gains.map(SteerSettings::gains),
            lyapunov: averaged_over(60.0),
            ..SpectrumSettings::default()
        };
        let r = spectrum(&bike, &s, &Silent).unwrap();
        let n = r.result.exponents.len();
        let mut expected: Vec<f64> = eig.iter().map(|e| e.re).collect();
        expected.resize(n, 0.0);
        expected.sort_by(|a, b| b.total_cmp(a));
        for (k, (got, want)) in r.result.exponents.iter().zip(&expected).enumerate() {
            // 60 s of averaging after a 10 s transient: the finite-time exponents of a constant
            // linear flow are within ~1/60 1/s of its real parts. The directions with no
            // restoring force shear (the heading grows with the steer angle's integral), and
            // theirs fall off only as ln t / t: 0.05 for those.
            let tolerance = if *want == 0.0 { 0.05 } else { 0.03 };
            assert!(
                (got - want).abs() < tolerance,
                "{} λ{}: {got} against Re {want} ({:?})",
                r.model,
                k + 1,
                r.result.exponents
            );
        }
        assert_eq!(r.model.ends_with("(steered)"), gains.is_some());
        assert_eq!(
            r.result.exponents[0] > 0.1,
            gains.is_none(),
            "{:?}",
            r.result.exponents
        );
    }
}

/// `linearize --speed V --steer-gains …`: the steer loop closed about the steady motion. Its
/// poles (the IR's steady-motion Jacobian) are the benchmark equations' with the feedback
/// substituted (1e-10), and every state's closed loop (the compiled model's own 9 × 9
/// Jacobian, a second path) has exactly those four poles besides the drift of position,
/// heading and speed; the verdict and the margins follow the poles.
#[test]
fn linearize_closes_the_steer_loop_about_the_steady_motion() {
    use twv_analysis::api::{analyse, LinearSettings};
    use twv_analysis::jobs::{JobOutput, Verdict};
    use twv_analysis::linear::ModeKind;
    let model = bicycle();
    for v in [0.5, 3.0, 6.0] {
        for g in &GAINS {
            let settings = LinearSettings {
                speed: Some(v),
                steer: Some(SteerSettings::gains(*g)),
                ..LinearSettings::default()
            };
            let r = analyse(&model, &settings).unwrap();
            assert!(
                r.equilibrium && r.pitch.is_none(),
                "{v} m/s: {}",
                r.residual
            );
            let st = r.steer.as_ref().unwrap();
            let ours = sorted(st.loop_poles.eigenvalues.clone());
            let theirs = sorted(eigenvalues(&benchmark_closed_loop(v, g)).unwrap());
            for (a, b) in ours.iter().zip(&theirs) {
                assert!(
                    (a - b).norm() <= 1e-10 * b.norm().max(1.0),
                    "at {v} m/s with {g:?}: {a} against the benchmark's {b}"
                );
            }
            let (poles, drift): (Vec<_>, Vec<_>) = st
                .closed_loop
                .iter()
                .partition(|m| m.kind != ModeKind::Drift);
            assert_eq!(poles.len(), 4, "{v} m/s: {:?}", st.closed_loop);
            assert!(drift.iter().all(|m| m.eigenvalue.norm() < 1e-6));
            for p in &ours {
                assert!(
                    poles
                        .iter()
                        .any(|m| (m.eigenvalue - p).norm() <= 1e-8 * p.norm().max(1.0)),
                    "{v} m/s: the loop pole {p} is not a closed-loop mode of every state"
                );
            }
            let stable = theirs.iter().all(|e| e.re < 0.0);
            assert_eq!(st.loop_poles.stable, stable);
            assert_eq!(st.margins.is_some(), stable);
            match r.verdict() {
                Verdict::Done => assert!(stable),
                Verdict::Negative(why) => assert!(!stable && why.contains("steer loop"), "{why}"),
            }
        }
    }
    // The verdict flips with the poles: lean and lean-rate feedback too weak for 3 m/s.
    let at = |gains: SteerGains| LinearSettings {
        speed: Some(3.0),
        steer: Some(SteerSettings::gains(gains)),
        ..LinearSettings::default()
    };
    let weak = analyse(
        &model,
        &at(SteerGains {
            k_phi: 20.0,
            k_phi_dot: 10.0,
            ..SteerGains::default()
        }),
    )
    .unwrap();
    assert!(matches!(weak.verdict(), Verdict::Negative(_)));
    assert!(matches!(
        analyse(&model, &at(GAINS[0])).unwrap().verdict(),
        Verdict::Done
    ));
}

/// A nilpotent block (states fed by others with nothing restoring them, as x and ψ by the
/// wheel speed of a bicycle at rest) beside an oscillator, ordered so that the block is lower
/// triangular: nalgebra's QR iteration alone never deflates it (its test is relative to the
/// diagonal, which the block drives to zero), and `eigenvalues` finds 0, 0, 0 and ±2i by its
/// shifted retry.
#[test]
fn eigenvalues_of_a_nilpotent_block_that_nalgebra_alone_does_not_deflate() {
    use nalgebra::Schur;
    #[rustfmt::skip]
    let a = DMatrix::from_row_slice(5, 5, &[
        0.0, -4.0, 0.0, 0.0, 0.0,
        1.0,  0.0, 0.0, 0.0, 0.0,
        0.0,  0.5, 0.0, 0.0, 0.0,
        0.0,  0.0, 2.0, 0.0, 0.0,
        0.0,  0.0, 0.0, 1.0, 0.0,
    ]);
    assert!(Schur::try_new(a.clone(), f64::EPSILON, 10_000).is_none());
    let mut found = eigenvalues(&a).unwrap();
    found.sort_by(|x, y| x.im.total_cmp(&y.im));
    let want = [
        Complex::new(0.0, -2.0),
        Complex::new(0.0, 0.0),
        Complex::new(0.0, 0.0),
        Complex::new(0.0, 0.0),
        Complex::new(0.0, 2.0),
    ];
    // A triple zero is found to about the cube root of the rounding (~1e-5 of ‖A‖).
    for (f, w) in found.iter().zip(&want) {
        assert!((f - w).norm() < 1e-4, "{found:?}");
    }
}

/// The bicycle at rest: x and ψ fed by the wheel speed with nothing restoring them make a
/// nilpotent block (see the test above); the modes are the benchmark's at v = 0 (±3.13,
/// ±5.53 1/s) and drift, and the verdict has no loop to judge.
#[test]
fn linearize_finds_the_modes_of_the_bicycle_at_rest() {
    use twv_analysis::api::{analyse, LinearSettings};
    use twv_analysis::jobs::{JobOutput, Verdict};
    use twv_analysis::linear::ModeKind;
    let r = analyse(&bicycle(), &LinearSettings::default()).unwrap();
    let theirs = eigenvalues(&benchmark_closed_loop(0.0, &SteerGains::default())).unwrap();
    let (modes, drift): (Vec<_>, Vec<_>) =
        r.open_loop.iter().partition(|m| m.kind != ModeKind::Drift);
    assert_eq!(modes.len(), 4, "{:?}", r.open_loop);
    assert!(drift.iter().all(|m| m.eigenvalue.norm() < 1e-6));
    for b in &theirs {
        assert!(
            modes
                .iter()
                .any(|m| (m.eigenvalue - b).norm() <= 1e-8 * b.norm()),
            "the benchmark's {b} at rest is not a mode: {modes:?}"
        );
    }
    assert!(r.pitch.is_none() && r.steer.is_none());
    assert!(matches!(r.verdict(), Verdict::Done));
}

#[test]
fn linearize_refuses_a_steer_law_without_its_steady_motion_in_one_line() {
    use twv_analysis::api::{analyse, At, LinearSettings};
    let law = Some(SteerSettings::gains(GAINS[0]));
    let error = |m: &ResolvedModel, s: LinearSettings| analyse(m, &s).unwrap_err().to_string();
    let cases = [
        (
            LinearSettings {
                steer: law,
                ..LinearSettings::default()
            },
            "speed too",
        ),
        (
            LinearSettings {
                speed: Some(f64::NAN),
                ..LinearSettings::default()
            },
            "speed",
        ),
        (
            LinearSettings {
                speed: Some(-2.0),
                ..LinearSettings::default()
            },
            "≥ 0",
        ),
        (
            LinearSettings {
                speed: Some(3.0),
                at: At::Hanging,
                ..LinearSettings::default()
            },
            "not both",
        ),
    ];
    for (s, needle) in cases {
        let e = error(&bicycle(), s);
        assert!(e.contains(needle) && !e.contains('\n'), "{e}");
    }
    let vehicle = ModelSpec::shipped("vehicle8").resolve().unwrap();
    let e = error(
        &vehicle,
        LinearSettings {
            speed: Some(3.0),
            steer: law,
            ..LinearSettings::default()
        },
    );
    assert!(e.contains("steady motion") && !e.contains('\n'), "{e}");
}

/// `phase --speed 3 --steer-gains "…;…"`: lean portraits of the steered bicycle. Each run starts
/// at the steady motion leaning by its tilt; each portrait's loop abscissa at the steady motion
/// is the lean-and-steer loop's (the linear steer loop, a second path); a stable design's runs
/// die out as fast as that abscissa says, a weak law's grow or fall — the verdict follows.
#[test]
fn the_steered_bicycles_phase_portraits_follow_its_steer_loop() {
    use twv_analysis::api::{portraits, Drive, PhaseSettings};
    use twv_analysis::control::{RunEnd, RunSettings};
    let bike = bicycle();
    let v = 3.0;
    let weak = SteerGains {
        k_phi: 20.0,
        k_phi_dot: 10.0,
        ..SteerGains::default()
    };
    let law = |gains| Drive::Steer(SteerSettings::gains(gains));
    let settings = PhaseSettings {
        portraits: vec![("design".into(), law(GAINS[0])), ("weak".into(), law(weak))],
        tilts: vec![0.02, -0.01],
        speed: Some(v),
        run: RunSettings {
            t_end: 8.0,
            ..RunSettings::default()
        },
        ..PhaseSettings::default()
    };
    let r = portraits(&bike, &settings, &Silent).unwrap();
    assert_eq!(r.plane, ["phi".to_string(), "w_phi".to_string()]);
    let steady = steady_state(&bike, v).unwrap();
    let lp = steer_loop(&bike, v).unwrap();
    let phi = bike.state_index("phi").unwrap();
    for (p, g) in r.portraits.iter().zip([GAINS[0], weak]) {
        let sigma = lp.closed_loop(&g).unwrap().spectral_abscissa;
        let ours = p.loop_abscissa.unwrap();
        assert!(
            (ours - sigma).abs() <= 1e-8 * sigma.abs().max(1.0),
            "{ours} against {sigma}"
        );
        assert_eq!(p.stable, sigma < 0.0);
        for (run, tilt) in p.runs.iter().zip(&settings.tilts) {
            let mut x0 = steady.clone();
            x0[phi] = *tilt;
            assert_eq!(run.x0, x0);
            let peak = run.points.iter().fold(0.0_f64, |m, q| m.max(q.0.abs()));
            if p.stable {
                assert!(
                    sigma * 8.0 < -2.0,
                    "the design decays within the run: σ = {sigma}"
                );
                assert!(matches!(run.end, RunEnd::Completed));
                assert!(run.final_phi.abs() < 0.05 * tilt.abs(), "{}", run.final_phi);
            } else {
                assert!(
                    matches!(run.end, RunEnd::Fell { .. }) || peak > 5.0 * tilt.abs(),
                    "the weak law's run stays within {peak}"
                );
            }
        }
    }
    // Bad input, one line each: a law without a speed, a speed on a model without a steady
    // motion, a law on a model without a steer input.
    let without_speed = PhaseSettings {
        speed: None,
        ..settings.clone()
    };
    let e = portraits(&bike, &without_speed, &Silent)
        .unwrap_err()
        .to_string();
    assert!(e.contains("speed") && !e.contains('\n'), "{e}");
    let vehicle = ModelSpec::shipped("vehicle8").resolve().unwrap();
    let e = portraits(&vehicle, &settings, &Silent)
        .unwrap_err()
        .to_string();
    assert!(e.contains("steady motion") && !e.contains('\n'), "{e}");
}
