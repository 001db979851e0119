//! The steer law's rate filter, 1/(τs + 1) on the lean and steer rates it reads: the filtered
//! loop against the benchmark equations with the filter substituted (a second path), the
//! unfiltered loop as τ → 0, the lag's cost in phase margin, the nonlinear closed loop on
//! NX + 2 states (its Jacobian against the linear loop, finite differences and its own
//! trace), rides, portraits and tuning with the filter, and bad input.

use nalgebra::DMatrix;
use serde_json::{json, Value};
use twv_analysis::api::{
    portraits, ride, steady_state, steer, steer_loop, Drive, PhaseSettings, RideSettings,
    RideVerdict, Silent, SteerLoopSettings, SteerVerdict,
};
use twv_analysis::control::steer::{FilteredSteer, SteerLaw, SteerSettings};
use twv_analysis::control::RunSettings;
use twv_analysis::integrate::VectorField;
use twv_analysis::jobs;
use twv_analysis::linear::modes::eigenvalues;
use twv_analysis::linear::SteerGains;
use twv_analysis::model::{ModelSource, ModelSpec};
use twv_analysis::tune::steer::certify_steer;
use twv_analysis::tune::TuneStatus;
use twv_ir::Interpreted;
use twv_model::Model;

use super::steer::{averaged_over, benchmark, benchmark_closed_loop, bicycle, sorted, GAINS};

/// Lean-rate feedback alone, which balances the benchmark bicycle at 3 m/s read directly (its
/// loop abscissa −0.43 1/s) and not through a 50 ms filter (+0.69 1/s).
const LEAN_RATE: SteerGains = SteerGains {
    k_phi: 0.0,
    k_delta: 0.0,
    k_phi_dot: 15.0,
    k_delta_dot: 0.0,
};

/// The benchmark's closed loop with the rates read through the filter: on (φ, δ, φ̇, δ̇, r_φ̇,
/// r_δ̇), written out from M, C1, K0, K2 without twv's steer-loop code.
fn benchmark_filtered(v: f64, g: &SteerGains, tau: f64) -> DMatrix<f64> {
    let angles = SteerGains {
        k_phi_dot: 0.0,
        k_delta_dot: 0.0,
        ..*g
    };
    let minv = benchmark()[0].clone().try_inverse().unwrap();
    let mut a = DMatrix::zeros(6, 6);
    a.view_mut((0, 0), (4, 4))
        .copy_from(&benchmark_closed_loop(v, &angles));
    for i in 0..2 {
        a[(2 + i, 4)] = minv[(i, 1)] * g.k_phi_dot;
        a[(2 + i, 5)] = minv[(i, 1)] * g.k_delta_dot;
        a[(4 + i, 2 + i)] = 1.0 / tau;
        a[(4 + i, 4 + i)] = -1.0 / tau;
    }
    a
}

#[test]
fn the_filtered_loop_is_the_benchmark_equations_with_the_filter_substituted() {
    let model = bicycle();
    for v in [0.5, 3.0, 6.0] {
        for tau in [0.02, 0.1] {
            let lp = steer_loop(&model, v)
                .unwrap()
                .with_rate_filter(Some(tau))
                .unwrap();
            for g in &GAINS {
                let ours = sorted(lp.closed_loop(g).unwrap().eigenvalues);
                let theirs = sorted(eigenvalues(&benchmark_filtered(v, g, tau)).unwrap());
                assert_eq!(ours.len(), 6);
                for (a, b) in ours.iter().zip(&theirs) {
                    assert!(
                        (a - b).norm() <= 1e-10 * b.norm().max(1.0),
                        "at {v} m/s, τ = {tau} s with {g:?}: {a} against {b}"
                    );
                }
                // The stack path a map takes agrees with the eigenvalues.
                let abscissa = lp.closed_loop_abscissa(g).unwrap();
                let largest = theirs.iter().map(|e| e.re).fold(f64::MIN, f64::max);
                assert!((abscissa - largest).abs() <= 1e-10 * largest.abs().max(1.0));
            }
        }
    }
}

