//! The firmware crate (`twv-firmware`: no_std, the C API of `include/twv_firmware.h`) against
//! the analysis library: its closed loop is the library's `PidLoop` under the library's RK4,
//! bit for bit, so the Cortex-M4 run of `.ci/cortex-m-test.sh` (which has the host's bits) is
//! twv's own simulation.

use twv_analysis::control::{ControllerSettings, PidLoop, Plant};
use twv_analysis::integrate::{Rk4, Stepper, VectorField};
use twv_analysis::linear::PidGains;
use twv_firmware::c_api;
use twv_firmware::pd::{ClosedLoop, PitchPd};
use twv_generated::Vehicle8;
use twv_model::Model;

fn plant(model: &Vehicle8) -> Plant<2> {
    Plant::from_info(&model.info(), &|n| {
        let i = Vehicle8::PARAMS.iter().position(|p| p.name == n)?;
        Some(model.params()[i])
    })
    .unwrap()
}

/// The firmware's law from the library's settings (PD, sine setpoint, optional saturation).
fn law(s: &ControllerSettings) -> PitchPd {
    let amplitude = match s.pitch.setpoint {
        twv_analysis::control::Setpoint::Sine { amplitude } => amplitude,
        twv_analysis::control::Setpoint::Zero => 0.0,
        other => panic!("the firmware's law has no {other:?} setpoint"),
    };
    PitchPd {
        kp: s.pitch.gains.kp,
        kd: s.pitch.gains.kd,
        setpoint_amplitude: amplitude,
        f_max: s.pitch.saturation.unwrap_or(f64::INFINITY),
    }
}

/// The library's state after `steps` RK4 steps of `h` of the PD loop from `x0`.
fn library_run(s: &ControllerSettings, x0: [f64; 8], h: f64, steps: u32) -> [f64; 8] {
    let model = Vehicle8::with_defaults();
    let pid: PidLoop<'_, Vehicle8, 8, 2, 8> = PidLoop::new(&model, s, plant(&model)).unwrap();
    let mut rk4 = Rk4::<_, 8, 0>::new(pid, 0.0, x0, [], h, false).unwrap();
    for _ in 0..steps {
        rk4.step().unwrap();
    }
    rk4.state().x
}

#[test]
fn the_firmware_closed_loop_is_the_librarys_bit_for_bit() {
    let x0 = [0.1, 0.0, 0.0, 0.0, 0.3, 0.0, 0.0, 0.05];
    let study = ControllerSettings::default();
    let saturated = ControllerSettings {
        pitch: twv_analysis::control::PitchPid {
            saturation: Some(400.0),
            ..ControllerSettings::pid(PidGains {
                kp: 3000.0,
                ki: 0.0,
                kd: 900.0,
            })
            .pitch
        },
        ..ControllerSettings::default()
    };
    for (what, s) in [("the study's PD", study), ("a saturated PD", saturated)] {
        let model = Vehicle8::with_defaults();
        let pd = law(&s);
        // The field at one state.
        let pid: PidLoop<'_, Vehicle8, 8, 2, 8> = PidLoop::new(&model, &s, plant(&model)).unwrap();
        let closed = ClosedLoop::new(&model, pd).unwrap();
        let (mut a, mut b) = ([0.0; 8], [0.0; 8]);
        pid.rhs(0.0, &x0, &mut a);
        closed.f(&x0, &mut b);
        assert_eq!(a.map(f64::to_bits), b.map(f64::to_bits), "{what}: ẋ");
        // 2 s of RK4 with the study's 1 ms step.
        let mut x = x0;
        assert!(closed.rk4(&mut x, 1e-3, 2000));
        assert_eq!(
            library_run(&s, x0, 1e-3, 2000).map(f64::to_bits),
            x.map(f64::to_bits),
            "{what}: the state after 2000 steps"
        );
        // ... and the loop did what a PD does: the pitch came back near its setpoint.
        assert!(
            x[0].abs() < 0.05 && x[0].abs() < x0[0],
            "{what}: Φ = {}",
            x[0]
        );
        // The C API gives the same state.
        let mut y = x0;
        let p = Vehicle8::DEFAULTS;
        let status =
            unsafe { c_api::twv_vehicle8_pd_rk4(p.as_ptr(), &pd, y.as_mut_ptr(), 1e-3, 2000) };
        assert_eq!(
            (status, y.map(f64::to_bits)),
            (c_api::OK, x.map(f64::to_bits)),
            "{what}"
        );
    }
}

