//! The report is a composition of library results: its numbers are exactly what the typed API
//! gives for the same settings (no second code path), and its findings flip with the data.

use twv_analysis::api::{
    analyse, simulate, spectrum, tune_model, LinearSettings, Silent, SimSettings, SpectrumSettings,
    TuneSettings,
};
use twv_analysis::control::ControllerSettings;
use twv_analysis::lyapunov::LyapunovSettings;
use twv_analysis::model::{ModelSpec, ParamSource};
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

/// The smallest text of every figure on the report's page, in CSS pixels where the page shows
/// it: the SVG's smallest font size, divided by its supersampling (viewBox width over declared
/// width), times the figure's scale (its declared width, shrunk to a `column` px wide page).
fn smallest_text_px(html: &str, column: f64) -> Vec<(String, f64)> {
    let attr = |tag: &str, name: &str| -> Option<String> {
        let start = tag.find(&format!("{name}=\""))? + name.len() + 2;
        Some(tag[start..].split('"').next()?.to_string())
    };
    html.split("<figure ")
        .skip(1)
        .map(|figure| {
            let open = &figure[..figure.find('>').unwrap()];
            let file = attr(open, "data-file").unwrap();
            let declared: f64 = attr(open, "data-width").unwrap().parse().unwrap();
            let svg = &figure[figure.find("<svg").unwrap()..figure.find("</svg>").unwrap()];
            let svg_open = &svg[..svg.find('>').unwrap()];
            let view_width: f64 = attr(svg_open, "viewBox")
                .unwrap()
                .split_whitespace()
                .nth(2)
                .unwrap()
                .parse()
                .unwrap();
            let smallest = svg
                .split("font-size=\"")
                .skip(1)
                .map(|s| s.split('"').next().unwrap().parse::<f64>().unwrap())
                .fold(f64::INFINITY, f64::min);
            let scale = (column / declared).min(1.0);
            (file, smallest * declared / view_width * scale)
        })
        .collect()
}

#[test]
fn every_figure_text_is_at_least_10_px_where_the_report_shows_it() {
    let report = build(
        &ReportSettings {
            quick: true,
            ..ReportSettings::default()
        },
        &Silent,
    )
    .unwrap();
    let column = f64::from(twv_analysis::report::PAGE_WIDTH);
    assert!(report.html.contains(&format!("max-width:{column}px")));
    let sizes = smallest_text_px(&report.html, column);
    assert!(sizes.len() >= 10, "{sizes:?}");
    for (file, px) in &sizes {
        assert!(
            *px >= 10.0,
            "{file}: its smallest text is {px:.1} px on the page"
        );
    }
    // The measure flips where it should: the widest figure in a column of 600 px reads small.
    assert!(smallest_text_px(&report.html, 600.0)
        .iter()
        .any(|(_, px)| *px < 10.0));
}

/// The bicycle section: the schedule balances the benchmark bicycle at every speed of the quick
/// report, the push below the weave speed fells it unsteered and dies out steered; the finding
/// says so, and says otherwise when the steered run is replaced by one that falls.
#[test]
fn the_bicycle_finding_follows_its_runs() {
    use twv_analysis::api::RideVerdict;
    use twv_analysis::report::bicycle_finding;
    let report = build(
        &ReportSettings {
            quick: true,
            measured_bicycle: Some(ParamSource::File(super::common::repo(
                "vehicles/bicycles/browser.toml",
            ))),
            ..ReportSettings::default()
        },
        &Silent,
    )
    .unwrap();
    let b = &report.results.bicycle;
    // The Monte Carlo part: Browser's draws, their counts consistent, the text from them.
    let u = b
        .uncertainty
        .as_ref()
        .expect("a measured bicycle was given");
    assert_eq!(u.samples.len(), 40);
    assert!(report.html.contains(&format!(
        "the closed loop is stable in {} of {} draws",
        u.stable, u.physical
    )));
    assert!(report.html.contains("bicycle_uncertainty_speeds.svg"));
    assert_eq!(b.unsteered.verdict, RideVerdict::Fell);
    assert_eq!(b.steered.verdict, RideVerdict::Recovered);
    assert!(b.steer.points.iter().all(|p| p.met));
    let finding = bicycle_finding(b);
    assert_eq!(finding.verdict, "balanced by steering at every speed");
    assert!(
        finding.text.contains("4.29 to 6.02 m/s"),
        "{}",
        finding.text
    );
    // The page escapes the spec's `>=`.
    let escaped = finding.text.replace('&', "&amp;").replace('>', "&gt;");
    assert!(report.html.contains(&escaped), "{escaped}");
    let mut worse = b.clone();
    worse.steered = worse.unsteered.clone();
    let flipped = bicycle_finding(&worse);
    assert_eq!(flipped.verdict, "not balanced at every speed");
    assert!(
        flipped.text.contains("does not die out"),
        "{}",
        flipped.text
    );
}
