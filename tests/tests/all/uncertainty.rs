//! `twv uncertainty`: the draws have the stated means and spreads and are independent; the
//! weave speed's spread over the draws is the first-order propagation of the parameters'
//! (a second path, finite differences of the band search); the nominal bicycle is `steady`'s;
//! shards merge to the bytes of one run; the verdict flips with the design; bad input.

use twv_analysis::api::{
    draw, merge_uncertainty, merge_uncertainty_dir, steady_motion, uncertainty,
    uncertainty_shard_files, Silent, SteadySettings, UncertaintyResult, UncertaintySettings,
    UncertaintyVerdict,
};
use twv_analysis::jobs::{JobOutput, Verdict};
use twv_analysis::linear::SteerGains;
use twv_analysis::model::{ModelSpec, ParamSource, ResolvedModel};
use twv_analysis::sweep::Shard;

use super::common::repo;

/// The measured bicycle `name` of vehicles/bicycles/, with its `[uncertainty]`.
fn measured(name: &str) -> ResolvedModel {
    ModelSpec::shipped("whipple")
        .with_params(ParamSource::File(repo(&format!(
            "vehicles/bicycles/{name}.toml"
        ))))
        .resolve()
        .unwrap()
}

/// Lean and lean-rate feedback that balance Pista, Fisher and Yellow at 3 m/s with room to
/// spare (max Re λ ≈ −2 1/s; not Browser, +0.09 1/s).
fn design() -> SteerGains {
    SteerGains {
        k_phi: 20.0,
        k_phi_dot: 10.0,
        ..SteerGains::default()
    }
}

fn settings(samples: usize) -> UncertaintySettings {
    UncertaintySettings {
        samples,
        lo: 2.0,
        hi: 8.0,
        gains: Some(design()),
        ..UncertaintySettings::default()
    }
}

