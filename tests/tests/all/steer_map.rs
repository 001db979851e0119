//! `twv steer-map`: every cell of a map against the published linear benchmark equations with
//! the feedback substituted (a second path), the zero-gain row against the open loop's
//! self-stable band, a verdict that flips when the gain's values move into the stabilising
//! range, a gain × gain map at one speed against the same equations, and bad input.

use twv_analysis::api::{steer_map, Silent, SteerMapResult, SteerMapSettings, SteerMapVerdict};
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
        ..SteerMapSettings::default()
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

/// Maps `away` (nowhere stable, its verdict naming `named`), then the same map with the
/// varied gain's values `into` (stable somewhere), which it returns.
fn flips(away: SteerMapSettings, into: Axis, named: &str) -> SteerMapResult {
    let r = steer_map(&bicycle(), &away, &Silent).unwrap();
    assert_eq!(
        (r.verdict, r.stable_cells),
        (SteerMapVerdict::NowhereStable, 0)
    );
    assert!(
        matches!(r.verdict(), Verdict::Negative(ref m) if m.contains(named)),
        "{:?}",
        r.verdict()
    );
    assert!(
        r.summary().contains("no value of k_phi_dot"),
        "{}",
        r.summary()
    );
    let into = SteerMapSettings {
        values: into,
        ..away
    };
    let r = steer_map(&bicycle(), &into, &Silent).unwrap();
    assert_eq!(r.verdict, SteerMapVerdict::StableSomewhere);
    assert!(r.stable_cells > 0 && r.verdict() == Verdict::Done);
    r
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
    let r = flips(away, axis(5.0, 40.0, 8), "k_phi_dot");
    // Files a person can open: the CSV has a row per cell, the figure renders.
    let files = r.files().unwrap();
    let names = files.names();
    assert!(names.contains(&"map.svg"), "{names:?}");
    assert_eq!(r.csv().lines().count(), 1 + 7 * 8);
}

/// The benchmark equations' spectral abscissa closed by `g` at `v` m/s.
fn benchmark_abscissa(v: f64, g: &SteerGains) -> f64 {
    spectral_abscissa(&eigenvalues(&benchmark_closed_loop(v, g)).unwrap())
}

/// Every cell of the gain × gain map `r` (the other gains `fixed`) is the benchmark equations'
/// closed loop at its speed, to the published matrices' digits.
fn gain_by_gain_is_the_benchmarks(r: &SteerMapResult, fixed: SteerGains) {
    let index = |name: &str| SteerGains::NAMES.iter().position(|n| *n == name).unwrap();
    let (j, k) = (index(&r.gain), index(r.against.as_deref().unwrap()));
    let n = r.against_values.len();
    for (jv, &y) in r.values.iter().enumerate() {
        for (i, &x) in r.against_values.iter().enumerate() {
            let mut row = fixed.row();
            (row[j], row[k]) = (y, x);
            let theirs = benchmark_abscissa(r.speeds[0], &SteerGains::from_row(row));
            let ours = r.abscissa[jv * n + i].unwrap();
            assert!(
                (ours - theirs).abs() <= 1e-10 * theirs.abs().max(1.0),
                "{row:?}: {ours} against the benchmark's {theirs}"
            );
        }
    }
}

