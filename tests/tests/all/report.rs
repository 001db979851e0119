//! The report is a composition of library results: its numbers are exactly what the typed API
//! gives for the same settings (no second code path), and its findings flip with the data.

use twv_analysis::api::{
    analyse, simulate, spectrum, tune_model, LinearSettings, Silent, SimSettings, SpectrumSettings,
    TuneSettings,
};
use twv_analysis::control::ControllerSettings;
use twv_analysis::lyapunov::LyapunovSettings;
use twv_analysis::model::ModelSpec;
use twv_analysis::report::{build, recovery_finding, trace_check, ReportSettings};

#[test]
fn report_numbers_are_the_library_results() {
    let settings = ReportSettings {
        quick: true,
        ..ReportSettings::default()
    };
    let report = build(&settings, &Silent).unwrap();
    let r = &report.results;
    let model = ModelSpec::shipped("vehicle8").resolve().unwrap();
    let tilt = model.rest_with("phi", 0.1).unwrap();

    let preset = spectrum(
        &model,
        &SpectrumSettings {
            x0: tilt.clone(),
            lyapunov: LyapunovSettings::preset_paper(),
            ..SpectrumSettings::default()
        },
        &Silent,
    )
    .unwrap();
    let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    assert_eq!(
        bits(&r.lyapunov_preset.result.exponents),
        bits(&preset.result.exponents)
    );
    assert_eq!(
        r.lyapunov_preset.result.sum.to_bits(),
        preset.result.sum.to_bits()
    );

    let forward = simulate(
        &model,
        &SimSettings {
            controller: ControllerSettings::default(),
            phi0: 0.1,
            ..SimSettings::default()
        },
        &Silent,
    )
    .unwrap();
    assert_eq!(r.recovery[0].metrics, forward.metrics);
    assert_eq!(r.recovery[0].rows, forward.rows);
    // The page's sentence is the finding computed from that very result.
    assert_eq!(r.findings[1].text, recovery_finding(&r.recovery[0]).text);

    let linear = analyse(&model, &LinearSettings::default()).unwrap();
    assert_eq!(r.linear.pitch, linear.pitch);
    let tuned = tune_model(&model, &TuneSettings::default()).unwrap();
    assert_eq!(
        r.tune.result.certificate.as_ref().map(|c| c.gains),
        tuned.result.certificate.as_ref().map(|c| c.gains)
    );
    assert_eq!(r.tune.verdict, tuned.verdict);
    assert_eq!(r.checks[1], trace_check(&preset));
    // Its wall time names the machine and the kernels' build it was measured on.
    assert_eq!(r.machine, twv_analysis::machine::describe());
    assert!(report.html.contains(&format!("s on {}.", r.machine)));
}

/// The recovery finding flips with the run: the same code called on a run that falls (the
/// study's PD with Kp below M_x g) says so.
#[test]
fn the_recovery_finding_follows_the_run() {
    let model = ModelSpec::shipped("vehicle8").resolve().unwrap();
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
    assert_eq!(recovery_finding(&run(3860.0)).verdict, "recovers");
    assert_eq!(recovery_finding(&run(800.0)).verdict, "falls");
}
