//! The PID pitch controller (issue 6): the study's PD recovers the vehicle from its tilts (and
//! what it does not regulate drifts), the closed-loop tangent is exact, closed-loop Lyapunov
//! exponents equal the eigenvalues' real parts at the upright, eigenvalues agree with
//! Routh–Hurwitz, anti-windup bounds the integral, and the metrics are right on known signals.

use nalgebra::DMatrix;
use twv_analysis::control::{
    response_metrics, run_closed_loop, scenario, AntiWindup, ControlError, ControllerSettings,
    PidLoop, PitchPid, Plant, Profile, RunEnd, RunSettings, Setpoint, VelocityLoop, YawLoop,
    STUDY_PD,
};
use twv_analysis::integrate::VectorField;
use twv_analysis::linear::{eigenvalues, CartPendulum, PidGains};
use twv_analysis::lyapunov::{lyapunov_spectrum, IntegratorChoice, LyapunovSettings};
use twv_analysis::progress::Silent;
use twv_generated::{Segway7, Vehicle8};
use twv_model::{Model, ModelInfo};

fn param(names: &[twv_model::ParamInfo], values: &[f64], name: &str) -> Option<f64> {
    names.iter().position(|p| p.name == name).map(|i| values[i])
}

fn vehicle8() -> Vehicle8 {
    Vehicle8::with_defaults()
}

fn plant8(model: &Vehicle8) -> Plant<2> {
    Plant::from_info(&model.info(), &|n| {
        param(&Vehicle8::PARAMS, &Vehicle8::DEFAULTS, n)
    })
    .unwrap()
}

/// The paper vehicle as a cart–pendulum (M_x = m1 + m2), the Routh–Hurwitz reference.
fn cart8() -> CartPendulum {
    let p = |n| param(&Vehicle8::PARAMS, &Vehicle8::DEFAULTS, n).unwrap();
    CartPendulum::from_vehicle(p("m1"), p("m2"), p("b"), p("I2_yy"), p("g")).unwrap()
}

fn pitch(gains: PidGains, setpoint: Setpoint) -> ControllerSettings {
    ControllerSettings {
        pitch: PitchPid {
            gains,
            setpoint,
            ..PitchPid::default()
        },
        ..ControllerSettings::default()
    }
}

fn run5() -> RunSettings {
    RunSettings {
        t_end: 6.0,
        ..RunSettings::default()
    }
}

#[test]
fn study_pd_recovers_vehicle8_from_forward_and_backward_tilts_and_drifts() {
    let model = vehicle8();
    let settings = ControllerSettings::default();
    let field = PidLoop::<_, 8, 2, 8>::new(&model, &settings, plant8(&model)).unwrap();
    let states = model.info().states;
    let idx = |n: &str| states.iter().position(|s| *s == n).unwrap();
    for phi0 in [0.1, -0.1, 0.2, -0.2] {
        let x0 = scenario::tilted::<8>(states, phi0).unwrap();
        let run = run_closed_loop(&field, &x0, &run5(), &Silent).unwrap();
        let m = &run.metrics;
        let last = run.trajectory.last();
        println!(
            "Φ0 = {phi0:+}: settling {:?} s, overshoot {:?}, peak F {:.1} N, final v_x {:+.4} m/s, x {:+.4} m, v_y {:e}, θ {:e}, w_z {:e}",
            m.phi.settling_time, m.phi.overshoot, m.peak_force, m.final_v_x.unwrap(),
            m.x_displacement.unwrap(), last[idx("v_y")], last[idx("theta")], last[idx("w_z")]
        );
        assert_eq!(run.trajectory.end, RunEnd::Completed);
        // Pitch recovered: within 2 % in a few seconds, and no overshoot (both poles real).
        let ts = m.phi.settling_time.expect("settles");
        assert!(ts < 4.0, "settling {ts}");
        assert!(last[idx("phi")].abs() < 1e-3 * phi0.abs());
        assert!(m.phi.overshoot.unwrap() < 1e-3);
        // The pitch-only loop does not regulate the velocity: the vehicle keeps moving at a
        // constant speed, in the direction of the lean.
        let v = m.final_v_x.unwrap();
        assert!(v * phi0 > 0.0 && v.abs() > 0.5 * phi0.abs(), "drift {v}");
        assert!((last[idx("w_y")]).abs() < 1e-3);
        // With T2 = 0 the motion stays planar: no lateral velocity, no yaw (mirror symmetry).
        for s in ["y", "theta", "v_y", "w_z"] {
            assert_eq!(last[idx(s)], 0.0, "{s}");
        }
    }
}

