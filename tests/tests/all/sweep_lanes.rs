//! The sweep's eight-at-a-time max-Lyapunov metric (`max_lyapunov_lanes`, lanes kernel, lanes
//! refilled as their points finish) gives every point exactly the bits and status of the
//! one-point metric (`metric::max_lyapunov`), whatever mix of outcomes shares a group, for PD
//! (the lane-wise law: plain, saturated, about a constant lean), PID with saturation and every
//! controller part, with the AVX-512 and AVX2 lanes kernels and with the one-lane-at-a-time
//! fallback. The one-point metric is the library's Benettin run (`lyapunov_spectrum_with`)
//! bit for bit, and its settled tail moves λ1 by at most its stated tolerance.

use twv_analysis::control::{
    AntiWindup, ControllerSettings, PidLoop, PitchPid, Plant, Profile, Setpoint, VelocityLoop,
    YawLoop,
};
use twv_analysis::linear::PidGains;
use twv_analysis::sweep::{
    max_lyapunov_lanes, metric, DriverChoice, MetricSettings, PointResult, Status,
};
use twv_generated::Vehicle8;
use twv_kernels::lanes::LANES;
use twv_model::Model;

fn plant(model: &Vehicle8) -> Plant<2> {
    Plant::from_info(&model.info(), &|n| {
        let i = Vehicle8::PARAMS.iter().position(|p| p.name == n)?;
        Some(Vehicle8::DEFAULTS[i])
    })
    .unwrap()
}

/// Eight gain sets whose runs end in every way: falls (Kp below M_x g), stable and unstable
/// oscillations, a stiff loop that RK4 with h = 1 ms cannot follow (Kd = 10⁷: it diverges and
/// falls), a gain that overflows in the first step (blows up), and ordinary points.
const GAINS: [(f64, f64); LANES] = [
    (100.0, 50.0),
    (3860.0, 1980.0),
    (8000.0, 4000.0),
    (2000.0, 10.0),
    (3000.0, 1.0e7),
    (1500.0, 600.0),
    (5000.0, 200.0),
    (1.0e306, 0.0),
];

/// More points for the lanes to take as others finish: loops that come to rest early (their
/// settled tail is taken), late, slowly and not at all (a slow divergence, an oscillation).
const MORE: [(f64, f64); 6] = [
    (4667.0, 1667.0),
    (7333.0, 3000.0),
    (1333.0, 3667.0),
    (667.0, 3000.0),
    (1333.0, 0.0),
    (3333.0, 833.0),
];

/// `a` and `b` are the same point, bit for bit (value, status, rest time).
#[track_caller]
fn same_point(a: &PointResult, b: &PointResult, what: &str) {
    let tag = format!("{what}, point {} (Kp {}, Kd {})", b.index, b.kp, b.kd);
    assert_eq!(a.index, b.index, "{tag}");
    assert_eq!((a.kp, a.ki, a.kd), (b.kp, b.ki, b.kd), "{tag}");
    assert_eq!(a.status, b.status, "{tag}");
    assert_eq!(a.settled_at, b.settled_at, "{tag}");
    assert_eq!(
        a.value.map(f64::to_bits),
        b.value.map(f64::to_bits),
        "{tag}: {:?} vs {:?}",
        a.value,
        b.value
    );
}

