//! The job registry: one name per job, every default from the settings type's `Default`, every
//! option's default read back as itself, settings that round-trip through JSON, and bad input
//! named by field, whichever way it arrives (JSON settings or flat options).

use serde_json::{json, Value};
use twv_analysis::api::json::*;
use twv_analysis::api::Silent;
use twv_analysis::jobs::{self, registry};
use twv_analysis::model::ModelSpec;

#[test]
fn every_job_has_one_name_and_its_aliases_are_its_own() {
    let mut seen = std::collections::BTreeSet::new();
    for job in registry() {
        for name in std::iter::once(job.name()).chain(job.aliases().iter().copied()) {
            assert!(seen.insert(name), "{name} names two jobs");
            assert_eq!(jobs::find(name).unwrap().name(), job.name(), "{name}");
        }
    }
    let e = jobs::find("fly").err().unwrap().to_string();
    assert!(
        e.contains("unknown job `fly`") && e.contains("lyapunov"),
        "{e}"
    );
}

/// A value for each option a job cannot run without (a state), so that its other options can
/// be tried.
fn required(job: &dyn jobs::AnyJob) -> Vec<(String, Value)> {
    job.options()
        .iter()
        .filter(|o| o.required)
        .map(|o| (o.name.to_string(), json!([0.1, 0.0, 0.0])))
        .collect()
}

#[test]
fn default_settings_read_back_as_themselves() {
    for job in registry() {
        let defaults = job.default_settings();
        let prepared = job.prepare_json(&defaults).unwrap();
        assert_eq!(prepared.settings(), defaults, "{}", job.name());
        // An empty object is the defaults too, and so are no options (but the required ones).
        assert_eq!(job.prepare_json(&json!({})).unwrap().settings(), defaults);
        if required(*job).is_empty() {
            assert_eq!(job.prepare_options(None, &[]).unwrap().settings(), defaults);
        } else {
            let e = job.prepare_options(None, &[]).err().unwrap().to_string();
            assert!(e.contains("needs it"), "{e}");
        }
    }
}

/// The defaults front ends show (`--help`, Python signatures) are the settings type's own: each
/// option's default, set as if a user had typed it, leaves the default settings unchanged.
#[test]
fn every_option_default_is_the_settings_default() {
    for job in registry() {
        let base = required(*job);
        let defaults = job.prepare_options(None, &base).unwrap().settings();
        for o in job.options() {
            if o.default.is_null() || o.required {
                continue;
            }
            if o.kind == jobs::Kind::Flag && o.default == Value::Bool(false) {
                continue; // giving a flag turns it on
            }
            let mut given = base.clone();
            given.push((o.name.to_string(), o.default.clone()));
            let mut expected = defaults.clone();
            // DOPRI's options show the default that choosing DOPRI gives: try them there.
            if o.help.contains("DOPRI") && o.name != "h" {
                let dopri = ("integrator".to_string(), json!("dopri"));
                given.push(dopri.clone());
                let mut chosen = base.clone();
                chosen.push(dopri);
                expected = job.prepare_options(None, &chosen).unwrap().settings();
            }
            let again = match job.prepare_options(None, &given) {
                Ok(p) => p.settings(),
                // An option of a choice not taken (tracking_time without back-calculation,
                // v_ref without the velocity loop) shows the default that choice gives; it
                // cannot be set alone.
                Err(e)
                    if [": needs ", "belongs to"]
                        .iter()
                        .any(|m| e.to_string().contains(m)) =>
                {
                    continue
                }
                Err(e) => panic!("{} --{}: {e}", job.name(), o.name),
            };
            assert_eq!(again, expected, "{} {} = {}", job.name(), o.name, o.default);
        }
    }
}

#[test]
fn options_change_the_settings_they_name_and_nothing_else() {
    let sim = jobs::find("simulate").unwrap();
    let s = sim
        .prepare_options(
            None,
            &[("kd".into(), "900".into()), ("t_end".into(), json!(5.0))],
        )
        .unwrap()
        .settings();
    let mut expected = sim.default_settings();
    expected["controller"]["pitch"]["gains"]["kd"] = json!(900.0);
    expected["run"]["t_end"] = json!(5.0);
    assert_eq!(s, expected);
    // The order options are given in does not matter: they apply in the table's order.
    let a = [
        ("tracking_time".into(), json!(0.5)),
        ("anti_windup".into(), json!("back_calc")),
    ];
    let b = [a[1].clone(), a[0].clone()];
    assert_eq!(
        sim.prepare_options(None, &a).unwrap().settings(),
        sim.prepare_options(None, &b).unwrap().settings()
    );
    // The maneuver's length follows its options unless t_end is given.
    let m = sim
        .prepare_options(
            None,
            &[
                ("scenario".into(), json!("maneuver")),
                ("cruise".into(), json!(1.0)),
            ],
        )
        .unwrap()
        .settings();
    assert_eq!(m["run"]["t_end"], json!(18.0)); // 1 s rest, 3 + 1 + 3 s, then 10 s
}