#[test]
fn a_vanishing_filter_is_the_unfiltered_loop() {
    let model = bicycle();
    let lp = steer_loop(&model, 3.0).unwrap();
    for g in &GAINS {
        let plain = sorted(lp.closed_loop(g).unwrap().eigenvalues);
        let mut gaps = Vec::new();
        for tau in [1e-5, 1e-6, 1e-7] {
            let filtered = lp.clone().with_rate_filter(Some(tau)).unwrap();
            let mut e = filtered.closed_loop(g).unwrap().eigenvalues;
            // Two fast poles near −1/τ; the other four approach the unfiltered loop's.
            e.sort_by(|a, b| b.re.total_cmp(&a.re));
            for fast in &e[4..] {
                assert!(
                    fast.re < -0.3 / tau,
                    "τ = {tau}: a fast pole {fast} far from −1/τ"
                );
            }
            let slow = sorted(e[..4].to_vec());
            let gap = slow
                .iter()
                .zip(&plain)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            gaps.push(gap);
        }
        // The slow poles' error shrinks in proportion to τ (first order in τ).
        assert!(gaps[2] < 1e-3, "{gaps:?}");
        for w in gaps.windows(2) {
            assert!(w[1] < 0.2 * w[0], "{gaps:?}");
        }
        // The margins too: the disk margin's phase at τ = 1e-7 is the unfiltered one's.
        let a0 = lp.analyse(g).unwrap().margins.disk.phase_deg;
        let a1 = lp
            .clone()
            .with_rate_filter(Some(1e-7))
            .unwrap()
            .analyse(g)
            .unwrap()
            .margins
            .disk
            .phase_deg;
        assert!((a0 - a1).abs() < 1e-2, "{a0} against {a1}");
    }
}

/// A low-pass filter lags: the longer τ, the less phase margin lean-rate feedback (steering
/// into the fall) keeps, until the loop is unstable — a verdict that flips with τ.
#[test]
fn the_filters_lag_costs_phase_margin_until_the_loop_is_unstable() {
    let model = bicycle();
    let lp = steer_loop(&model, 3.0).unwrap();
    let g = LEAN_RATE;
    let mut margins = Vec::new();
    for tau in [None, Some(0.002), Some(0.005), Some(0.01)] {
        let a = lp
            .clone()
            .with_rate_filter(tau)
            .unwrap()
            .analyse(&g)
            .unwrap();
        assert!(a.closed_loop.stable, "τ = {tau:?}");
        margins.push(a.margins.disk.phase_deg);
    }
    for w in margins.windows(2) {
        assert!(w[1] < w[0], "disk phase margins {margins:?}");
    }
    let slow = lp.with_rate_filter(Some(0.05)).unwrap();
    assert!(!slow.closed_loop(&g).unwrap().stable);
}