/// Runs both paths for `base` with the gains above (plus `ki`), compares every point; returns
/// the points.
fn compare<const NA: usize>(base: &ControllerSettings, ki: f64, what: &str) -> Vec<PointResult> {
    let model = Vehicle8::with_defaults();
    let plant = plant(&model);
    let s = MetricSettings {
        iterations: 15,
        ..MetricSettings::default()
    };
    let mut x0 = [0.0; 8];
    x0[plant.measured.phi] = 0.1;
    let settings: Vec<ControllerSettings> = GAINS
        .iter()
        .chain(&MORE)
        .map(|&(kp, kd)| ControllerSettings {
            pitch: PitchPid {
                gains: PidGains { kp, ki, kd },
                ..base.pitch
            },
            ..base.clone()
        })
        .collect();
    let loops: Vec<PidLoop<'_, Vehicle8, 8, 2, NA>> = settings
        .iter()
        .map(|c| PidLoop::new(&model, c, plant).unwrap())
        .collect();
    let indices: Vec<usize> = (0..loops.len()).map(|l| 100 + 7 * l).collect();
    let one: Vec<PointResult> = (0..loops.len())
        .map(|l| metric::max_lyapunov(&loops[l], &x0, &s, indices[l]))
        .collect();
    use twv_kernels::isa::{force, Isa};
    // Each build this CPU can run (a lower one is what `force` falls back to otherwise).
    for isa in [Isa::Avx512, Isa::Avx2, Isa::Neon, Isa::Baseline] {
        let used = force(isa);
        let lanes = max_lyapunov_lanes(&loops, &x0, &s, &indices, &DriverChoice::default());
        assert_eq!(lanes.len(), one.len(), "{what}: one result per point");
        for (a, b) in lanes.iter().zip(&one) {
            same_point(a, b, &format!("{what} ({} kernel)", used.name()));
        }
    }
    force(Isa::Avx512);
    one
}

#[test]
fn lanes_metric_has_the_bits_of_the_one_point_metric() {
    // The study's PD with its 0.03 sin Φ setpoint (what `twv sweep` maps by default).
    let pd = ControllerSettings::default();
    let points = compare::<8>(&pd, 0.0, "PD");
    let statuses: Vec<Status> = points.iter().map(|p| p.status).collect();
    for wanted in [Status::Ok, Status::Fell, Status::BlewUp] {
        assert!(
            statuses.contains(&wanted),
            "the PD group should contain a {wanted:?} point: {statuses:?}"
        );
    }
    // Lanes refilled from a settled point as well as from a finished horizon.
    let settled = points.iter().filter(|p| p.settled_at.is_some()).count();
    let full = points.iter().filter(|p| p.status == Status::Ok).count() - settled;
    assert!(
        settled > 0 && full > 0,
        "the PD points should include settled ({settled}) and full-horizon ({full}) runs"
    );

    // PD with a force limit some gains reach (the lane-wise law's saturated branch), and PD
    // about a constant lean (its setpoint without a Φ-derivative).
    let saturated = ControllerSettings {
        pitch: PitchPid {
            saturation: Some(3000.0),
            ..pd.pitch
        },
        ..ControllerSettings::default()
    };
    compare::<8>(&saturated, 0.0, "PD saturated");
    let lean = ControllerSettings {
        pitch: PitchPid {
            setpoint: Setpoint::Constant { value: 0.02 },
            ..pd.pitch
        },
        ..ControllerSettings::default()
    };
    compare::<8>(&lean, 0.0, "PD about a constant lean");

    // PID with saturation and back-calculation (NA = 9).
    let pid = ControllerSettings {
        pitch: PitchPid {
            setpoint: Setpoint::STUDY,
            saturation: Some(3000.0),
            anti_windup: AntiWindup::BackCalculation { tracking_time: 0.5 },
            ..PitchPid::default()
        },
        ..ControllerSettings::default()
    };
    compare::<9>(&pid, 400.0, "PID saturated");

    // Every controller part: rate filter, velocity PI, yaw P (NA = 11).
    let all = ControllerSettings {
        pitch: PitchPid {
            derivative_filter: Some(0.02),
            anti_windup: AntiWindup::Conditional,
            saturation: Some(6000.0),
            ..pid.pitch
        },
        velocity: Some(VelocityLoop {
            kp: 0.05,
            ki: 0.01,
            reference: Profile::constant(1.0),
            lean_max: None,
        }),
        yaw: Some(YawLoop {
            kp: 40.0,
            reference: Profile::constant(0.2),
        }),
    };
    compare::<11>(&all, 400.0, "every controller part");
}

