//! `twv steer-map`: every cell of a map against the published linear benchmark equations with
//! the feedback substituted (a second path), the zero-gain row against the open loop's
//! self-stable band, a verdict that flips when the gain's values move into the stabilising
//! range, and bad input.

use twv_analysis::api::{steer_map, Silent, SteerMapSettings, SteerMapVerdict};
use twv_analysis::jobs::{JobOutput, Verdict};
use twv_analysis::linear::modes::{eigenvalues, spectral_abscissa};
use twv_analysis::linear::SteerGains;
use twv_analysis::model::{ModelSpec, ResolvedModel};
use twv_analysis::sweep::Axis;

use super::steer::benchmark_closed_loop;

fn bicycle() -> ResolvedModel {
    ModelSpec::shipped("whipple").resolve().unwrap()
}

fn axis(lo: f64, hi: f64, n: usize) -> Axis {
    Axis { lo, hi, n }
}

#[test]
fn every_cell_is_the_benchmark_equations_closed_by_the_gains() {
    let s = SteerMapSettings {
        speed: axis(0.5, 9.0, 18),
        gain: "k_phi".into(),
        values: axis(-20.0, 80.0, 11),
        gains: SteerGains {
            k_phi_dot: 6.0,
            k_delta: -15.0,
            ..SteerGains::default()
        },
        rate_filter: None,
    };
    let r = steer_map(&bicycle(), &s, &Silent).unwrap();
    assert_eq!(r.abscissa.len(), 18 * 11);
    let n = r.speeds.len();
    for (j, &x) in r.values.iter().enumerate() {
        for (i, &v) in r.speeds.iter().enumerate() {
            let g = SteerGains {
                k_phi: x,
                ..s.gains
            };
            let theirs = spectral_abscissa(&eigenvalues(&benchmark_closed_loop(v, &g)).unwrap());
            let ours = r.abscissa[j * n + i].unwrap();
            // The published matrices carry 13-15 significant digits.
            assert!(
                (ours - theirs).abs() <= 1e-10 * theirs.abs().max(1.0),
                "at {v} m/s, k_phi = {x}: {ours} against the benchmark's {theirs}"
            );
        }
    }
    // The per-speed ranges are the stable cells of each column.
    for (i, range) in r.stabilising.iter().enumerate() {
        let stable: Vec<f64> = (0..r.values.len())
            .filter(|j| r.abscissa[j * n + i].unwrap() < 0.0)
            .map(|j| r.values[j])
            .collect();
        assert_eq!(range.count, stable.len());
        assert_eq!(range.lo, stable.first().copied());
        assert_eq!(range.hi, stable.last().copied());
    }
}

#[test]
fn the_unsteered_row_is_stable_exactly_in_the_self_stable_band() {
    let s = SteerMapSettings {
        values: axis(0.0, 10.0, 3),
        ..SteerMapSettings::default()
    };
    let r = steer_map(&bicycle(), &s, &Silent).unwrap();
    // The benchmark's weave and capsize speeds (Meijaard et al. 2007, Table 2).
    let (w, c) = (r.weave_speed.unwrap(), r.capsize_speed.unwrap());
    assert!(
        (w - 4.2924).abs() < 1e-4 && (c - 6.0243).abs() < 1e-4,
        "{w} {c}"
    );
    assert_eq!(r.self_stable, vec![(w, c)]);
    for (i, &v) in r.speeds.iter().enumerate() {
        let stable = r.abscissa[i].unwrap() < 0.0;
        assert_eq!(stable, v > w && v < c, "at {v} m/s, nobody steering");
    }
    // Lean-rate feedback balances the bicycle below the weave speed too, if strong enough: at
    // 3 m/s 10 N m s/rad does, 5 does not (the boundary is near 8).
    let below = r.stabilising.iter().find(|p| p.speed == 3.0).unwrap();
    assert_eq!((below.lo, below.count), (Some(10.0), 1), "{below:?}");
}

#[test]
fn the_verdict_follows_the_map() {
    // Steering away from a growing lean (k_phi_dot < 0) balances the bicycle at no speed below
    // its weave speed; steering into it does.
    let away = SteerMapSettings {
        speed: axis(0.5, 3.5, 7),
        values: axis(-40.0, -5.0, 8),
        ..SteerMapSettings::default()
    };
    let r = steer_map(&bicycle(), &away, &Silent).unwrap();
    assert_eq!(r.verdict, SteerMapVerdict::NowhereStable);
    assert_eq!(r.stable_cells, 0);
    assert!(matches!(r.verdict(), Verdict::Negative(m) if m.contains("k_phi_dot")));
    assert!(
        r.summary().contains("no value of k_phi_dot"),
        "{}",
        r.summary()
    );
    let into = SteerMapSettings {
        values: axis(5.0, 40.0, 8),
        ..away
    };
    let r = steer_map(&bicycle(), &into, &Silent).unwrap();
    assert_eq!(r.verdict, SteerMapVerdict::StableSomewhere);
    assert!(r.stable_cells > 0 && r.verdict() == Verdict::Done);
    // Files a person can open: the CSV has a row per cell, the figure renders.
    let files = r.files().unwrap();
    let names = files.names();
    assert!(names.contains(&"map.svg"), "{names:?}");
    assert_eq!(r.csv().lines().count(), 1 + 7 * 8);
}

#[test]
fn bad_input_gets_one_line_naming_it() {
    let model = bicycle();
    let error = |s: SteerMapSettings, m: &ResolvedModel| {
        let e = steer_map(m, &s, &Silent).unwrap_err().to_string();
        assert!(!e.contains('\n'), "{e}");
        e
    };
    let negative = error(
        SteerMapSettings {
            speed: axis(-1.0, 5.0, 10),
            ..SteerMapSettings::default()
        },
        &model,
    );
    assert!(
        negative.contains("speed") && negative.contains("≥ 0"),
        "{negative}"
    );
    let gain = error(
        SteerMapSettings {
            gain: "k_psi".into(),
            ..SteerMapSettings::default()
        },
        &model,
    );
    assert!(
        gain.contains("k_psi") && gain.contains("k_phi_dot"),
        "{gain}"
    );
    let huge = error(
        SteerMapSettings {
            values: axis(0.0, 1.0, 1_000_001),
            ..SteerMapSettings::default()
        },
        &model,
    );
    assert!(huge.contains("values") && huge.contains("1000"), "{huge}");
    let nan = error(
        SteerMapSettings {
            gains: SteerGains {
                k_delta: f64::NAN,
                ..SteerGains::default()
            },
            ..SteerMapSettings::default()
        },
        &model,
    );
    assert!(nan.contains("k_delta"), "{nan}");
    let vehicle = ModelSpec::shipped("vehicle8").resolve().unwrap();
    let no_steer = error(SteerMapSettings::default(), &vehicle);
    assert!(no_steer.contains("T_delta"), "{no_steer}");
}