fn filtered_field_check(tau: f64, saturation: Option<f64>) {
    let model = bicycle();
    let bike = Interpreted::<9, 4>::new(&model.ir, &model.params).unwrap();
    let info = bike.info();
    let modes: Vec<String> = ["phi", "delta", "w_phi", "w_delta"]
        .map(String::from)
        .to_vec();
    let settings = SteerSettings {
        gains: GAINS[0],
        saturation,
        rate_filter: Some(tau),
    };
    let law = SteerLaw::<9, 4>::new(
        "whipple",
        info.states,
        info.inputs,
        &modes,
        &settings,
        [0.0; 4],
    )
    .unwrap();
    let field = FilteredSteer::<_, 9, 4, 11>::new(&bike, law).unwrap();
    assert_eq!(
        FilteredSteer::<Interpreted<9, 4>, 9, 4, 11>::filter_states(info.states, &law),
        ["w_phi_f".to_string(), "w_delta_f".to_string()]
    );
    let v = 3.0;
    let steady: [f64; 9] = steady_state(&model, v).unwrap().try_into().unwrap();
    let xa = field.initial_state(&steady);
    // At straight running, on the modes and the filter, J is the linear filtered loop.
    let mut jac = [[0.0; 11]; 11];
    field.jacobian(0.0, &xa, &mut jac);
    let linear = steer_loop(&model, v)
        .unwrap()
        .with_rate_filter(Some(tau))
        .unwrap()
        .closed_loop_matrix(&GAINS[0]);
    let index: Vec<usize> = modes
        .iter()
        .map(|m| model.state_index(m).unwrap())
        .chain([9, 10])
        .collect();
    for (i, &r) in index.iter().enumerate() {
        for (j, &c) in index.iter().enumerate() {
            let (a, b) = (jac[r][c], linear[(i, j)]);
            assert!(
                (a - b).abs() <= 1e-12 * b.abs().max(1.0),
                "J[{r}][{c}] = {a} against the linear loop's {b}"
            );
        }
    }
    // Away from it (leaning, steering, the filter lagging): J against central differences of
    // the field, and the trace against J's diagonal.
    let mut x = xa;
    for (i, dx) in [
        (3, 0.05),
        (5, -0.03),
        (6, 0.2),
        (8, -0.1),
        (9, 0.15),
        (10, 0.3),
    ] {
        x[i] += dx;
    }
    field.jacobian(0.0, &x, &mut jac);
    for c in 0..11 {
        let h = 1e-6;
        let (mut up, mut down) = (x, x);
        up[c] += h;
        down[c] -= h;
        let (mut fu, mut fd) = ([0.0; 11], [0.0; 11]);
        field.rhs(0.0, &up, &mut fu);
        field.rhs(0.0, &down, &mut fd);
        for r in 0..11 {
            let fd_value = (fu[r] - fd[r]) / (2.0 * h);
            assert!(
                (jac[r][c] - fd_value).abs() <= 1e-5 * fd_value.abs().max(1.0),
                "∂F_{r}/∂x_{c}: {} against finite differences {fd_value} (τ {tau}, limit \
                 {saturation:?})",
                jac[r][c]
            );
        }
    }
    let diagonal: f64 = (0..11).map(|i| jac[i][i]).sum();
    let trace = field.trace_jacobian(0.0, &x);
    assert!(
        (trace - diagonal).abs() <= 1e-10 * diagonal.abs().max(1.0),
        "{trace} against {diagonal}"
    );
}

#[test]
fn the_filtered_nonlinear_loop_has_the_linear_loops_jacobian_and_its_own_exact_one() {
    filtered_field_check(0.05, None);
    // Saturated at this state (|T| > 1 N m): the rates' and angles' gains act no more.
    filtered_field_check(0.05, Some(1.0));
}