/// The metric's run, written with the library's pieces as `metric::max_lyapunov` was before it
/// had its own driver: RK4 on the projected loop, stopped at a fall, through the Benettin
/// driver of `twv lyap` with the metric's settings.
fn benettin_reference(
    lp: &PidLoop<'_, Vehicle8, 8, 2, 8>,
    x0: &[f64; 8],
    s: &MetricSettings,
) -> PointResult {
    use std::cell::Cell;
    use twv_analysis::control::loop_states;
    use twv_analysis::integrate::{Projected, Rk4};
    use twv_analysis::lyapunov::{initial_basis, lyapunov_spectrum_with, LyapunovError};
    use twv_analysis::sweep::FallStop;
    let settings = metric::lyapunov_settings(s);
    let fell = Cell::new(false);
    let xa = lp.initial_state(x0);
    let projected = Projected {
        field: lp,
        keep: loop_states(lp, &[xa]),
    };
    let w0 = initial_basis::<8, 1>(&settings.basis);
    let outcome = Rk4::new(projected, 0.0, xa, w0, s.h, false)
        .map_err(LyapunovError::from)
        .and_then(|inner| {
            let stepper = FallStop {
                inner,
                phi: lp.plant().measured.phi,
                limit: s.fall_angle,
                fell: &fell,
            };
            lyapunov_spectrum_with::<_, 8, 1>(stepper, &settings)
        });
    let (value, status) = match outcome {
        _ if fell.get() => (None, Status::Fell),
        Ok(r) => (r.exponents.first().copied(), Status::Ok),
        Err(LyapunovError::Integrate(_)) => (None, Status::BlewUp),
        Err(_) => (None, Status::Failed),
    };
    let value = value.filter(|v| v.is_finite());
    PointResult {
        index: 0,
        kp: lp.settings().pitch.gains.kp,
        ki: lp.settings().pitch.gains.ki,
        kd: lp.settings().pitch.gains.kd,
        status: if status == Status::Ok && value.is_none() {
            Status::Failed
        } else {
            status
        },
        value,
        settled_at: None,
    }
}

/// The PD loops of `gains` on the default vehicle, and the tilted start.
fn pd_loops<'a>(
    model: &'a Vehicle8,
    settings: &'a [ControllerSettings],
) -> (Vec<PidLoop<'a, Vehicle8, 8, 2, 8>>, [f64; 8]) {
    let plant = plant(model);
    let loops = settings
        .iter()
        .map(|c| PidLoop::new(model, c, plant).unwrap())
        .collect();
    let mut x0 = [0.0; 8];
    x0[plant.measured.phi] = 0.1;
    (loops, x0)
}

fn pd_settings(gains: impl IntoIterator<Item = (f64, f64)>) -> Vec<ControllerSettings> {
    gains
        .into_iter()
        .map(|(kp, kd)| ControllerSettings::pid(PidGains { kp, ki: 0.0, kd }))
        .collect()
}

#[test]
fn without_the_settled_tail_the_metric_is_the_benettin_run_bit_for_bit() {
    let model = Vehicle8::with_defaults();
    let settings = pd_settings(GAINS.iter().chain(&MORE).copied());
    let (loops, x0) = pd_loops(&model, &settings);
    let s = MetricSettings {
        iterations: 15,
        settle_distance: None,
        ..MetricSettings::default()
    };
    for lp in &loops {
        let ours = metric::max_lyapunov(lp, &x0, &s, 0);
        let reference = benettin_reference(lp, &x0, &s);
        same_point(&ours, &reference, "the metric against the Benettin run");
    }
}

