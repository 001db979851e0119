//! The sweep's eight-at-a-time max-Lyapunov metric (`max_lyapunov_lanes`, lanes kernel) gives
//! every point exactly the bits and status of the one-point metric (`metric::max_lyapunov`),
//! whatever mix of outcomes shares a group, for PD (the lane-wise law: plain, saturated, about
//! a constant lean), PID with saturation and every controller part, with the AVX-512 and AVX2
//! lanes kernels and with the one-lane-at-a-time fallback.

use twv_analysis::control::{
    AntiWindup, ControllerSettings, PidLoop, PitchPid, Plant, Profile, Setpoint, VelocityLoop,
    YawLoop,
};
use twv_analysis::linear::PidGains;
use twv_analysis::sweep::{max_lyapunov_lanes, metric, MetricSettings, PointResult, Status};
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

/// Runs both paths for `base` with the gains above (plus `ki`), compares every point.
fn compare<const NA: usize>(base: &ControllerSettings, ki: f64, what: &str) -> Vec<Status> {
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
    let loops: [_; LANES] = loops.try_into().unwrap_or_else(|_| unreachable!());
    let indices: [usize; LANES] = std::array::from_fn(|l| 100 + 7 * l);
    let one: Vec<PointResult> = (0..LANES)
        .map(|l| metric::max_lyapunov(&loops[l], &x0, &s, indices[l]))
        .collect();
    use twv_kernels::isa::{force, Isa};
    // Each build this CPU can run (a lower one is what `force` falls back to otherwise).
    for isa in [Isa::Avx512, Isa::Avx2, Isa::Baseline] {
        let used = force(isa);
        let lanes = max_lyapunov_lanes(&loops, &x0, &s, indices);
        for (a, b) in lanes.iter().zip(&one) {
            let tag = format!("{what} ({} kernel) point {}", used.name(), b.index);
            assert_eq!(a.index, b.index, "{tag}");
            assert_eq!((a.kp, a.ki, a.kd), (b.kp, b.ki, b.kd), "{tag}");
            assert_eq!(a.status, b.status, "{tag}");
            assert_eq!(
                a.value.map(f64::to_bits),
                b.value.map(f64::to_bits),
                "{tag}: {:?} vs {:?}",
                a.value,
                b.value
            );
        }
    }
    force(Isa::Avx512);
    one.iter().map(|p| p.status).collect()
}

#[test]
fn lanes_metric_has_the_bits_of_the_one_point_metric() {
    // The study's PD with its 0.03 sin Φ setpoint (what `twv sweep` maps by default).
    let pd = ControllerSettings::default();
    let statuses = compare::<8>(&pd, 0.0, "PD");
    for wanted in [Status::Ok, Status::Fell, Status::BlewUp] {
        assert!(
            statuses.contains(&wanted),
            "the PD group should contain a {wanted:?} point: {statuses:?}"
        );
    }

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
