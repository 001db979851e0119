//! The audit: generated vs hand model passes for every vehicle and both parameter files, and
//! deliberate mistakes fail it, naming the equation — including a dropped gyroscopic pair that
//! conserves energy and so only a term-by-term comparison can find.

use std::path::PathBuf;

use twv_analysis::api::audit_model;
use twv_analysis::audit::{audit, AuditReport, AuditSettings};
use twv_analysis::hand_model::{HandSegway7, HandVehicle7, HandVehicle8, Mistake, VehicleParams};
use twv_analysis::model::{ModelSpec, ParamSource};

fn vehicle_file(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../vehicles")
        .join(name)
}

fn settings() -> AuditSettings {
    AuditSettings {
        samples: 100,
        ..Default::default()
    }
}

#[test]
fn every_vehicle_passes_with_both_parameter_files() {
    for file in ["paper.toml", "segway.toml"] {
        for model in ["vehicle8", "vehicle7", "segway7"] {
            let resolved = ModelSpec::shipped(model)
                .with_params(ParamSource::File(vehicle_file(file)))
                .resolve()
                .unwrap();
            let report = audit_model(&resolved, &settings()).unwrap();
            assert!(report.passed, "{model} with {file}:\n{}", report.table());
            let worst = report
                .quantities
                .iter()
                .fold(0.0_f64, |m, q| m.max(q.max_rel));
            assert!(
                worst < 1e-13,
                "{model} with {file}: worst term error {worst:e}"
            );
        }
    }
}

fn paper() -> VehicleParams {
    let loaded = ModelSpec::shipped("vehicle8")
        .with_params(ParamSource::File(vehicle_file("paper.toml")))
        .resolve()
        .unwrap();
    let value = |n: &str| loaded.param(n).unwrap();
    VehicleParams {
        m1: value("m1"),
        m2: value("m2"),
        g: value("g"),
        a: value("a"),
        b: value("b"),
        c: value("c"),
        i1: [value("I1_xx"), value("I1_yy"), value("I1_zz")],
        i2: [value("I2_xx"), value("I2_yy"), value("I2_zz")],
        r: value("R"),
        m_w: value("m_w"),
        j_a: value("J_a"),
        j_d: value("J_d"),
    }
}

fn failing_entries(report: &AuditReport) -> Vec<String> {
    report
        .quantities
        .iter()
        .flat_map(|q| q.entries.iter())
        .filter(|e| e.max_rel > report.tolerance)
        .map(|e| e.label.clone())
        .collect()
}

#[test]
fn dropped_gyroscopic_pair_fails_although_energy_balances() {
    let p = paper();
    let reference = HandVehicle7::new(p);
    let report = audit(
        &p,
        |q| HandVehicle7::new(*q).with_mistake(Mistake::DropGyroscopicPair),
        &reference,
        false,
        &settings(),
    );
    assert!(!report.passed);
    let bad = failing_entries(&report);
    assert!(
        bad.contains(&"Cp[v_x]".to_string()) && bad.contains(&"Cp[w_z]".to_string()),
        "{bad:?}"
    );
    assert!(
        !bad.contains(&"Cp[w_y]".to_string()),
        "the pitch equation is untouched: {bad:?}"
    );
    assert!(report
        .failures
        .iter()
        .any(|f| f.starts_with("Cp:") && f.contains("at x = [")));
    let balance = report
        .physics
        .iter()
        .find(|c| c.name == "dE/dt = Qᵀp")
        .unwrap();
    assert!(
        balance.passed,
        "the dropped pair does no work: energy cannot see it"
    );
}

#[test]
fn flipped_gravity_sign_fails_naming_the_pitch_equation() {
    let p = paper();
    for (name, report) in [
        (
            "vehicle8",
            audit(
                &p,
                |q| HandVehicle8::new(*q).with_mistake(Mistake::FlipGravitySign),
                &HandVehicle8::new(p),
                false,
                &settings(),
            ),
        ),
        (
            "segway7",
            audit(
                &p,
                |q| HandSegway7::new(*q).with_mistake(Mistake::FlipGravitySign),
                &HandSegway7::new(p),
                true,
                &settings(),
            ),
        ),
    ] {
        assert!(!report.passed, "{name}");
        let bad = failing_entries(&report);
        assert!(bad.contains(&"F[w_y]".to_string()), "{name}: {bad:?}");
        let upright = report
            .physics
            .iter()
            .find(|c| c.name == "upright eigenvalues ±√λ²")
            .unwrap();
        assert!(
            !upright.passed,
            "{name}: a flipped gravity makes the upright a centre"
        );
    }
}

#[test]
fn audit_output_is_deterministic_for_a_seed() {
    let s = settings();
    let segway = ModelSpec::shipped("segway7").resolve().unwrap();
    let a = audit_model(&segway, &s).unwrap();
    let b = audit_model(&segway, &s).unwrap();
    assert_eq!(
        serde_json::to_string(&a).unwrap(),
        serde_json::to_string(&b).unwrap()
    );
    let other = audit_model(&segway, &AuditSettings { seed: 7, ..s }).unwrap();
    assert_ne!(
        serde_json::to_string(&a).unwrap(),
        serde_json::to_string(&other).unwrap()
    );
}