#[test]
fn the_settled_tail_moves_lambda1_by_at_most_its_stated_tolerance() {
    use twv_analysis::sweep::SETTLED_TAIL_TOLERANCE;
    // The study's settings (K = 100 after the 1 s transient) on a (Kp, Kd) grid spanning the
    // map: falls, fast and slow decays, oscillations, a slow divergence.
    let gains = [700.0, 1333.0, 2500.0, 4000.0, 5500.0, 8000.0]
        .into_iter()
        .flat_map(|kp| [0.0, 300.0, 800.0, 1600.0, 2800.0, 4000.0].map(|kd| (kp, kd)));
    let model = Vehicle8::with_defaults();
    let settings = pd_settings(gains);
    let (loops, x0) = pd_loops(&model, &settings);
    let indices: Vec<usize> = (0..loops.len()).collect();
    let run = |settle_distance| {
        let s = MetricSettings {
            settle_distance,
            ..MetricSettings::default()
        };
        max_lyapunov_lanes(&loops, &x0, &s, &indices, &DriverChoice::default())
    };
    let full = run(None);
    let largest_change = |with: &[PointResult]| {
        let mut largest = 0.0_f64;
        for (a, b) in with.iter().zip(&full) {
            assert_eq!(a.status, b.status, "Kp {} Kd {}", b.kp, b.kd);
            if let (Some(x), Some(y)) = (a.value, b.value) {
                largest = largest.max((x - y).abs());
            }
        }
        largest
    };
    let default = run(MetricSettings::default().settle_distance);
    let settled = default.iter().filter(|p| p.settled_at.is_some()).count();
    let ok = default.iter().filter(|p| p.status == Status::Ok).count();
    assert!(
        settled >= ok / 3 && settled < ok,
        "{settled} of {ok} runs should take the settled tail (some, not all)"
    );
    for p in &default {
        if let Some(t) = p.settled_at {
            assert!(
                t > 1.0 && t < 11.0,
                "settled at {t} s: after the transient, before the end"
            );
        }
    }
    let change = largest_change(&default);
    assert!(
        change <= SETTLED_TAIL_TOLERANCE,
        "λ1 moved by {change:e} /s with the settled tail (stated tolerance {SETTLED_TAIL_TOLERANCE:e})"
    );
    // The rest criterion is what holds the tolerance: calling loops at rest that still have a
    // tenth of a radian to go breaks it.
    let loose = largest_change(&run(Some(0.3)));
    assert!(
        loose > SETTLED_TAIL_TOLERANCE,
        "a loose rest criterion should break the tolerance (moved {loose:e} /s)"
    );
}

/// A sweep's driver build is the one its first chunks ran fastest, whichever that is: the
/// builds take turns while timed, then the smallest time per step wins (on a CPU with one
/// build, the baseline, there is nothing to choose); a sweep of few chunks is not timed.
#[test]
fn a_sweep_runs_the_driver_build_its_timed_chunks_found_fastest() {
    use twv_kernels::isa::{current, Isa};
    let chosen = |baseline_time: f64| {
        let choice = DriverChoice::with_timing(true);
        let mut timed = Vec::new();
        loop {
            let (isa, to_time) = choice.next();
            if !to_time {
                break (isa, timed);
            }
            timed.push(isa);
            let per_step = if isa == Isa::Baseline {
                baseline_time
            } else {
                1.0
            };
            choice.record(isa, per_step);
        }
    };
    // The driver has builds for x86-64's AVX2 and AVX-512; elsewhere the baseline only.
    let best = match current() {
        Isa::Avx512 | Isa::Avx2 => current(),
        Isa::Neon | Isa::Baseline => Isa::Baseline,
    };
    let (slow_baseline, timed) = chosen(2.0);
    assert_eq!(slow_baseline, best, "timed: {timed:?}");
    let (fast_baseline, timed) = chosen(0.5);
    assert_eq!(fast_baseline, Isa::Baseline, "timed: {timed:?}");
    if best != Isa::Baseline {
        assert!(timed.contains(&best) && timed.contains(&Isa::Baseline));
    }
    // A sweep of few chunks is not timed: it runs the kernels' instruction set throughout.
    let few = DriverChoice::for_chunks(DriverChoice::MIN_TIMED_CHUNKS - 1);
    assert_eq!(few.next(), (current(), false));
    assert!(
        DriverChoice::for_chunks(DriverChoice::MIN_TIMED_CHUNKS)
            .next()
            .1
            || best == Isa::Baseline
    );
}
