//! The typed API called directly — no binary, no files — for every job, each against an
//! independent path or a known answer: the generated model itself, the interpreter, closed-form
//! eigenvalues, the Routh–Hurwitz threshold.

use std::path::PathBuf;

use twv_analysis::api::{
    analyse, audit_model, evaluate, generate, portraits, simulate, spectrum, sweep, tune_model, At,
    CodegenSettings, EvalSettings, LinearSettings, LoopVerdict, PhaseSettings, Recovery, Silent,
    SimSettings, SpectrumSettings, SweepSettings, TuneSettings, TuneVerdict,
};
use twv_analysis::audit::AuditSettings;
use twv_analysis::control::{ControllerSettings, STUDY_PD};
use twv_analysis::lyapunov::{Classification, LyapunovSettings};
use twv_analysis::model::{ModelSource, ModelSpec};
use twv_analysis::sweep::{Axis, Grid, Metric, Status};
use twv_analysis::Error;
use twv_model::Model;

fn repo(path: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(path)
}

fn shipped(name: &str) -> twv_analysis::model::ResolvedModel {
    ModelSpec::shipped(name).resolve().unwrap()
}

fn ir(path: &str) -> twv_analysis::model::ResolvedModel {
    ModelSpec {
        model: ModelSource::IrFile(repo(path)),
        ..ModelSpec::default()
    }
    .resolve()
    .unwrap()
}

const X8: [f64; 8] = [0.3, 1.0, 2.0, 0.5, -1.0, 2.0, 0.7, 3.0];

#[test]
fn eval_is_the_generated_model_and_the_interpreter_bit_for_bit() {
    let settings = EvalSettings {
        x: X8.to_vec(),
        u: Some(vec![3.0, -2.0]),
        jacobians: true,
    };
    let api = evaluate(&shipped("vehicle8"), &settings).unwrap();
    let m = twv_generated::Vehicle8::with_defaults();
    let mut f = [0.0; 8];
    m.f(&X8, &[3.0, -2.0], &mut f);
    assert_eq!(api.f, f.to_vec());
    let interp = evaluate(&ir("generated/ir/vehicle8.json"), &settings).unwrap();
    assert_eq!(
        api, interp,
        "the interpreter gives the generated code's bits"
    );
    // Bad input is a typed error naming the field.
    let short = EvalSettings {
        x: vec![0.1; 3],
        ..EvalSettings::default()
    };
    match evaluate(&shipped("vehicle8"), &short) {
        Err(Error::Input { field, reason }) => {
            assert_eq!(field, "x");
            assert!(reason.contains("8"), "{reason}");
        }
        other => panic!("expected an input error, got {other:?}"),
    }
    let huge = EvalSettings {
        x: vec![1e308; 3],
        ..EvalSettings::default()
    };
    assert!(matches!(
        evaluate(&shipped("lorenz"), &huge),
        Err(Error::NonFinite { .. })
    ));
}

#[test]
fn codegen_emits_the_model_and_bakes_on_request() {
    let runtime = generate(&shipped("lorenz"), &CodegenSettings::default()).unwrap();
    assert!(runtime.contains("pub struct Lorenz"), "{runtime}");
    let baked = generate(
        &shipped("lorenz"),
        &CodegenSettings {
            name: Some("MyLorenz".into()),
            baked: true,
        },
    )
    .unwrap();
    assert!(baked.contains("pub struct MyLorenz"));
    assert_ne!(runtime, baked);
}

#[test]
fn audit_passes_for_a_vehicle_and_refuses_what_it_cannot_audit() {
    let settings = AuditSettings {
        samples: 20,
        simulations: 1,
        ..AuditSettings::default()
    };
    assert!(audit_model(&shipped("vehicle7"), &settings).unwrap().passed);
    assert!(matches!(
        audit_model(&shipped("lorenz"), &settings),
        Err(Error::Unsupported { .. })
    ));
    let bad = AuditSettings {
        tolerance: -1.0,
        ..settings
    };
    assert!(matches!(
        audit_model(&shipped("vehicle7"), &bad),
        Err(Error::Input { .. })
    ));
}