/// `ride` and `phase` with the filter: two more columns (the filtered rates, in rad/s,
/// starting at the rates), a recovery with a short filter that turns into a fall with a long
/// one (the linear loop's verdict flips between them), and a portrait whose abscissa is the
/// filtered loop's.
#[test]
fn a_filtered_ride_recovers_or_falls_as_its_linear_loop_says() {
    let bike = bicycle();
    let v = 3.0;
    let lp = steer_loop(&bike, v).unwrap();
    for (tau, recovers) in [(0.01, true), (0.05, false)] {
        let stable = lp
            .clone()
            .with_rate_filter(Some(tau))
            .unwrap()
            .closed_loop(&LEAN_RATE)
            .unwrap()
            .stable;
        assert_eq!(stable, recovers);
        let s = RideSettings {
            speed: Some(v),
            perturb: [("w_phi".to_string(), 0.1)].into(),
            steer: Some(SteerSettings {
                rate_filter: Some(tau),
                ..SteerSettings::gains(LEAN_RATE)
            }),
            watch: "phi".into(),
            run: RunSettings {
                t_end: 10.0,
                ..RunSettings::default()
            },
            ..RideSettings::default()
        };
        let r = ride(&bike, &s, &Silent).unwrap();
        assert_eq!(r.columns.len(), 1 + 9 + 2);
        assert_eq!(&r.columns[10..], ["w_phi_f", "w_delta_f"]);
        assert_eq!(&r.units[10..], ["rad/s", "rad/s"]);
        let (w_phi, w_delta) = (
            bike.state_index("w_phi").unwrap() + 1,
            bike.state_index("w_delta").unwrap() + 1,
        );
        assert_eq!(r.rows[0][10], r.rows[0][w_phi]);
        assert_eq!(r.rows[0][11], r.rows[0][w_delta]);
        assert_eq!(
            r.verdict == RideVerdict::Recovered,
            recovers,
            "τ = {tau}: {:?}, peak {}, tail {}",
            r.verdict,
            r.peak,
            r.tail_peak
        );
    }
    let settings = PhaseSettings {
        portraits: vec![(
            "design".into(),
            Drive::Steer(SteerSettings::gains(GAINS[0])),
        )],
        tilts: vec![0.02],
        speed: Some(v),
        steer_filter: Some(0.05),
        run: RunSettings {
            t_end: 4.0,
            ..RunSettings::default()
        },
        ..PhaseSettings::default()
    };
    let p = portraits(&bike, &settings, &Silent).unwrap();
    let sigma = lp
        .with_rate_filter(Some(0.05))
        .unwrap()
        .closed_loop(&GAINS[0])
        .unwrap()
        .spectral_abscissa;
    let ours = p.portraits[0].loop_abscissa.unwrap();
    assert!((ours - sigma).abs() <= 1e-8, "{ours} against {sigma}");
    assert_eq!(p.portraits[0].steer.unwrap().rate_filter, Some(0.05));
}

/// `steer --rate-filter τ`: the schedule is tuned and certified on the filtered loop (the
/// certificate equals an independent certification with the filter, and the same gains
/// certified without it have other margins). A lag makes a spec infeasible that is met
/// without it: reported with the best fraction reached, a verdict that flips with τ.
#[test]
fn a_schedule_tuned_with_the_filter_is_certified_with_it() {
    let bike = bicycle();
    let tau = 0.02;
    let s = SteerLoopSettings {
        lo: 2.0,
        hi: 3.0,
        step: 1.0,
        rate_filter: Some(tau),
        spec: "dpm>=30".parse().unwrap(),
        ..SteerLoopSettings::default()
    };
    let r = steer(&bike, &s, &Silent).unwrap();
    assert_eq!(r.verdict, SteerVerdict::Met);
    assert_eq!(r.rate_filter, Some(tau));
    for p in &r.points {
        let c = p.certificate.as_ref().unwrap();
        let lp = steer_loop(&bike, p.speed).unwrap();
        let filtered = lp.clone().with_rate_filter(Some(tau)).unwrap();
        let again = certify_steer(&filtered, &c.gains, &s.spec).unwrap();
        assert_eq!(again.analysis.closed_loop.eigenvalues.len(), 6);
        assert_eq!(again.analysis.margins.disk, c.analysis.margins.disk);
        assert!(c.meets_spec && p.ride.unwrap().verdict == RideVerdict::Recovered);
        let plain = certify_steer(&lp, &c.gains, &s.spec).unwrap();
        assert!(
            (plain.analysis.margins.disk.phase_deg - c.analysis.margins.disk.phase_deg).abs() > 0.1,
            "the filter changes the margins"
        );
    }
    // 45° of disk phase margin at 2 m/s: met reading the rates directly, not through 50 ms.
    let at_two = |rate_filter| SteerLoopSettings {
        lo: 2.0,
        hi: 2.0,
        rate_filter,
        ..SteerLoopSettings::default()
    };
    let direct = steer(&bike, &at_two(None), &Silent).unwrap();
    assert_eq!(direct.verdict, SteerVerdict::Met);
    let lagged = steer(&bike, &at_two(Some(0.05)), &Silent).unwrap();
    assert_eq!(lagged.verdict, SteerVerdict::NotMet);
    let p = &lagged.points[0];
    assert_eq!(p.tune_status, Some(TuneStatus::Infeasible));
    assert!(
        p.best_fraction > 0.5 && p.best_fraction < 1.0,
        "{}",
        p.best_fraction
    );
}