#[test]
fn bad_options_are_refused_naming_them() {
    let sim = jobs::find("simulate").unwrap();
    let refused = |given: &[(&str, Value)]| {
        let given: Vec<(String, Value)> = given
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect();
        sim.prepare_options(None, &given).err().unwrap().to_string()
    };
    assert!(refused(&[("kpp", json!(1))]).starts_with("kpp: simulate has no such option"));
    assert!(refused(&[("tracking_time", json!(1))]).contains("back_calc"));
    assert!(refused(&[("v_ref", json!(1))]).contains("velocity loop"));
    assert!(refused(&[("rtol", json!(1e-6))]).starts_with("rtol: applies to the adaptive"));
    assert!(refused(&[("gains", json!([3000, 900, 0]))]).contains("not a list"));
    assert!(
        refused(&[("x0", json!("0.1,0,0")), ("tilt", json!(0.1))]).contains("cannot be given with")
    );
    assert!(refused(&[("v_cruise", json!(1))]).contains("maneuver"));
    assert!(refused(&[("t_end", json!("-1"))]).contains("t_end"));
    assert!(refused(&[("kd", json!("nan"))]).contains("Kd"));
    // An axis named by its flag, dashes and all.
    let map = jobs::find("steer_map").unwrap();
    let given = [("against_values".to_string(), json!("1:0:5"))];
    let e = map.prepare_options(None, &given).err().unwrap().to_string();
    assert!(e.starts_with("--against-values `1:0:5`: need A < B"), "{e}");
}

#[test]
fn bad_settings_name_the_field() {
    let model = ModelSpec::shipped("vehicle8").resolve().unwrap();
    let e = run("linear", &model, r#"{"lqr_qq": 1}"#, &Silent).unwrap_err();
    assert!(e.to_string().contains("unknown field `lqr_qq`"), "{e}");
    let e = run("tune", &model, r#"{"spec": "dpm>=95"}"#, &Silent).unwrap_err();
    assert!(e.to_string().contains("dpm"), "{e}");
    let e = run("simulate", &model, r#"{"phi0": "a"}"#, &Silent).unwrap_err();
    assert!(e.to_string().starts_with("phi0: simulate:"), "{e}");
    let e = run("simulate", &model, r#"{"run": {"t_end": "a"}}"#, &Silent).unwrap_err();
    assert!(e.to_string().starts_with("run.t_end: simulate:"), "{e}");
    let e = run("fly", &model, "{}", &Silent).unwrap_err();
    assert!(e.to_string().contains("the jobs: evaluate"), "{e}");
    // The map's numerical settings are checked before any point runs (not `blew_up` points).
    for (field, bad) in [
        ("h", json!(0.0)),
        ("t_sample", json!(-0.1)),
        ("iterations", json!(0)),
    ] {
        let text = json!({"metric_settings": {field: bad}}).to_string();
        let e = run("sweep", &model, &text, &Silent)
            .unwrap_err()
            .to_string();
        assert!(e.contains(field), "{field}: {e}");
        let e = run("exponent", &model, &text, &Silent)
            .unwrap_err()
            .to_string();
        assert!(e.contains(field), "{field}: {e}");
    }
    let grid = r#"{"grid": {"kp": {"lo": 0, "hi": 8000, "n": 4}, "kd": {"lo": 0, "hi": 4000, "n": 4}, "ki": null}, "metric": "spectral-abscissa"}"#;
    assert_eq!(sweep_len(&model, grid).unwrap(), 16);
    let e = sweep_range(&model, grid, 10..17, &Silent).unwrap_err();
    assert!(e.to_string().contains("10..17"), "{e}");
}

#[test]
fn a_spec_reads_as_text_or_as_written() {
    let tune = jobs::find("tune").unwrap();
    let text = tune
        .prepare_json(&json!({"spec": "dpm>=60,dgm>=6dB"}))
        .unwrap()
        .settings();
    let again = tune.prepare_json(&text).unwrap().settings();
    assert_eq!(text, again);
}

/// The JSON runner and the typed call give the same bytes.
#[test]
fn the_json_runner_is_the_typed_job() {
    use twv_analysis::jobs::{Job, Linearize};
    let model = ModelSpec::shipped("vehicle8").resolve().unwrap();
    let typed = Linearize::run(&model, &Linearize::defaults(), &Silent).unwrap();
    let by_name = run("linearize", &model, "{}", &Silent).unwrap();
    assert_eq!(by_name.result, to_text(&typed).unwrap());
    let by_options = run_options("linear", &model, None, r#"{"kd": 1980}"#, &Silent).unwrap();
    assert_eq!(by_options.result, by_name.result);
    assert!(by_name.negative.is_none());
    // A loop that cannot stabilise: the verdict is negative, computed from the poles.
    let bad = run_options("linearize", &model, None, r#"{"kp": 100}"#, &Silent).unwrap();
    assert_eq!(bad.negative.as_deref(), Some("the pitch loop is unstable"));
}

/// `phi_dot0`: a push on the pitch rate from the upright is the same run as the whole initial
/// state written out, bit for bit, and the study's PD recovers from it.
#[test]
fn a_push_on_the_pitch_rate_is_the_initial_state_it_names() {
    let model = ModelSpec::shipped("vehicle8").resolve().unwrap();
    let push = run_options(
        "simulate",
        &model,
        None,
        r#"{"tilt": 0, "phi_dot0": 0.3}"#,
        &Silent,
    );
    let written = run_options(
        "simulate",
        &model,
        None,
        r#"{"x0": [0, 0, 0, 0, 0.3, 0, 0, 0]}"#,
        &Silent,
    );
    let (push, written) = (push.unwrap(), written.unwrap());
    assert_eq!(push.csv, written.csv);
    let result: Value = serde_json::from_str(&push.result).unwrap();
    assert_eq!(result["x0"][4], json!(0.3));
    assert_eq!(result["recovery"], json!("recovered"));
    let e = run_options("simulate", &model, None, r#"{"phi_dot0": "nan"}"#, &Silent);
    assert!(e.unwrap_err().to_string().contains("phi_dot0"));
}