/// An 11-state IR (larger than any shipped model) runs on the interpreter, and its spectrum is
/// the real parts −1 + a cos(2πk/11) of the ring's eigenvalues (a normal matrix: the
/// finite-time exponents are exact up to the RK4 error).
#[test]
fn spectrum_of_an_eleven_state_ring_is_its_eigenvalues() {
    let model = ir("tests/data/ring11.json");
    assert_eq!(model.ir.nx(), 11);
    let result = spectrum(
        &model,
        &SpectrumSettings {
            x0: vec![0.0; 11],
            // After a transient the basis spans the ring's dominant eigenspaces; a normal matrix
            // then stretches each by exactly e^(Re λ · t).
            lyapunov: LyapunovSettings {
                iterations: 50,
                transient: 100.0,
                ..LyapunovSettings::preset_paper()
            },
            ..SpectrumSettings::default()
        },
        &Silent,
    )
    .unwrap();
    let a = model.param("a").unwrap();
    let mut expected: Vec<f64> = (0..11)
        .map(|k| -1.0 + a * (2.0 * std::f64::consts::PI * k as f64 / 11.0).cos())
        .collect();
    expected.sort_by(|x, y| y.total_cmp(x));
    // The gaps between the ring's rates are ~0.08 /s: after 100 s the basis is aligned to
    // e^(−8) ≈ 3e-4; the sum (the trace, −11) does not depend on the alignment at all.
    for (l, e) in result.result.exponents.iter().zip(&expected) {
        assert!((l - e).abs() < 1e-3, "{l} vs {e}");
    }
    assert!(
        (result.result.sum + 11.0).abs() < 1e-9,
        "{}",
        result.result.sum
    );
    assert!(matches!(
        result.result.classification,
        Classification::Equilibrium { unstable: 0 }
    ));
}

#[test]
fn closed_loop_spectrum_has_the_loop_poles_and_the_drift_zeros() {
    let result = spectrum(
        &shipped("vehicle8"),
        &SpectrumSettings {
            x0: vec![0.0; 8],
            controller: Some(ControllerSettings::pid(STUDY_PD)),
            lyapunov: LyapunovSettings {
                transient: 20.0,
                iterations: 400,
                ..LyapunovSettings::preset_paper()
            },
            ..SpectrumSettings::default()
        },
        &Silent,
    )
    .unwrap();
    let l = &result.result.exponents;
    // At the upright the closed loop rests: its exponents are the real parts of its
    // eigenvalues, the two loop poles (−1.362, −21.690 with the study setpoint) and the drift
    // zeros, whose shear (x with v_x) decays only like ln t / t.
    assert!((l[l.len() - 1] + 21.6898).abs() < 1e-3, "{l:?}");
    assert!(l.iter().any(|v| (v + 1.36208).abs() < 1e-3), "{l:?}");
    assert!(l[0].abs() < result.result.zero_floor, "{l:?}");
    assert_eq!(result.drift_states, ["x", "y", "theta"]);
}

#[test]
fn simulate_recovers_above_the_threshold_and_falls_below() {
    let model = shipped("vehicle8");
    let run = |kp: f64| {
        let mut controller = ControllerSettings::default();
        controller.pitch.gains.kp = kp;
        simulate(
            &model,
            &SimSettings {
                controller,
                ..SimSettings::default()
            },
            &Silent,
        )
        .unwrap()
    };
    let ok = run(STUDY_PD.kp);
    assert_eq!(ok.recovery, Recovery::Recovered);
    assert!((ok.metrics.phi.settling_time.unwrap() - 2.93).abs() < 0.01);
    assert_eq!(run(800.0).recovery, Recovery::Fell);
}

#[test]
fn phase_portraits_name_the_stable_gain_sets() {
    let out = portraits(&shipped("vehicle8"), &PhaseSettings::default(), &Silent).unwrap();
    let stable: Vec<bool> = out.portraits.iter().map(|p| p.stable).collect();
    // (a) Ki above the Routh–Hurwitz limit, (b) below it, (c) Kp < M_x g, (d) the study's PD.
    assert_eq!(stable, [false, true, false, true]);
}

