//! The library's JSON entry point: settings round-trip, bad settings name the field.

use twv_analysis::api::json::*;
use twv_analysis::api::{LinearSettings, Silent, SimSettings, SpectrumSettings, TuneSettings};
use twv_analysis::audit::AuditSettings;
use twv_analysis::model::ModelSpec;

#[test]
fn default_settings_read_back_as_themselves() {
    for job in ["spectrum", "simulate", "linear", "tune", "audit"] {
        let text = default_settings(job).unwrap();
        let again = match job {
            "spectrum" => to_text(&settings::<SpectrumSettings>(job, &text).unwrap()),
            "simulate" => to_text(&settings::<SimSettings>(job, &text).unwrap()),
            "linear" => to_text(&settings::<LinearSettings>(job, &text).unwrap()),
            "tune" => to_text(&settings::<TuneSettings>(job, &text).unwrap()),
            _ => to_text(&settings::<AuditSettings>(job, &text).unwrap()),
        }
        .unwrap();
        assert_eq!(text, again, "{job}");
    }
    assert_eq!(
        settings::<SimSettings>("simulate", "{}").unwrap(),
        SimSettings::default()
    );
}

#[test]
fn bad_settings_name_the_field() {
    let model = ModelSpec::shipped("vehicle8").resolve().unwrap();
    let e = run("linear", &model, r#"{"lqr_qq": 1}"#, &Silent).unwrap_err();
    assert!(e.to_string().contains("unknown field `lqr_qq`"), "{e}");
    let e = run("tune", &model, r#"{"spec": "dpm>=95"}"#, &Silent).unwrap_err();
    assert!(e.to_string().contains("dpm"), "{e}");
    let e = run("simulate", &model, r#"{"phi0": "a"}"#, &Silent).unwrap_err();
    assert!(e.to_string().starts_with("settings: simulate:"), "{e}");
    let e = run("fly", &model, "{}", &Silent).unwrap_err();
    assert!(e.to_string().contains("known: spectrum"), "{e}");
    let grid = r#"{"grid": {"kp": {"lo": 0, "hi": 8000, "n": 4}, "kd": {"lo": 0, "hi": 4000, "n": 4}, "ki": null}, "metric": "spectral-abscissa"}"#;
    assert_eq!(sweep_len(&model, grid).unwrap(), 16);
    let e = sweep_range(&model, grid, 10..17, &Silent).unwrap_err();
    assert!(e.to_string().contains("10..17"), "{e}");
}

#[test]
fn a_spec_reads_as_text_or_as_written() {
    let text: TuneSettings = settings("tune", r#"{"spec": "dpm>=60,dgm>=6dB"}"#).unwrap();
    let written = to_text(&text).unwrap();
    let again: TuneSettings = settings("tune", &written).unwrap();
    assert_eq!(text, again);
}
