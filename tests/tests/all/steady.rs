//! The Whipple bicycle, shipped as its derived IR and run on the interpreter, linearised about
//! straight running against speed: the eigenvalues of Meijaard et al. (2007)'s Table 2 and their
//! weave and capsize speeds (`tests/data/meijaard2007.json`), and the verdict flipping with the
//! grid.

use std::path::PathBuf;

use serde_json::Value;
use twv_analysis::api::{steady_motion, Silent, SteadySettings, SteadyVerdict};
use twv_analysis::model::{Engine, ModelSpec};
use twv_analysis::Error;

fn reference() -> Value {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("data/meijaard2007.json");
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Table 2's row at one speed as the full list of eigenvalues, sorted as the library sorts.
fn table_row(row: &Value) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for e in row.as_array().unwrap() {
        let (re, im) = (e[0].as_f64().unwrap(), e[1].as_f64().unwrap());
        out.push((re, im));
        if im != 0.0 {
            out.push((re, -im));
        }
    }
    out.sort_by(|p, q| p.0.total_cmp(&q.0).then(p.1.total_cmp(&q.1)));
    out
}

#[test]
fn the_bicycle_is_a_shipped_interpreted_model() {
    let model = ModelSpec::shipped("whipple").resolve().unwrap();
    assert_eq!(model.engine, Engine::Interpreted);
    assert_eq!(model.states().len(), 9);
    assert!(twv_analysis::model::shipped_models().contains(&"whipple"));
}

#[test]
fn eigenvalues_equal_table_2_and_the_stable_range_the_papers() {
    let reference = reference();
    let model = ModelSpec::shipped("whipple").resolve().unwrap();
    let settings = SteadySettings {
        lo: 0.0,
        hi: 10.0,
        step: 1.0,
        ..SteadySettings::default()
    };
    let result = steady_motion(&model, &settings, &Silent).unwrap();
    assert_eq!(result.modes, ["phi", "delta", "w_phi", "w_delta"]);
    assert_eq!(result.points.len(), 11);
    let mut worst: f64 = 0.0;
    for p in &result.points {
        let want = table_row(&reference["table2"][format!("{}", p.speed as i64)]);
        for (got, want) in p.eigenvalues.iter().zip(&want) {
            worst = worst
                .max((got.0 - want.0).abs())
                .max((got.1 - want.1).abs());
        }
    }
    assert!(worst <= 1e-10, "worst Table 2 error {worst:e}");
    assert_eq!(result.verdict, SteadyVerdict::SelfStable);
    let [(weave, capsize)] = result.stable_ranges[..] else {
        panic!("one stable range: {:?}", result.stable_ranges);
    };
    let (w, c) = (
        reference["weave_speed"].as_f64().unwrap(),
        reference["capsize_speed"].as_f64().unwrap(),
    );
    assert!((weave - w).abs() <= 1e-10, "weave {weave} vs {w}");
    assert!((capsize - c).abs() <= 1e-10, "capsize {capsize} vs {c}");
}

#[test]
fn the_verdict_flips_with_the_speeds_looked_at() {
    let model = ModelSpec::shipped("whipple").resolve().unwrap();
    let slow = SteadySettings {
        lo: 0.0,
        hi: 4.0,
        step: 0.1,
        ..SteadySettings::default()
    };
    let result = steady_motion(&model, &slow, &Silent).unwrap();
    assert_eq!(result.verdict, SteadyVerdict::NowhereStable);
    assert!(result.stable_ranges.is_empty());
    // A grid inside the stable range: the whole grid is the range, bounds at its edges.
    let inside = SteadySettings {
        lo: 4.5,
        hi: 5.5,
        step: 0.5,
        ..SteadySettings::default()
    };
    let result = steady_motion(&model, &inside, &Silent).unwrap();
    assert_eq!(result.stable_ranges, vec![(4.5, 5.5)]);
}

#[test]
fn bad_grids_and_models_without_a_steady_motion_are_refused() {
    let model = ModelSpec::shipped("whipple").resolve().unwrap();
    for (lo, hi, step, field) in [
        (1.0, 0.0, 0.1, "speed"),
        (0.0, 1.0, 0.0, "speed"),
        (0.0, f64::NAN, 0.1, "speed"),
        (0.0, 1e9, 1e-6, "speed"),
    ] {
        let settings = SteadySettings {
            lo,
            hi,
            step,
            ..SteadySettings::default()
        };
        let err = steady_motion(&model, &settings, &Silent).unwrap_err();
        assert!(
            matches!(&err, Error::Input { field: f, .. } if f == field),
            "{err}"
        );
    }
    let lorenz = ModelSpec::shipped("lorenz").resolve().unwrap();
    let err = steady_motion(&lorenz, &SteadySettings::default(), &Silent).unwrap_err();
    assert!(err.to_string().contains("no steady motion"), "{err}");
}

#[test]
fn the_figure_follows_each_mode_through_the_crossings() {
    let model = ModelSpec::shipped("whipple").resolve().unwrap();
    let result = steady_motion(&model, &SteadySettings::default(), &Silent).unwrap();
    let branches = result.branches();
    assert_eq!(branches.len(), 4);
    let at = |v: f64| {
        result
            .points
            .iter()
            .position(|p| (p.speed - v).abs() < 1e-9)
            .unwrap()
    };
    let (three, ten) = (at(3.0), at(10.0));
    // The capsize mode: -2.6337 at 3 m/s (Table 2) and +0.1611 at 10 m/s, one branch, although
    // its real part crosses the weave's near 4.7 m/s (sorting by real part would switch curves).
    let capsize = branches
        .iter()
        .find(|b| (b[three].0 + 2.63366137253667).abs() < 1e-9)
        .expect("the capsize branch");
    assert!(
        (capsize[ten].0 - 0.16105338653172).abs() < 1e-9,
        "{:?}",
        capsize[ten]
    );
    assert!(capsize[ten].1 == 0.0);
}