#[test]
fn bad_filters_get_one_line_naming_the_option() {
    let refused = |job: &str, model: &str, given: Vec<(&str, Value)>| -> String {
        let given: Vec<(String, Value)> =
            given.into_iter().map(|(k, v)| (k.to_string(), v)).collect();
        let job = jobs::find(job).unwrap();
        let e = match job.prepare_options(None, &given) {
            Err(e) => e.to_string(),
            Ok(p) => {
                let m = ModelSpec::shipped(model).resolve().unwrap();
                p.run(&m, &Silent).err().unwrap().to_string()
            }
        };
        assert!(!e.contains('\n'), "{e}");
        e
    };
    let gains = json!("k_phi_dot=15");
    for tau in [json!(0.0), json!(-0.1), json!(1e9)] {
        let e = refused(
            "ride",
            "whipple",
            vec![("steer_gains", gains.clone()), ("steer_filter", tau)],
        );
        assert!(e.starts_with("steer_filter:"), "{e}");
    }
    let e = refused("ride", "whipple", vec![("steer_filter", json!(0.05))]);
    assert!(
        e.starts_with("steer_filter:") && e.contains("steer_gains"),
        "{e}"
    );
    let e = refused(
        "ride",
        "vehicle8",
        vec![
            ("steer_gains", gains.clone()),
            ("steer_filter", json!(0.05)),
        ],
    );
    assert!(e.contains("steer input"), "{e}");
    for job in ["steer", "steer_map", "uncertainty"] {
        let e = refused(job, "whipple", vec![("rate_filter", json!(-1.0))]);
        assert!(e.starts_with("rate_filter:"), "{job}: {e}");
    }
    let e = refused("phase", "whipple", vec![("steer_filter", json!(0.05))]);
    assert!(e.starts_with("steer_filter:"), "{e}");
}

/// The steered jobs are compiled for the bicycles' state count (9) alone: a model of another
/// count that does have a steer input (vehicle8's IR with its second input renamed `T_delta`)
/// gets one line naming its count, with or without the rate filter; without the rename it is
/// refused for having no steer input, the check before it.
#[test]
fn a_steer_law_on_a_model_of_another_state_count_is_refused_by_name() {
    let vehicle8 = twv_generated::ir_json("vehicle8").expect("vehicle8 is shipped");
    let run = |ir_text: &str, job: &str, given: &[(&str, Value)]| -> String {
        let ir = twv_ir::parse_ir(ir_text, "vehicle8 (steer input renamed)").unwrap();
        let model = ModelSpec {
            model: ModelSource::Ir(Box::new(ir)),
            ..ModelSpec::default()
        }
        .resolve()
        .unwrap();
        let given: Vec<(String, Value)> = given
            .iter()
            .map(|(k, v)| (k.to_string(), v.clone()))
            .collect();
        let prepared = jobs::find(job)
            .unwrap()
            .prepare_options(None, &given)
            .unwrap();
        let e = prepared.run(&model, &Silent).err().unwrap().to_string();
        assert!(!e.contains('\n'), "{e}");
        e
    };
    let steered = twv_ir::rehash(&vehicle8.replace("\"T2\"", "\"T_delta\""));
    assert_ne!(steered, vehicle8, "vehicle8's IR names its input T2");
    let gains = ("steer_gains", json!("k_phi_dot=15"));
    let x0 = ("x0", json!([0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]));
    let cases: [(&str, Vec<(&str, Value)>); 3] = [
        ("ride", vec![gains.clone()]),
        ("ride", vec![gains.clone(), ("steer_filter", json!(0.05))]),
        ("lyapunov", vec![gains.clone(), x0]),
    ];
    for (job, given) in &cases {
        let e = run(&steered, job, given);
        assert!(
            e.contains("9 states") && e.contains("this one has 8"),
            "{job}: {e}"
        );
        let e = run(vehicle8, job, given);
        assert!(e.contains("no steer input"), "{job}: {e}");
    }
}