#[test]
fn the_draws_have_the_stated_means_and_spreads_and_are_independent() {
    let m = measured("browser");
    let n = 4000;
    let draws: Vec<Vec<f64>> = (0..n)
        .map(|k| draw(&m.params, &m.uncertainty, 7, k))
        .collect();
    assert_eq!(
        draw(&m.params, &m.uncertainty, 7, 11),
        draws[11],
        "draw k depends on k only"
    );
    assert_ne!(draws[0], draws[1]);
    let varied: Vec<usize> = (0..m.params.len())
        .filter(|&i| m.uncertainty[i] > 0.0)
        .collect();
    assert!(
        varied.len() >= 20,
        "Browser states most of its values' uncertainty"
    );
    let column = |i: usize| draws.iter().map(|d| d[i]).collect::<Vec<f64>>();
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    for i in 0..m.params.len() {
        let v = column(i);
        let (mu, sd) = (m.params[i], m.uncertainty[i]);
        if sd == 0.0 {
            assert!(v.iter().all(|x| *x == mu), "an exact value is never varied");
            continue;
        }
        let got_mean = mean(&v);
        let got_sd =
            (v.iter().map(|x| (x - got_mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt();
        // 4.5 standard errors: the mean's is sd/√n, the standard deviation's about sd/√(2n).
        assert!(
            (got_mean - mu).abs() < 4.5 * sd / (n as f64).sqrt(),
            "mean of {i}: {got_mean} against {mu}"
        );
        assert!(
            (got_sd / sd - 1.0).abs() < 4.5 / (2.0 * n as f64).sqrt(),
            "sd of {i}: {got_sd} against {sd}"
        );
    }
    // Independent: the correlation of neighbouring varied values is within 4.5/√n of 0.
    for w in varied.windows(2) {
        let (a, b) = (column(w[0]), column(w[1]));
        let (ma, mb) = (mean(&a), mean(&b));
        let cov = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - ma) * (y - mb))
            .sum::<f64>();
        let r = cov
            / (a.iter().map(|x| (x - ma).powi(2)).sum::<f64>()
                * b.iter().map(|y| (y - mb).powi(2)).sum::<f64>())
            .sqrt();
        assert!(
            r.abs() < 4.5 / (n as f64).sqrt(),
            "correlation {r} of {w:?}"
        );
    }
}

/// The weave speed of `m` with `values` for its parameters.
fn weave_speed(m: &ResolvedModel, values: &[f64]) -> f64 {
    let named: Vec<(String, f64)> =
        m.ir.params()
            .iter()
            .map(|p| p.name.clone())
            .zip(values.iter().copied())
            .collect();
    let at = m.with_param_values(&named, "test").unwrap();
    let s = SteadySettings {
        lo: 2.0,
        hi: 8.0,
        step: 0.05,
        bound_tolerance: 1e-11,
    };
    steady_motion(&at, &s, &Silent)
        .unwrap()
        .weave_speed
        .unwrap()
}

#[test]
fn the_weave_speeds_spread_is_the_first_order_propagation_of_the_parameters() {
    // Pista: a wide self-stable band (3.67-5.51 m/s), so a draw's weave speed is a smooth
    // function of its values.
    let m = measured("pista");
    let r = uncertainty(&m, &settings(400), &Silent).unwrap();
    assert_eq!(r.physical, 400);
    let spread = r.weave_speed.unwrap();
    assert_eq!(spread.count, 400, "every draw of Pista has a band");
    // The second path: σ_w² = Σ (∂w/∂p_i σ_i)², each derivative a central difference of the
    // band search at ±σ_i.
    let mut variance = 0.0;
    for i in 0..m.params.len() {
        let sd = m.uncertainty[i];
        if sd == 0.0 {
            continue;
        }
        let (mut up, mut down) = (m.params.clone(), m.params.clone());
        up[i] += sd;
        down[i] -= sd;
        let dw = (weave_speed(&m, &up) - weave_speed(&m, &down)) / 2.0;
        variance += dw * dw;
    }
    let linear = variance.sqrt();
    // 400 draws estimate σ to about 1/√800 = 3.5 % (1σ); 15 % is four of those, and covers
    // the propagation's neglected second-order terms (σ is ~1 % of each value).
    assert!(
        (spread.sd / linear - 1.0).abs() < 0.15,
        "Monte Carlo σ {} m/s against first-order {linear} m/s",
        spread.sd
    );
    // And the draws' mean weave speed is the nominal one within a few standard errors.
    let nominal = r.nominal.weave_speed.unwrap();
    assert!(
        (spread.mean - nominal).abs() < 4.0 * linear / 20.0 + 1e-3,
        "mean {} against nominal {nominal}",
        spread.mean
    );
}

#[test]
fn the_nominal_bicycle_is_steadys_and_the_quantiles_are_ordered() {
    let m = measured("browser");
    let r = uncertainty(&m, &settings(24), &Silent).unwrap();
    let band = steady_motion(
        &m,
        &SteadySettings {
            lo: 2.0,
            hi: 8.0,
            step: 0.05,
            ..SteadySettings::default()
        },
        &Silent,
    )
    .unwrap();
    let (w, c) = (
        r.nominal.weave_speed.unwrap(),
        r.nominal.capsize_speed.unwrap(),
    );
    assert!((w - band.weave_speed.unwrap()).abs() < 1e-8, "{w}");
    assert!((c - band.capsize_speed.unwrap()).abs() < 1e-8, "{c}");
    assert_eq!(r.samples.len(), 24);
    assert!(r.samples.iter().enumerate().all(|(i, s)| s.index == i));
    for s in [r.weave_speed, r.capsize_speed, r.disk_phase_margin_deg]
        .into_iter()
        .flatten()
    {
        assert!(
            s.min <= s.p05 && s.p05 <= s.p50 && s.p50 <= s.p95 && s.p95 <= s.max,
            "{s:?}"
        );
        assert!(s.min <= s.mean && s.mean <= s.max && s.sd >= 0.0);
    }
    // Browser's band is 0.12 m/s wide: its uncertainty removes it in some draws, and the
    // counts say so rather than hide it.
    assert!(r.self_stable <= r.physical);
    assert_eq!(r.weave_speed.map_or(0, |s| s.count), r.self_stable);
    let text = r.summary();
    assert!(text.contains("weave speed: nominal 4.2147"), "{text}");
}

#[test]
fn shards_merge_to_the_bytes_of_one_run() {
    let m = measured("yellow");
    let whole = uncertainty(&m, &settings(10), &Silent).unwrap();
    let shards: Vec<UncertaintyResult> = [2, 0, 1]
        .into_iter()
        .map(|i| {
            let s = UncertaintySettings {
                shard: Shard::new(i, 3).unwrap(),
                ..settings(10)
            };
            uncertainty(&m, &s, &Silent).unwrap()
        })
        .collect();
    assert_eq!(shards.iter().map(|s| s.samples.len()).sum::<usize>(), 10);
    let merged = merge_uncertainty(shards.clone()).unwrap();
    assert_eq!(
        serde_json::to_string(&merged).unwrap(),
        serde_json::to_string(&whole).unwrap()
    );
    assert_eq!(merged.csv(), whole.csv());
    // Through files, as the tasks of an array write them into one folder: each shard's files
    // beside the others', `twv merge`'s step joins them into the whole run's files.
    let dir = std::env::temp_dir().join(format!("twv-uncertainty-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    for s in &shards {
        s.files().unwrap().write(&dir).unwrap();
    }
    assert_eq!(uncertainty_shard_files(&dir).unwrap().len(), 3);
    let (joined, written) = merge_uncertainty_dir(&dir).unwrap();
    assert_eq!(joined, whole);
    assert!(written.iter().any(|p| p.ends_with("speeds.svg")));
    assert_eq!(
        std::fs::read(dir.join("uncertainty.json")).unwrap(),
        whole.files().unwrap().entries[1].1
    );
    std::fs::remove_dir_all(&dir).unwrap();
    // A shard missing, or one of another run, is refused by name.
    let err = merge_uncertainty(shards[..2].to_vec())
        .unwrap_err()
        .to_string();
    assert!(err.contains("each of the 3 shards once"), "{err}");
    let mut other = shards.clone();
    other[0] = uncertainty(
        &m,
        &UncertaintySettings {
            seed: 2,
            shard: Shard::new(2, 3).unwrap(),
            ..settings(10)
        },
        &Silent,
    )
    .unwrap();
    let err = merge_uncertainty(other).unwrap_err().to_string();
    assert!(err.contains("of another run"), "{err}");
}

#[test]
fn the_verdict_follows_the_design() {
    let m = measured("fisher");
    let steered = uncertainty(&m, &settings(8), &Silent).unwrap();
    assert_eq!(steered.verdict, UncertaintyVerdict::AllStable);
    assert_eq!(steered.stable, 8);
    assert_eq!(steered.verdict(), Verdict::Done);
    // Nobody steering at 3 m/s, below every draw's weave speed: the same draws, all fallen.
    let unsteered = uncertainty(
        &m,
        &UncertaintySettings {
            gains: Some(SteerGains::default()),
            ..settings(8)
        },
        &Silent,
    )
    .unwrap();
    assert_eq!(unsteered.verdict, UncertaintyVerdict::NotAllStable);
    assert_eq!(unsteered.stable, 0);
    let Verdict::Negative(why) = unsteered.verdict() else {
        panic!("nobody steering at 3 m/s is not balanced")
    };
    assert!(why.contains("stable in 0 of 8"), "{why}");
    // The draws are the same whatever the design.
    assert_eq!(
        steered
            .samples
            .iter()
            .map(|s| &s.params)
            .collect::<Vec<_>>(),
        unsteered
            .samples
            .iter()
            .map(|s| &s.params)
            .collect::<Vec<_>>()
    );
}

#[test]
fn a_design_tuned_on_the_nominal_bicycle_meets_its_spec_there() {
    let m = measured("crescendo");
    let r = uncertainty(
        &m,
        &UncertaintySettings {
            gains: None,
            ..settings(6)
        },
        &Silent,
    )
    .unwrap();
    assert!(r.design.is_some());
    assert!(r.nominal.meets_spec && r.nominal.stable, "{:?}", r.nominal);
    assert!(r.nominal.disk_phase_margin_deg.unwrap() >= 45.0 - 1e-6);
}

#[test]
fn bad_input_is_named() {
    let m = measured("browser");
    let cases: Vec<(UncertaintySettings, &str)> = vec![
        (settings(0), "samples"),
        (settings(1_000_000), "samples"),
        (
            UncertaintySettings {
                lo: -1.0,
                ..settings(4)
            },
            "speeds",
        ),
        (
            UncertaintySettings {
                hi: f64::NAN,
                ..settings(4)
            },
            "speeds",
        ),
        (
            UncertaintySettings {
                speed: 0.0,
                ..settings(4)
            },
            "speed",
        ),
        (
            UncertaintySettings {
                gains: Some(SteerGains {
                    k_phi: f64::NAN,
                    ..SteerGains::default()
                }),
                ..settings(4)
            },
            "gains",
        ),
        (
            UncertaintySettings {
                shard: Shard { index: 3, count: 2 },
                ..settings(4)
            },
            "shard",
        ),
        (
            UncertaintySettings {
                shard: Shard::new(0, 5).unwrap(),
                ..settings(4)
            },
            "shard",
        ),
    ];
    for (s, field) in cases {
        let err = uncertainty(&m, &s, &Silent).unwrap_err().to_string();
        assert!(err.contains(field), "{s:?}: {err}");
    }
    // The shipped bicycle's defaults state no uncertainty: nothing to draw.
    let plain = ModelSpec::shipped("whipple").resolve().unwrap();
    let err = uncertainty(&plain, &settings(4), &Silent)
        .unwrap_err()
        .to_string();
    assert!(err.contains("no uncertainty"), "{err}");
}