/// Central differences of the field's own `rhs`, column by column.
fn finite_difference<F: VectorField<N>, const N: usize>(
    field: &F,
    t: f64,
    x: &[f64; N],
) -> [[f64; N]; N] {
    let mut j = [[0.0; N]; N];
    for c in 0..N {
        let h = 1e-6 * x[c].abs().max(1.0);
        let (mut xp, mut xm) = (*x, *x);
        xp[c] += h;
        xm[c] -= h;
        let (mut fp, mut fm) = ([0.0; N], [0.0; N]);
        field.rhs(t, &xp, &mut fp);
        field.rhs(t, &xm, &mut fm);
        for r in 0..N {
            j[r][c] = (fp[r] - fm[r]) / (2.0 * h);
        }
    }
    j
}

fn assert_tangent_exact<F: VectorField<N>, const N: usize>(
    field: &F,
    t: f64,
    x: &[f64; N],
    what: &str,
) {
    let mut exact = [[0.0; N]; N];
    field.jacobian(t, x, &mut exact);
    let fd = finite_difference(field, t, x);
    let scale = exact.iter().flatten().fold(1.0_f64, |m, v| m.max(v.abs()));
    for r in 0..N {
        for c in 0..N {
            let d = (exact[r][c] - fd[r][c]).abs();
            assert!(
                d < 1e-6 * scale,
                "{what}: J[{r}][{c}] = {} vs FD {}",
                exact[r][c],
                fd[r][c]
            );
        }
    }
    let tr: f64 = (0..N).map(|i| exact[i][i]).sum();
    assert!(
        (field.trace_jacobian(t, x) - tr).abs() < 1e-10 * scale,
        "{what}: trace"
    );
}