#[test]
fn a_gain_by_gain_map_is_the_benchmark_equations_at_its_speed() {
    // At 3 m/s, below the weave speed: lean-rate × lean feedback, a steer-angle gain fixed.
    let s = SteerMapSettings {
        speed: axis(3.0, 3.0, 1),
        gain: "k_phi_dot".into(),
        values: axis(-10.0, 30.0, 9),
        against: Some("k_phi".into()),
        against_values: axis(-20.0, 100.0, 13),
        gains: SteerGains {
            k_delta: -5.0,
            k_phi: 1e6, // the varied gains' entries are ignored
            ..SteerGains::default()
        },
        ..SteerMapSettings::default()
    };
    let r = steer_map(&bicycle(), &s, &Silent).unwrap();
    assert_eq!((r.abscissa.len(), r.against_values.len()), (9 * 13, 13));
    gain_by_gain_is_the_benchmarks(&r, s.gains);
    let n = r.against_values.len();
    // Each column is one value of k_phi at the map's speed.
    for (i, range) in r.stabilising.iter().enumerate() {
        assert_eq!(
            (range.speed, range.against),
            (3.0, Some(r.against_values[i]))
        );
        let count = (0..r.values.len())
            .filter(|j| r.abscissa[j * n + i].unwrap() < 0.0)
            .count();
        assert_eq!(range.count, count);
    }
    // Nobody steering, the bicycle is unstable at 3 m/s (below its weave speed, 4.29).
    let open = r.unsteered_abscissa.unwrap();
    assert!(
        (open - benchmark_abscissa(3.0, &SteerGains::default())).abs() < 1e-10 && open > 0.0,
        "{open}"
    );
    assert!(
        r.summary().contains("at 3 m/s it is unstable"),
        "{}",
        r.summary()
    );
    assert_eq!(r.verdict, SteerMapVerdict::StableSomewhere);
    // The CSV names the second gain; the figure's x axis is it.
    let csv = r.csv();
    assert!(
        csv.starts_with("speed,k_phi,k_phi_dot,closed_loop_abscissa,stable\n"),
        "{csv}"
    );
    assert_eq!(csv.lines().count(), 1 + 9 * 13);
    assert!(r.files().unwrap().names().contains(&"map.svg"));
}

#[test]
fn a_gain_by_gain_verdict_flips_with_the_gains() {
    // Steering away from a growing lean balances it at 2 m/s for no lean gain of the map;
    // steering into it does.
    let away = SteerMapSettings {
        speed: axis(2.0, 2.0, 1),
        values: axis(-40.0, -1.0, 6),
        against: Some("k_phi".into()),
        against_values: axis(-50.0, 50.0, 11),
        ..SteerMapSettings::default()
    };
    let r = flips(away, axis(1.0, 40.0, 6), "k_phi_dot and k_phi");
    gain_by_gain_is_the_benchmarks(&r, SteerGains::default());
}

#[test]
fn bad_input_gets_one_line_naming_it() {
    let at_3 = |against: &str| SteerMapSettings {
        speed: axis(3.0, 3.0, 1),
        against: Some(against.into()),
        ..SteerMapSettings::default()
    };
    let cases = [
        (
            SteerMapSettings {
                speed: axis(-1.0, 5.0, 10),
                ..SteerMapSettings::default()
            },
            ["speed", "≥ 0"],
        ),
        (
            SteerMapSettings {
                gain: "k_psi".into(),
                ..SteerMapSettings::default()
            },
            ["k_psi", "k_phi_dot"],
        ),
        (
            SteerMapSettings {
                values: axis(0.0, 1.0, 1_000_001),
                ..SteerMapSettings::default()
            },
            ["values", "1000"],
        ),
        (
            SteerMapSettings {
                gains: SteerGains {
                    k_delta: f64::NAN,
                    ..SteerGains::default()
                },
                ..SteerMapSettings::default()
            },
            ["k_delta", "k_delta"],
        ),
        // A gain × gain map against its own gain, at several speeds, against no gain.
        (at_3("k_phi_dot"), ["against", "k_phi_dot"]),
        (
            SteerMapSettings {
                speed: axis(1.0, 5.0, 3),
                ..at_3("k_phi")
            },
            ["speed", "one speed"],
        ),
        (at_3("k_psi"), ["against", "k_psi"]),
    ];
    let model = bicycle();
    for (s, words) in cases {
        let e = steer_map(&model, &s, &Silent).unwrap_err().to_string();
        assert!(!e.contains('\n'), "{e}");
        assert!(words.iter().all(|w| e.contains(w)), "{e}: wanted {words:?}");
    }
    let vehicle = ModelSpec::shipped("vehicle8").resolve().unwrap();
    let e = steer_map(&vehicle, &SteerMapSettings::default(), &Silent).unwrap_err();
    assert!(e.to_string().contains("T_delta"), "{e}");
}