#[test]
fn linear_margins_exist_only_for_a_stable_loop() {
    let model = shipped("vehicle8");
    let up = analyse(&model, &LinearSettings::default()).unwrap();
    let pitch = up.pitch.as_ref().unwrap();
    assert_eq!(pitch.verdict, LoopVerdict::Stable);
    let m = pitch.margins.as_ref().unwrap();
    let mx_g = 123.0 * 9.81;
    assert!((m.gain_margin_lower - mx_g / STUDY_PD.kp).abs() < 1e-6);
    let hanging = analyse(
        &model,
        &LinearSettings {
            at: At::Hanging,
            ..LinearSettings::default()
        },
    )
    .unwrap();
    let pitch = hanging.pitch.as_ref().unwrap();
    assert_eq!(pitch.verdict, LoopVerdict::Unstable);
    assert!(pitch.margins.is_none());
    // Not an equilibrium: refused, unless asked for.
    let tilted = LinearSettings {
        at: At::State(vec![0.3, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        ..LinearSettings::default()
    };
    assert!(matches!(analyse(&model, &tilted), Err(Error::Input { .. })));
    let allowed = analyse(
        &model,
        &LinearSettings {
            allow_non_equilibrium: true,
            ..tilted
        },
    )
    .unwrap();
    assert!(!allowed.equilibrium && allowed.residual > 1.0);
}

#[test]
fn tune_meets_the_default_spec_and_an_effort_bound_can_make_it_infeasible() {
    let model = shipped("vehicle8");
    let met = tune_model(&model, &TuneSettings::default()).unwrap();
    assert_eq!(met.verdict, TuneVerdict::Met);
    assert!(met.result.certificate.as_ref().unwrap().meets_spec);
    // dpm ≥ 60 needs Kp ≥ 4.5·10³ (the lower disk gain bound at DC), i.e. ≥ 450 N after a
    // 0.1 rad tilt: a 300 N bound cannot be met, and every part of the answer says so.
    let bounded = tune_model(
        &model,
        &TuneSettings {
            spec: "dpm>=60,force<=300".parse().unwrap(),
            ..TuneSettings::default()
        },
    )
    .unwrap();
    assert_eq!(bounded.verdict, TuneVerdict::Infeasible);
    assert!(!bounded.result.met());
    if let Some(c) = &bounded.result.certificate {
        assert!(!c.meets_spec);
    }
    let loose = tune_model(
        &model,
        &TuneSettings {
            spec: "dpm>=60,force<=600".parse().unwrap(),
            ..TuneSettings::default()
        },
    )
    .unwrap();
    assert_eq!(loose.verdict, TuneVerdict::Met);
    assert!(loose.tilt_check.unwrap().peak_force <= 600.0);
}

#[test]
fn sweep_in_memory_has_one_result_per_point() {
    let grid = Grid {
        kp: Axis {
            lo: 0.0,
            hi: 4000.0,
            n: 5,
        },
        kd: Axis {
            lo: 500.0,
            hi: 1500.0,
            n: 3,
        },
        ki: None,
        params: Vec::new(),
    };
    let points = sweep(
        &shipped("vehicle8"),
        &SweepSettings::new(grid, Metric::SettlingTime),
        &Silent,
    )
    .unwrap();
    assert_eq!(points.len(), 15);
    // Above Kp = M_x g / 0.97 (the study setpoint's factor) the tilt settles; below it the
    // vehicle falls or, near the threshold, drifts away too slowly to fall within 10 s.
    for p in &points {
        if p.kp * 0.97 > 123.0 * 9.81 {
            assert_eq!(p.status, Status::Ok, "{p:?}");
        } else {
            assert!(
                matches!(p.status, Status::Fell | Status::NotSettled),
                "{p:?}"
            );
        }
    }
}

/// The type a dispatch hands to generic code, by name.
struct TypeOf;

impl twv_analysis::model::ModelTask for TypeOf {
    type Output = &'static str;
    fn run<const NX: usize, const NU: usize, M: Model<NX, NU>>(
        self,
        _: &M,
        _: &twv_analysis::model::ResolvedModel,
    ) -> twv_analysis::Result<&'static str> {
        Ok(std::any::type_name::<M>())
    }
}

impl twv_analysis::model::ControlTask for TypeOf {
    type Output = &'static str;
    fn run<const NX: usize, const NU: usize, const NA: usize, M: Model<NX, NU>>(
        self,
        _: &M,
        _: &twv_analysis::model::ResolvedModel,
    ) -> twv_analysis::Result<&'static str> {
        Ok(std::any::type_name::<M>())
    }
}

/// Every job is compiled once per model type it is handed, so a shipped model must reach the
/// jobs as the same type as any IR of its state count (its generated code one variant, the
/// interpreter another): then shipping a model adds no instantiation of any job. Checked for
/// every shipped model against its own IR on the interpreter, open-loop and, for the vehicles,
/// closed-loop.
#[test]
fn a_shipped_model_and_an_ir_of_its_size_reach_the_jobs_as_one_type() {
    use twv_analysis::model::{dispatch, dispatch_control, Engine};
    for name in ["vehicle8", "vehicle7", "segway7", "lorenz", "henon_heiles"] {
        let generated = shipped(name);
        let interpreted = ir(&format!("generated/ir/{name}.json"));
        assert_eq!(generated.engine, Engine::Generated(name.into()), "{name}");
        assert_eq!(interpreted.engine, Engine::Interpreted, "{name}");
        let (a, b) = (
            dispatch(&generated, TypeOf).unwrap(),
            dispatch(&interpreted, TypeOf).unwrap(),
        );
        assert_eq!(a, b, "{name}: open-loop jobs see two types");
        if name.starts_with("vehicle") || name == "segway7" {
            for nz in 0..=3 {
                let (a, b) = (
                    dispatch_control(&generated, nz, TypeOf).unwrap(),
                    dispatch_control(&interpreted, nz, TypeOf).unwrap(),
                );
                assert_eq!(a, b, "{name}, {nz} controller states: two types");
            }
        }
    }
}