#[test]
fn closed_loop_tangent_is_exact_with_every_controller_part() {
    let model = vehicle8();
    // PID + rate filter + study setpoint + velocity PI + yaw P: 3 controller states, NA = 11.
    let settings = ControllerSettings {
        pitch: PitchPid {
            gains: PidGains {
                kp: 3860.0,
                ki: 900.0,
                kd: 1980.0,
            },
            setpoint: Setpoint::STUDY,
            derivative_filter: Some(0.02),
            saturation: Some(5000.0),
            anti_windup: AntiWindup::BackCalculation { tracking_time: 0.5 },
        },
        velocity: Some(VelocityLoop {
            kp: 0.05,
            ki: 0.01,
            reference: Profile::constant(1.0),
            lean_max: None,
        }),
        yaw: Some(YawLoop {
            kp: 40.0,
            reference: Profile::constant(0.2),
        }),
    };
    let field = PidLoop::<_, 8, 2, 11>::new(&model, &settings, plant8(&model)).unwrap();
    assert_tangent_exact(&field, 0.0, &[0.0; 11], "upright");
    let generic = [0.12, 0.3, -0.2, 0.4, -0.3, 0.8, 0.1, 0.25, 0.01, -0.05, 0.2];
    assert_tangent_exact(&field, 1.3, &generic, "generic state");
    // Saturated (back-calculation branch active): F_cmd ≈ 3860·0.5 > 1000.
    let sat = ControllerSettings {
        pitch: PitchPid {
            saturation: Some(1000.0),
            ..settings.pitch
        },
        ..settings.clone()
    };
    let field = PidLoop::<_, 8, 2, 11>::new(&model, &sat, plant8(&model)).unwrap();
    let x = [0.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    assert!(field.command(0.0, &x).saturated);
    assert_tangent_exact(&field, 0.0, &x, "saturated");
    // The segway's wheel-torque map, with PID (NA = 8).
    let seg = Segway7::with_defaults();
    let plant = Plant::<2>::from_info(&seg.info(), &|n| {
        param(&Segway7::PARAMS, &Segway7::DEFAULTS, n)
    })
    .unwrap();
    let s = ControllerSettings::pid(PidGains {
        kp: 3000.0,
        ki: 500.0,
        kd: 800.0,
    });
    let field = PidLoop::<_, 7, 2, 8>::new(&seg, &s, plant).unwrap();
    assert_tangent_exact(
        &field,
        0.0,
        &[0.1, 0.0, 0.0, 0.2, 0.3, 0.5, 0.1, 0.02],
        "segway7",
    );
}

/// A + B k for F = k·x on F1, from the model's own jac_x and jac_u (independent of PidLoop).
fn pd_closed_loop_matrix(model: &Vehicle8, kp_eff: f64, kd: f64) -> DMatrix<f64> {
    let (x, u) = ([0.0; 8], [0.0; 2]);
    let (mut a, mut b) = ([[0.0; 8]; 8], [[0.0; 2]; 8]);
    model.jac_x(&x, &u, &mut a);
    model.jac_u(&x, &u, &mut b);
    let mut k = [0.0; 8];
    k[0] = kp_eff; // phi
    k[4] = kd; // w_y
    DMatrix::from_fn(8, 8, |i, j| a[i][j] + b[i][0] * k[j])
}

#[test]
fn closed_loop_exponents_at_the_upright_equal_eigenvalue_real_parts() {
    let model = vehicle8();
    let settings = ControllerSettings::default(); // study PD with 0.03 sin Φ
    let field = PidLoop::<_, 8, 2, 8>::new(&model, &settings, plant8(&model)).unwrap();
    // d/dΦ (Φ − 0.03 sin Φ) = 0.97 at the upright.
    let acl = pd_closed_loop_matrix(&model, 0.97 * STUDY_PD.kp, STUDY_PD.kd);
    let mut re: Vec<f64> = eigenvalues(&acl).unwrap().iter().map(|e| e.re).collect();
    re.sort_by(|a, b| b.total_cmp(a));
    let s = LyapunovSettings {
        t_sample: 0.1,
        iterations: 400,
        transient: 20.0,
        integrator: IntegratorChoice::Rk4 { h: 1e-3 },
        ..LyapunovSettings::default()
    };
    let r = lyapunov_spectrum::<_, 8, 8>(&field, &[0.0; 8], &s).unwrap();
    println!("eigenvalue real parts {re:?}\nexponents {:?}", r.exponents);
    // The two pitch-loop modes: the exponents are their real parts to round-off level (the
    // transient aligned the basis, so no O(1/T) start-up term is left).
    for (l, e) in r.exponents[6..].iter().zip(&re[6..]) {
        assert!((l - e).abs() < 1e-6 * e.abs(), "{l} vs {e}");
    }
    // Six zero eigenvalues: the drift the pitch loop does not move (x, y, θ, v_x, v_y, w_z).
    // x = ∫v_x is a Jordan block, so its pair of finite-time exponents is ±ln((T0 + T)/T0)/T
    // (polynomial growth), here ±ln 3/40 ≈ ±0.0275; the other four are zero.
    let jordan = (60.0_f64 / 20.0).ln() / 40.0;
    assert!(re[..6].iter().all(|e| e.abs() < 1e-9));
    assert!(
        (r.exponents[0] - jordan).abs() < 0.05 * jordan,
        "{}",
        r.exponents[0]
    );
    assert!(
        (r.exponents[5] + jordan).abs() < 0.05 * jordan,
        "{}",
        r.exponents[5]
    );
    assert!(r.exponents[1..5].iter().all(|l| l.abs() < 1e-9));
    let tr = r.mean_trace.unwrap();
    assert!(
        (r.sum - tr).abs() < 1e-8 * tr.abs(), // RK4's own error on the −21.7 mode
        "Σλ = {} vs ⟨tr J⟩ = {tr}",
        r.sum
    );
}

fn dense<F: VectorField<N>, const N: usize>(field: &F, x: &[f64; N]) -> DMatrix<f64> {
    let mut m = [[0.0; N]; N];
    field.jacobian(0.0, x, &mut m);
    DMatrix::from_fn(N, N, |r, c| m[r][c])
}

#[test]
fn closed_loop_stability_by_eigenvalues_agrees_with_routh_hurwitz() {
    let model = vehicle8();
    let cp = cart8();
    let mxg = cp.m_x * cp.g;
    let mut checked = 0;
    for kp_ratio in [0.8, 0.95, 1.05, 1.5, 3.0] {
        for kd in [50.0, 600.0] {
            let kp = kp_ratio * mxg;
            let limit = cp.ki_limit(kp, kd).max(100.0);
            for ki in [0.0, 0.5 * limit, 1.5 * limit] {
                let gains = PidGains { kp, ki, kd };
                let settings = pitch(gains, Setpoint::Zero);
                let plant = plant8(&model);
                // The closed-loop Jacobian from the augmented field (∫Φ is a state when Ki ≠ 0).
                let j = if ki == 0.0 {
                    let f = PidLoop::<_, 8, 2, 8>::new(&model, &settings, plant).unwrap();
                    dense(&f, &[0.0; 8])
                } else {
                    let f = PidLoop::<_, 8, 2, 9>::new(&model, &settings, plant).unwrap();
                    dense(&f, &[0.0; 9])
                };
                // The zero eigenvalues are the drift modes the pitch loop cannot move.
                let loop_eigs: Vec<_> = eigenvalues(&j)
                    .unwrap()
                    .into_iter()
                    .filter(|e| e.norm() > 1e-6)
                    .collect();
                let stable = loop_eigs.iter().all(|e| e.re < 0.0);
                assert_eq!(
                    stable,
                    cp.routh_hurwitz_stable(&gains),
                    "Kp = {kp}, Ki = {ki}, Kd = {kd}: eigenvalues {loop_eigs:?}"
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 30);
}

/// Ki = 10⁴ with |F| ≤ 200 N from a 0.15 rad tilt: without anti-windup the integral winds up
/// while the force saturates, the loop overshoots and the vehicle falls; conditional integration
/// and back-calculation keep the integral an order of magnitude smaller and recover.
#[test]
fn anti_windup_keeps_the_integral_bounded_under_saturation() {
    let model = vehicle8();
    let gains = PidGains {
        kp: 3860.0,
        ki: 1e4,
        kd: 1980.0,
    };
    let run = RunSettings {
        t_end: 8.0,
        ..RunSettings::default()
    };
    let x0 = scenario::tilted::<8>(model.info().states, 0.15).unwrap();
    let mut peaks = Vec::new();
    for aw in [
        AntiWindup::None,
        AntiWindup::Conditional,
        AntiWindup::BackCalculation { tracking_time: 0.3 },
    ] {
        let settings = ControllerSettings {
            pitch: PitchPid {
                gains,
                setpoint: Setpoint::Zero,
                saturation: Some(200.0),
                anti_windup: aw,
                ..PitchPid::default()
            },
            ..ControllerSettings::default()
        };
        let field = PidLoop::<_, 8, 2, 9>::new(&model, &settings, plant8(&model)).unwrap();
        let r = run_closed_loop(&field, &x0, &run, &Silent).unwrap();
        let zmax = r
            .trajectory
            .component(8)
            .iter()
            .fold(0.0_f64, |m, v| m.max(v.abs()));
        println!(
            "{aw:?}: {:?}, max |∫e| {zmax:.4} rad s, saturated {:.0} % of samples, settling {:?} s",
            r.trajectory.end,
            100.0 * r.metrics.saturated_fraction,
            r.metrics.phi.settling_time
        );
        assert!(r.commands.iter().all(|c| c.force.abs() <= 200.0));
        peaks.push((aw, r.trajectory.end, zmax, r.metrics.phi.settling_time));
    }
    let (_, end, wound, _) = peaks[0];
    assert!(
        matches!(end, RunEnd::Fell { .. }),
        "no anti-windup: {end:?}"
    );
    for &(aw, end, zmax, settling) in &peaks[1..] {
        assert_eq!(end, RunEnd::Completed, "{aw:?}");
        assert!(settling.is_some_and(|t| t < 7.0), "{aw:?}: {settling:?}");
        assert!(zmax < 0.1 && zmax < 0.2 * wound, "{aw:?}: {zmax}");
    }
}

#[test]
fn metrics_of_known_signals() {
    let tau = 0.5;
    let t: Vec<f64> = (0..=4000).map(|i| i as f64 * 1e-3).collect();
    let y: Vec<f64> = t.iter().map(|t| 1.0 - (-t / tau).exp()).collect();
    let m = response_metrics(&t, &y, 1.0, 0.02);
    println!("{m:?}");
    assert_eq!(m.overshoot, Some(0.0));
    let ts = m.settling_time.unwrap();
    assert!((ts - tau * 50f64.ln()).abs() < 2e-3, "{ts}");
    assert!((m.iae - tau).abs() < 1e-3 * tau, "{}", m.iae);
    assert!((m.ise - tau / 2.0).abs() < 1e-3 * tau, "{}", m.ise);
    // Second order, ζ = 0.3: overshoot exp(−πζ/√(1−ζ²)).
    let (zeta, wn) = (0.3_f64, 4.0_f64);
    let wd = wn * (1.0 - zeta * zeta).sqrt();
    let y: Vec<f64> = t
        .iter()
        .map(|t| {
            1.0 - (-zeta * wn * t).exp()
                * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin())
        })
        .collect();
    let m = response_metrics(&t, &y, 1.0, 0.02);
    let expected = (-std::f64::consts::PI * zeta / (1.0 - zeta * zeta).sqrt()).exp();
    assert!(
        (m.overshoot.unwrap() - expected).abs() < 1e-4,
        "{:?} vs {expected}",
        m.overshoot
    );
    // A signal still outside the band at the end has not settled.
    let y: Vec<f64> = t.iter().map(|t| 1.0 - (-t / tau).exp()).collect();
    let m = response_metrics(&t[..1000], &y[..1000], 1.0, 0.02);
    assert_eq!(m.settling_time, None);
}

#[test]
fn unrecognised_inputs_are_a_clear_error() {
    let info = ModelInfo {
        name: "cart",
        ir_hash: "",
        states: &["phi", "x", "w_y", "v_x"],
        inputs: &["push"],
        params: &[],
    };
    let err = Plant::<1>::from_info(&info, &|_| None).unwrap_err();
    assert!(matches!(err, ControlError::UnrecognisedInputs { .. }));
    assert!(err.to_string().contains("push"), "{err}");
}

/// segway7: the same PD force realised as equal wheel torques τ_L = τ_R = F R/2 stabilises the
/// pitch too (the motor reaction on the chassis helps), and leaves the same kind of drift.
#[test]
fn segway7_wheel_torques_realise_the_force() {
    let model = Segway7::with_defaults();
    let r = param(&Segway7::PARAMS, &Segway7::DEFAULTS, "R").unwrap();
    let plant = Plant::<2>::from_info(&model.info(), &|n| {
        param(&Segway7::PARAMS, &Segway7::DEFAULTS, n)
    })
    .unwrap();
    let settings = ControllerSettings::default();
    let field = PidLoop::<_, 7, 2, 7>::new(&model, &settings, plant).unwrap();
    let x0 = scenario::tilted::<7>(model.info().states, 0.1).unwrap();
    let run = run_closed_loop(&field, &x0, &run5(), &Silent).unwrap();
    for c in &run.commands {
        assert_eq!(c.u[0], c.u[1]);
        assert!((c.u[0] - c.force * r / 2.0).abs() <= 1e-12 * c.force.abs().max(1.0));
    }
    let m = &run.metrics;
    println!(
        "segway7: settling {:?}, final v_x {:?}",
        m.phi.settling_time, m.final_v_x
    );
    assert!(m.phi.settling_time.is_some_and(|t| t < 4.0));
    assert!(m.final_v_x.unwrap() > 0.0);
}

/// The velocity loop turns the pitch controller into a vehicle that starts, cruises and stops:
/// v_x follows the trapezoid and the vehicle comes to rest.
#[test]
fn maneuver_tracks_the_velocity_reference_and_stops() {
    let model = vehicle8();
    let profile = scenario::maneuver(2.0, 3.0, 5.0).unwrap();
    let t_end = profile.t_last() + 10.0;
    let settings = ControllerSettings {
        velocity: Some(VelocityLoop {
            kp: 0.08,
            ki: 0.03,
            reference: profile,
            lean_max: None,
        }),
        ..ControllerSettings::default()
    };
    let field = PidLoop::<_, 8, 2, 9>::new(&model, &settings, plant8(&model)).unwrap();
    let run = RunSettings {
        t_end,
        ..RunSettings::default()
    };
    let r = run_closed_loop(&field, &[0.0; 8], &run, &Silent).unwrap();
    let v = r.trajectory.component(5);
    let cruise_end = r.trajectory.t.iter().position(|t| *t >= 9.0).unwrap();
    println!(
        "v_x at the end of the cruise {:.3}, peak {:.3}, final {:.2e}, distance {:?}",
        v[cruise_end],
        v.iter().fold(0.0_f64, |m, v| m.max(*v)),
        r.metrics.final_v_x.unwrap(),
        r.metrics.x_displacement
    );
    assert!((v[cruise_end] - 2.0).abs() < 0.2);
    assert!(r.metrics.final_v_x.unwrap().abs() < 0.05);
    assert!(r.metrics.final_phi.abs() < 0.01);
}

/// A 3 m/s velocity step with the force limited to 300 N: the unlimited velocity loop asks for a
/// 0.24 rad lean at once, the recovery force saturates and the vehicle falls; with the lean
/// limited to 0.05 rad the force stays in range and the vehicle reaches 3 m/s. While limited the
/// tangent is the limit's (the lean's derivative vanishes, the integral holds).
#[test]
fn lean_limit_carries_a_saturating_velocity_step() {
    let model = vehicle8();
    let step = |lean_max| ControllerSettings {
        pitch: PitchPid {
            saturation: Some(300.0),
            ..PitchPid::default()
        },
        velocity: Some(VelocityLoop {
            kp: 0.08,
            ki: 0.03,
            reference: Profile::constant(3.0),
            lean_max,
        }),
        ..ControllerSettings::default()
    };
    let run = RunSettings {
        t_end: 25.0,
        ..RunSettings::default()
    };
    let free = step(None);
    let field = PidLoop::<_, 8, 2, 9>::new(&model, &free, plant8(&model)).unwrap();
    let r = run_closed_loop(&field, &[0.0; 8], &run, &Silent).unwrap();
    assert!(
        matches!(r.trajectory.end, RunEnd::Fell { .. }),
        "without a lean limit the step should end in a fall: {:?}",
        r.trajectory.end
    );

    let limited = step(Some(0.05));
    let field = PidLoop::<_, 8, 2, 9>::new(&model, &limited, plant8(&model)).unwrap();
    let r = run_closed_loop(&field, &[0.0; 8], &run, &Silent).unwrap();
    assert_eq!(r.trajectory.end, RunEnd::Completed);
    let v_final = r.metrics.final_v_x.unwrap();
    println!("lean-limited 3 m/s step: final v_x {v_final:.4} m/s");
    assert!((v_final - 3.0).abs() < 0.06, "final v_x {v_final}");
    // The setpoint never leans past the study setpoint plus the limit.
    for (t, x) in r.trajectory.t.iter().zip(&r.trajectory.x) {
        let xa: [f64; 9] = std::array::from_fn(|i| x.get(i).copied().unwrap_or(0.0));
        let cmd = field.command(*t, &xa);
        assert!(cmd.phi_ref.abs() <= 0.05 + 0.03 * x[0].sin().abs() + 1e-12);
    }

    // Limited (v_x = 0: e_v = 3, lean 0.24 → 0.05) and not (v_x = 2.9): exact tangents.
    let mut x = [0.02, 0.0, 0.0, 0.0, 0.1, 0.0, 0.05, 0.3, 0.4];
    assert!(field.command(0.0, &x).phi_ref > 0.049);
    assert_tangent_exact(&field, 0.0, &x, "lean limited");
    x[5] = 2.9;
    assert_tangent_exact(&field, 0.0, &x, "lean within its limit");
}