/// `lyapunov --speed 3 --steer-gains … --steer-filter τ`: the spectrum of the filtered closed
/// loop on 11 states is the real parts of its 6 loop poles and 5 drift zeros.
#[test]
fn the_filtered_loops_lyapunov_spectrum_is_its_closed_loop_eigenvalues() {
    use twv_analysis::api::{spectrum, SpectrumSettings};
    let bike = bicycle();
    let tau = 0.02;
    let lp = steer_loop(&bike, 3.0)
        .unwrap()
        .with_rate_filter(Some(tau))
        .unwrap();
    let mut expected: Vec<f64> = lp
        .closed_loop(&LEAN_RATE)
        .unwrap()
        .eigenvalues
        .iter()
        .map(|e| e.re)
        .collect();
    expected.resize(11, 0.0);
    expected.sort_by(|a, b| b.total_cmp(a));
    let s = SpectrumSettings {
        speed: Some(3.0),
        steer: Some(SteerSettings {
            rate_filter: Some(tau),
            ..SteerSettings::gains(LEAN_RATE)
        }),
        lyapunov: averaged_over(40.0),
        ..SpectrumSettings::default()
    };
    let r = spectrum(&bike, &s, &Silent).unwrap();
    assert!(r.model.ends_with("(steered, rate filter)"), "{}", r.model);
    assert_eq!(r.result.exponents.len(), 11);
    for (k, (got, want)) in r.result.exponents.iter().zip(&expected).enumerate() {
        // 40 s of averaging: within ~1/40 1/s of a slow real part (0.05 for the shearing
        // drift directions, see the unfiltered test); RK4 at h = 10 ms is within 0.5 % of the
        // filter's fast poles near −1/τ (h/τ = 0.5).
        let tolerance = if want.abs() > 20.0 {
            0.005 * want.abs()
        } else {
            0.05
        };
        assert!(
            (got - want).abs() < tolerance,
            "λ{}: {got} against Re {want} ({:?})",
            k + 1,
            r.result.exponents
        );
    }
}

/// `linearize --speed 3 --steer-gains … --steer-filter τ`: the loop's 6 poles are the
/// benchmark's with the filter substituted, and every state's closed loop (the model's 9 × 9
/// Jacobian and the filter, 11 modes) has exactly those besides the 5 drift modes; the
/// filter's states are named after the rates.
#[test]
fn linearize_closes_the_filtered_loop_about_the_steady_motion() {
    use twv_analysis::api::{analyse, LinearSettings};
    let bike = bicycle();
    let (v, tau) = (3.0, 0.02);
    let report = analyse(
        &bike,
        &LinearSettings {
            speed: Some(v),
            steer: Some(SteerSettings {
                rate_filter: Some(tau),
                ..SteerSettings::gains(GAINS[1])
            }),
            ..LinearSettings::default()
        },
    )
    .unwrap();
    let steer = report.steer.unwrap();
    let theirs = sorted(eigenvalues(&benchmark_filtered(v, &GAINS[1], tau)).unwrap());
    let poles = sorted(steer.loop_poles.eigenvalues.clone());
    assert_eq!(poles.len(), 6);
    for (a, b) in poles.iter().zip(&theirs) {
        assert!(
            (a - b).norm() <= 1e-10 * b.norm().max(1.0),
            "{a} against {b}"
        );
    }
    assert_eq!(steer.closed_loop.len(), 11);
    let moving: Vec<_> = steer
        .closed_loop
        .iter()
        .map(|m| m.eigenvalue)
        .filter(|e| e.norm() > 1e-9)
        .collect();
    let moving = sorted(moving);
    assert_eq!(moving.len(), 6, "{moving:?}");
    for (a, b) in moving.iter().zip(&theirs) {
        assert!(
            (a - b).norm() <= 1e-8 * b.norm().max(1.0),
            "{a} against {b}"
        );
    }
    assert!(steer
        .closed_loop
        .iter()
        .any(|m| m.states.iter().any(|s| s == "w_phi_f")));
}