#[test]
fn the_c_api_refuses_what_it_cannot_use_and_says_when_a_state_blows_up() {
    let p = Vehicle8::DEFAULTS;
    let pd = PitchPd {
        kp: 3000.0,
        kd: 900.0,
        setpoint_amplitude: 0.03,
        f_max: f64::INFINITY,
    };
    let mut x = [0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    unsafe {
        assert_eq!(
            c_api::twv_vehicle8_pd_rk4(p.as_ptr(), &pd, x.as_mut_ptr(), 0.0, 5),
            c_api::BAD_STEP
        );
        assert_eq!(
            c_api::twv_vehicle8_pd_rk4(p.as_ptr(), &pd, x.as_mut_ptr(), f64::NAN, 5),
            c_api::BAD_STEP
        );
        assert_eq!(
            c_api::twv_vehicle8_pd_rk4(core::ptr::null(), &pd, x.as_mut_ptr(), 1e-3, 5),
            c_api::NULL_POINTER
        );
        assert_eq!(
            c_api::twv_vehicle8_f(p.as_ptr(), x.as_ptr(), core::ptr::null(), x.as_mut_ptr()),
            c_api::NULL_POINTER
        );
        assert!(c_api::twv_pitch_pd_force(core::ptr::null(), x.as_ptr()).is_nan());
        assert_eq!(
            x,
            [0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            "refused calls write nothing"
        );
        // A loop far too stiff for the step: RK4 diverges, the status says so.
        let stiff = PitchPd { kd: 1e9, ..pd };
        assert_eq!(
            c_api::twv_vehicle8_pd_rk4(p.as_ptr(), &stiff, x.as_mut_ptr(), 1e-3, 2000),
            c_api::NOT_FINITE
        );
        assert!(x.iter().any(|v| !v.is_finite()));
        let mut dx = [0.0; 8];
        let nan_input = [f64::NAN, 0.0];
        let x0 = [0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
        assert_eq!(
            c_api::twv_vehicle8_f(p.as_ptr(), x0.as_ptr(), nan_input.as_ptr(), dx.as_mut_ptr()),
            c_api::NOT_FINITE
        );
    }
}

#[test]
fn the_c_header_states_the_rust_sizes_and_codes() {
    let header = include_str!("../../../firmware/include/twv_firmware.h");
    let define = |name: &str| -> i64 {
        let line = header
            .lines()
            .find(|l| l.starts_with(&format!("#define {name} ")))
            .unwrap_or_else(|| panic!("no #define {name}"));
        line.split_whitespace().nth(2).unwrap().parse().unwrap()
    };
    assert_eq!(define("TWV_VEHICLE8_NX"), c_api::NX as i64);
    assert_eq!(define("TWV_VEHICLE8_NU"), c_api::NU as i64);
    assert_eq!(define("TWV_VEHICLE8_NP"), c_api::NP as i64);
    assert_eq!(define("TWV_OK"), c_api::OK as i64);
    assert_eq!(define("TWV_NOT_FINITE"), c_api::NOT_FINITE as i64);
    assert_eq!(define("TWV_NULL_POINTER"), c_api::NULL_POINTER as i64);
    assert_eq!(define("TWV_BAD_STEP"), c_api::BAD_STEP as i64);
    assert_eq!(define("TWV_NOT_WIRED"), c_api::NOT_WIRED as i64);
    // The parameter order the header names is the model's.
    let listed = header
        .split_once("Parameters p, in this order:")
        .and_then(|(_, rest)| rest.split_once("(twv's"))
        .unwrap()
        .0
        .replace('*', " ");
    let listed: Vec<&str> = listed.split(',').map(str::trim).collect();
    let names: Vec<&str> = Vehicle8::PARAMS.iter().map(|p| p.name).collect();
    assert_eq!(listed, names);
}
