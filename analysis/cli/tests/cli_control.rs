//! The control commands (`sim`, `disturb`, `phase`, `linear`, `tune`) end to end: the real
//! binary, with assertions on the physics (mirror symmetry, the Kp > M_x g threshold, the
//! closed-form pendulum eigenvalue and gain margin) rather than on snapshots; and for bad input
//! one clear message, a non-zero exit, no panic and no partial output.

mod common;

use std::path::Path;

use common::{fails_with, negative_with, twv};

use serde_json::Value;

/// Run and expect success; the stdout.
fn ok(args: &[&str]) -> String {
    let out = twv(args);
    assert!(
        out.status.success(),
        "twv {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// Run with `--json` appended and expect success; the parsed stdout.
fn json(args: &[&str]) -> Value {
    let mut all = args.to_vec();
    all.push("--json");
    serde_json::from_str(&ok(&all)).expect("stdout is JSON")
}

fn scratch(name: &str) -> common::Scratch {
    common::scratch("cli-control", name)
}

fn num(v: &Value) -> f64 {
    v.as_f64()
        .unwrap_or_else(|| panic!("expected a number, got {v}"))
}

/// A complex number serialised as `[re, im]`.
fn complex(v: &Value) -> (f64, f64) {
    (num(&v[0]), num(&v[1]))
}

// The paper vehicle (vehicles/paper.toml): m1 = 115, m2 = 8, b = 0.55, I2_yy = 0.81, g = 9.81.
const M1: f64 = 115.0;
const M2: f64 = 8.0;
const L: f64 = 0.55;
const I2_YY: f64 = 0.81;
const G: f64 = 9.81;
/// The translational mass M_x = m1 + m2 [kg].
const MX: f64 = M1 + M2;
/// The study's PD gain Kp [N/rad].
const STUDY_KP: f64 = 3860.0;

/// The upright pendulum's open-loop eigenvalue: λ² = m_p g l M_x / (I_p M_x − m_p² l²),
/// I_p = I_y + m_p l² (docs/src/conventions.md).
fn lambda() -> f64 {
    let ip = I2_YY + M2 * L * L;
    (M2 * G * L * MX / (ip * MX - M2 * M2 * L * L)).sqrt()
}

/// A CSV with a header: the column names and the numeric rows.
struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Csv {
    fn read(path: &Path) -> Csv {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let header: Vec<String> = lines
            .next()
            .expect("a header")
            .split(',')
            .map(String::from)
            .collect();
        let rows: Vec<Vec<f64>> = lines
            .map(|l| {
                let row: Vec<f64> = l
                    .split(',')
                    .map(|c| c.parse().unwrap_or_else(|_| panic!("`{c}` in {l}")))
                    .collect();
                assert_eq!(row.len(), header.len(), "row width: {l}");
                row
            })
            .collect();
        assert!(!rows.is_empty(), "{} has no rows", path.display());
        Csv { header, rows }
    }

    fn col(&self, name: &str) -> Vec<f64> {
        let i = self
            .header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header));
        self.rows.iter().map(|r| r[i]).collect()
    }
}

fn is_svg(path: &Path) -> bool {
    std::fs::read_to_string(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
        .starts_with("<svg")
}

/// `twv disturb --direction DIR --t-end 5 --out OUT --json`: the JSON on stdout.
fn disturb(dir: &Path, tilt: &str) -> Value {
    json(&[
        "disturb",
        "--direction",
        tilt,
        "--t-end",
        "5",
        "--out",
        dir.to_str().unwrap(),
    ])
}

#[test]
fn disturb_recovers_and_forward_and_backward_mirror_each_other() {
    let base = scratch("disturb");
    let (fwd, bwd) = (base.join("forward"), base.join("backward"));
    let jf = disturb(&fwd, "forward");
    let jb = disturb(&bwd, "backward");
    for (dir, j, sign) in [(&fwd, &jf, 1.0), (&bwd, &jb, -1.0)] {
        for svg in ["phi.svg", "phi_dot.svg", "v_x.svg", "x.svg", "force.svg"] {
            assert!(is_svg(&dir.join(svg)), "{svg}");
        }
        // metrics.json holds what --json printed.
        let file: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("metrics.json")).unwrap())
                .unwrap();
        assert_eq!(&file, j);
        let m = &j["metrics"];
        for v in [
            &m["phi"]["settling_time"],
            &m["phi"]["overshoot"],
            &m["phi"]["iae"],
            &m["peak_force"],
        ] {
            assert!(num(v).is_finite(), "{m}");
        }
        assert_eq!(j["end"]["kind"], "completed");
        assert!(num(&m["phi"]["settling_time"]) < 5.0);
        assert!(num(&m["peak_force"]) > 0.0);

        let csv = Csv::read(&dir.join("sim.csv"));
        for c in ["phi", "w_y", "v_x", "x"] {
            assert!(csv.header.iter().any(|h| h == c), "{c}: {:?}", csv.header);
        }
        let phi = csv.col("phi");
        assert_eq!(phi[0], sign * 0.1, "the tilt's sign and default size");
        let end = *phi.last().unwrap();
        assert!(end.abs() <= 0.02 * phi[0].abs(), "Φ back within 2 %: {end}");
        // A forward tilt is caught by driving forward, a backward one by driving backward.
        assert!(sign * csv.col("x").last().unwrap() > 0.0);
        assert!(sign * num(&m["final_v_x"]) > 0.0);
    }
    // Mirror images: Φ, Φ̇, v_x, x and the force change sign, time and the rest do not.
    let (f, b) = (
        Csv::read(&fwd.join("sim.csv")),
        Csv::read(&bwd.join("sim.csv")),
    );
    assert_eq!(f.header, b.header);
    assert_eq!(f.rows.len(), b.rows.len());
    assert_eq!(f.col("t"), b.col("t"));
    for c in ["phi", "w_y", "v_x", "x", "F"] {
        let (cf, cb) = (f.col(c), b.col(c));
        let scale = cf.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        assert!(scale > 0.0, "{c} moves");
        for (i, (u, v)) in cf.iter().zip(&cb).enumerate() {
            assert!((u + v).abs() <= 1e-12 * scale, "{c}[{i}]: {u} vs {v}");
        }
    }
    for c in ["y", "theta", "v_y", "w_z"] {
        assert!(f.col(c).iter().chain(&b.col(c)).all(|v| *v == 0.0), "{c}");
    }
    let (mf, mb) = (&jf["metrics"], &jb["metrics"]);
    for k in ["iae", "settling_time", "overshoot"] {
        assert_eq!(mf["phi"][k], mb["phi"][k], "{k}");
    }
    assert_eq!(mf["peak_force"], mb["peak_force"]);
    assert_eq!(num(&mf["x_displacement"]), -num(&mb["x_displacement"]));
}

#[test]
fn disturb_magnitude_sets_the_initial_tilt() {
    let j = json(&[
        "disturb",
        "--direction",
        "backward",
        "--tilt",
        "0.05",
        "--t-end",
        "1",
    ]);
    assert_eq!(num(&j["x0"][0]), -0.05);
}

#[test]
fn maneuver_starts_cruises_and_stops() {
    let base = scratch("maneuver");
    let dir = base.join("out");
    let j = json(&[
        "sim",
        "--scenario",
        "maneuver",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert_eq!(j["end"]["kind"], "completed");
    let m = &j["metrics"];
    assert!(num(&m["final_v_x"]).abs() < 0.05, "stopped: {m}");
    assert!(num(&m["final_phi"]).abs() < 0.01, "upright: {m}");
    // The distance is the area under the reference: 2 m/s × (3 s ramp + 5 s cruise) = 16 m.
    let x = num(&m["x_displacement"]);
    assert!(x > 0.0 && (x - 16.0).abs() < 0.5, "x displacement {x}");
    let csv = Csv::read(&dir.join("sim.csv"));
    let v_max = csv.col("v_x").iter().fold(f64::MIN, |a, v| a.max(*v));
    assert!((1.5..3.0).contains(&v_max), "cruise speed reached: {v_max}");
    assert_eq!(
        csv.col("v_ref").iter().fold(f64::MIN, |a, v| a.max(*v)),
        2.0
    );
}

#[test]
fn sim_below_kp_threshold_falls_over_and_says_so() {
    // A fall is a result, not an error: exit 0, reported in the summary and the JSON.
    // Kp = 1000 N/rad < M_x g = 1206.63 N/rad.
    let args = ["sim", "--gains", "1000,0,300", "--t-end", "5"];
    let text = ok(&args);
    assert!(text.contains("FELL OVER"), "{text}");
    let j = json(&args);
    assert_eq!(j["end"]["kind"], "fell", "{}", j["end"]);
    assert!(num(&j["end"]["phi"]).abs() >= std::f64::consts::FRAC_PI_2);
    assert!(num(&j["end"]["t"]) < 5.0);
    // The study's PD on the same run does not fall.
    assert!(!ok(&["sim", "--t-end", "5"]).contains("FELL"));
}

#[test]
fn sim_kp_threshold_is_mx_g() {
    // With Φ_ref = 0 the loop is stable iff Kp > M_x g = 1206.63 N/rad (docs/src/conventions.md): just below
    // the tilt grows, just above it decays.
    let final_phi = |kp: f64| {
        let gains = format!("{kp},0,300");
        let j = json(&[
            "sim",
            "--gains",
            &gains,
            "--setpoint",
            "zero",
            "--t-end",
            "8",
        ]);
        assert_eq!(j["end"]["kind"], "completed", "Kp {kp}");
        num(&j["metrics"]["final_phi"])
    };
    assert!((MX * G - 1206.63).abs() < 1e-9);
    assert!(final_phi(0.985 * MX * G) > 0.1, "grows below the threshold");
    assert!(
        final_phi(1.015 * MX * G) < 0.1,
        "decays above the threshold"
    );
}

#[test]
fn phase_draws_four_portraits_and_names_the_stable_sets() {
    let base = scratch("phase");
    let dir = base.join("out");
    let j = json(&["phase", "--t-end", "3", "--out", dir.to_str().unwrap()]);
    for f in [
        "phase_1.svg",
        "phase_2.svg",
        "phase_3.svg",
        "phase_4.svg",
        "phase.svg",
    ] {
        assert!(is_svg(&dir.join(f)), "{f}");
    }
    // The combined figure draws the four portraits (each with its own axes), and a PNG of
    // every figure lies beside it.
    let combined = std::fs::read_to_string(dir.join("phase.svg")).unwrap();
    assert_eq!(combined.matches(">\nΦ [rad]\n<").count(), 4);
    for f in ["phase_1.png", "phase.png"] {
        assert_eq!(&std::fs::read(dir.join(f)).unwrap()[1..4], b"PNG", "{f}");
    }
    let file: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("phase.json")).unwrap()).unwrap();
    assert_eq!(file, j);
    let csv = Csv::read(&dir.join("phase.csv"));
    assert_eq!(csv.header, ["set", "run", "t", "phi", "phi_dot"]);
    let sets = csv.col("set");
    assert_eq!((sets[0], *sets.last().unwrap()), (1.0, 4.0));

    let portraits = j["portraits"].as_array().unwrap();
    assert_eq!(portraits.len(), 4);
    let stable: Vec<bool> = portraits
        .iter()
        .map(|p| num(&p["loop_abscissa"]) < 0.0)
        .collect();
    // (a) Ki above the Routh–Hurwitz limit, (b) stable PID, (c) Kp < M_x g, (d) the study's PD.
    assert_eq!(stable, [false, true, false, true]);
    let pd = &portraits[3];
    assert_eq!(num(&pd["controller"]["pitch"]["gains"]["kp"]), STUDY_KP);
    for r in pd["runs"].as_array().unwrap() {
        assert_eq!(r["end"]["kind"], "completed");
        assert!(num(&r["final_phi"]).abs() < 0.05 * num(&r["phi0"]).abs());
    }
    // The saddle (c) throws the larger tilts over.
    assert!(portraits[2]["runs"]
        .as_array()
        .unwrap()
        .iter()
        .any(|r| r["end"]["kind"] == "fell"));
}

#[test]
fn phase_with_given_gain_sets_and_open_loop_forces() {
    let j = json(&[
        "phase",
        "--gains",
        "3860,0,1980;1000,0,300",
        "--x0",
        "0.05,0,0,0,0,0,0,0",
        "--t-end",
        "1",
    ]);
    let p = j["portraits"].as_array().unwrap();
    assert_eq!(p.len(), 2);
    assert_eq!(p[0]["runs"].as_array().unwrap().len(), 1);
    // Open loop, no force: the upright is a saddle with rate λ.
    let j = json(&["phase", "--force", "0,0", "--t-end", "0.5"]);
    let a = num(&j["portraits"][0]["loop_abscissa"]);
    assert!((a - lambda()).abs() < 1e-6, "{a} vs {}", lambda());
}

#[test]
fn linear_matches_the_closed_form_pendulum() {
    let j = json(&["linear"]);
    assert!(num(&j["residual"]) < 1e-12);
    let lam = lambda();
    // The open loop's unstable mode is +λ, and −λ is there too.
    let modes = j["open_loop"].as_array().unwrap();
    let unstable: Vec<&Value> = modes.iter().filter(|m| m["kind"] == "Unstable").collect();
    assert_eq!(unstable.len(), 1);
    let (re, im) = complex(&unstable[0]["eigenvalue"]);
    assert!((re - lam).abs() <= 1e-9 && im == 0.0, "{re} vs {lam}");
    assert!(modes.iter().any(|m| {
        let (re, im) = complex(&m["eigenvalue"]);
        (re + lam).abs() <= 1e-9 && im == 0.0
    }));
    // The study's PD: a stable loop whose gain can drop to M_x g / Kp.
    assert_eq!(j["pitch"]["verdict"], "stable");
    assert!(num(&j["pitch"]["spectral_abscissa"]) < 0.0);
    let margins = &j["pitch"]["margins"];
    let lower = num(&margins["gain_margin_lower"]);
    assert!((lower - MX * G / STUDY_KP).abs() <= 1e-6, "{lower}");
    assert!(
        margins["gain_margin_upper"].is_null(),
        "no upper limit for a PD"
    );
    // Another Kp moves the lower margin as M_x g / Kp.
    let j5 = json(&["linear", "--gains", "5000,0,1500"]);
    let lower = num(&j5["pitch"]["margins"]["gain_margin_lower"]);
    assert!((lower - MX * G / 5000.0).abs() <= 1e-6, "{lower}");
    // LQR: Riccati residual and a stable closed loop.
    let lqr = &j["lqr"];
    assert_eq!(lqr["status"], "Solved");
    assert!(num(&lqr["residual"]) <= 1e-9);
    assert!(num(&lqr["spectral_abscissa"]) < 0.0);
    for e in lqr["closed_loop_eigenvalues"].as_array().unwrap() {
        assert!(complex(e).0 < 0.0);
    }
}

#[test]
fn linear_hanging_oscillates_at_lambda() {
    // An unstable loop is a negative verdict: exit code 3, the analysis still printed.
    let out = twv(&["linear", "--at", "hanging", "--json"]);
    negative_with(&out, &["unstable"]);
    let j: Value = serde_json::from_slice(&out.stdout).unwrap();
    let lam = lambda();
    assert!(num(&j["residual"]) < 1e-9);
    let marginal: Vec<(f64, f64)> = j["open_loop"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|m| m["kind"] == "Marginal")
        .map(|m| complex(&m["eigenvalue"]))
        .collect();
    assert_eq!(marginal.len(), 2, "{marginal:?}");
    for (re, im) in &marginal {
        assert!(
            re.abs() <= 1e-9 && (im.abs() - lam).abs() <= 1e-9,
            "{re} {im}"
        );
    }
    assert!(marginal[0].1 * marginal[1].1 < 0.0, "±iλ");
    // The upright's PD is wrong-signed here: the loop is unstable, and no margin is claimed.
    assert_eq!(j["pitch"]["verdict"], "unstable");
    assert!(j["pitch"]["margins"].is_null());
}

#[test]
fn linear_works_on_segway7() {
    let j = json(&["linear", "--model", "segway7"]);
    assert_eq!(j["model"], "segway7");
    assert!(j["open_loop"]
        .as_array()
        .unwrap()
        .iter()
        .any(|m| m["kind"] == "Unstable" && complex(&m["eigenvalue"]).0 > 0.0));
    assert_eq!(j["pitch"]["verdict"], "stable");
    assert!(num(&j["lqr"]["residual"]) <= 1e-9);
    assert!(num(&j["lqr"]["spectral_abscissa"]) < 0.0);
    // The summary prints as well.
    assert!(ok(&["linear", "--model", "segway7"]).contains("stable"));
}

#[test]
fn tune_meets_a_disk_phase_margin_and_the_gains_check_out() {
    let j = json(&["tune", "--spec", "dpm>=45"]);
    let r = &j["result"];
    assert_eq!(r["status"], "Solved");
    let c = &r["certificate"];
    assert_eq!(c["meets_spec"], true);
    assert_eq!(c["analysis"]["closed_loop"]["stable"], true);
    assert!(num(&c["analysis"]["closed_loop"]["spectral_abscissa"]) < 0.0);
    assert!(num(&c["analysis"]["margins"]["disk"]["phase_deg"]) >= 45.0);
    // Independently, through `twv linear` with the tuned gains.
    let g = &c["gains"];
    let (kp, ki, kd) = (num(&g["kp"]), num(&g["ki"]), num(&g["kd"]));
    assert!(kp > MX * G, "a stabilising PD needs Kp > M_x g: {kp}");
    let gains = format!("{kp},{ki},{kd}");
    let lin = json(&["linear", "--gains", &gains]);
    assert_eq!(lin["pitch"]["verdict"], "stable");
    let dpm = num(&lin["pitch"]["margins"]["disk_phase_deg"]);
    assert!(dpm >= 45.0 - 1e-6, "{dpm}");
}

/// An objective that stops at the iteration limit is not called an optimum (issue 38: "met
/// (IterationLimit)" with Kp = 241,326 read as a tuned result); one that converges is.
#[test]
fn an_objective_stopped_at_the_iteration_limit_says_so() {
    let unbounded = ok(&["tune", "--pid", "--objective", "max-proportional"]);
    assert!(unbounded.contains("not an optimum"), "{unbounded}");
    assert!(unbounded.contains("limit of 60 subproblems"), "{unbounded}");
    let j = json(&["tune", "--pid", "--objective", "max-proportional"]);
    assert_eq!(j["result"]["status"], "IterationLimit");
    let converged = ok(&["tune", "--spec", "dpm>=45"]);
    assert!(converged.contains("met (Solved"), "{converged}");
    assert!(!converged.contains("not an optimum"), "{converged}");
}

#[test]
fn tune_reports_an_infeasible_spec_with_the_best_fraction() {
    let out = twv(&["tune", "--spec", "dpm>=89.9", "--delay", "0.2", "--json"]);
    let stderr = negative_with(&out, &["infeasible", "dpm>=89.9", "%"]);
    let j: Value = serde_json::from_slice(&out.stdout).expect("the result still prints");
    assert_eq!(j["result"]["status"], "Infeasible");
    let best = num(&j["result"]["best_fraction"]);
    assert!((0.0..1.0).contains(&best), "{best}");
    let pct = format!("{:.1} %", 100.0 * best);
    assert!(stderr.contains(&pct), "`{pct}` missing from: {stderr}");
    // Never silently relaxed: the certificate, if any, does not claim the spec.
    if let Some(c) = j["result"]["certificate"].as_object() {
        assert!(num(&c["analysis"]["margins"]["disk"]["phase_deg"]) < 89.9);
    }
}

#[test]
fn tune_malformed_spec_is_named() {
    fails_with(&twv(&["tune", "--spec", "dpm>>45"]), &["dpm>>45"]);
    fails_with(&twv(&["tune", "--spec", "foo>=3"]), &["foo>=3"]);
    fails_with(&twv(&["tune", "--spec", "dpm>=120"]), &["dpm", "120"]);
    fails_with(&twv(&["tune", "--spec", ""]), &["expected"]);
}

#[test]
fn malformed_gains_are_a_clear_error() {
    for cmd in [
        &["sim", "--gains", "1,2"][..],
        &["disturb", "--direction", "forward", "--gains", "1,2"],
        &["phase", "--gains", "1,2"],
        &["phase", "--gains", "3860,0,1980;1,2"],
        &["linear", "--gains", "1,2"],
    ] {
        fails_with(&twv(cmd), &["--gains", "1,2", "Kp,Ki,Kd"]);
    }
    fails_with(&twv(&["sim", "--gains", "3860,x,1980"]), &["--gains", "x"]);
    fails_with(&twv(&["tune", "--target", "1"]), &["--target", "Kp,Kd"]);
}

#[test]
fn unwritable_output_directory_is_an_error_without_output() {
    let dir = scratch("unwritable");
    let file = dir.join("a-file");
    std::fs::write(&file, "").unwrap();
    let target = file.join("sub");
    let target = target.to_str().unwrap();
    for cmd in [
        &["sim", "--t-end", "0.5", "--out", target][..],
        &[
            "disturb",
            "--direction",
            "backward",
            "--t-end",
            "0.5",
            "--out",
            target,
        ],
        &["phase", "--t-end", "0.5", "--out", target],
    ] {
        let out = twv(cmd);
        fails_with(&out, &["a-file"]);
        assert!(out.stdout.is_empty(), "nothing printed for {cmd:?}");
        assert_eq!(
            std::fs::read_dir(&dir).unwrap().count(),
            1,
            "nothing written besides the file ({cmd:?})"
        );
        assert_eq!(std::fs::read(&file).unwrap(), b"", "the file is untouched");
    }
}

#[test]
fn non_positive_magnitude_and_times_are_rejected() {
    for m in ["-0.1", "0", "nan"] {
        let out = twv(&["disturb", "--direction", "forward", "--tilt", m]);
        fails_with(&out, &["--tilt", "> 0"]);
    }
    for t in ["-5", "0", "inf"] {
        for cmd in [
            &["sim", "--t-end", t][..],
            &["disturb", "--direction", "forward", "--t-end", t],
            &["phase", "--t-end", t],
        ] {
            fails_with(&twv(cmd), &["t_end", "> 0"]);
        }
    }
    fails_with(&twv(&["sim", "--sample", "0"]), &["sample", "> 0"]);
    // A run too long to hold in memory is refused up front, not after hours.
    fails_with(
        &twv(&["sim", "--t-end", "1e9"]),
        &["number of samples", "100000000000", "sample interval"],
    );
    fails_with(&twv(&["sim", "--fall-angle", "-1"]), &["fall angle", "-1"]);
    fails_with(&twv(&["linear", "--delay", "-1"]), &["delay", "-1"]);
    fails_with(&twv(&["tune", "--actuator-lag", "-1"]), &["lag", "-1"]);
    fails_with(&twv(&["linear", "--lqr-r", "0"]), &["--lqr-r"]);
    for lean in ["2", "0", "-0.1", "nan"] {
        let cmd = ["sim", "--v-loop", "0.08,0.03", "--lean-max", lean];
        fails_with(&twv(&cmd), &["lean limit", "(0, π/2)"]);
    }
    fails_with(
        &twv(&["sim", "--lean-max", "0.05"]),
        &["--lean-max", "v_loop"],
    );
}

#[test]
fn unknown_model_is_named() {
    for cmd in [
        &["sim", "--model", "nope"][..],
        &["disturb", "--direction", "forward", "--model", "nope"],
        &["phase", "--model", "nope"],
        &["linear", "--model", "nope"],
        &["tune", "--model", "nope"],
    ] {
        fails_with(&twv(cmd), &["nope", "vehicle8"]);
    }
    // A shipped model without a pitch.
    fails_with(&twv(&["sim", "--model", "lorenz"]), &["lorenz"]);
    fails_with(&twv(&["phase", "--model", "lorenz"]), &["lorenz", "phi"]);
}

#[test]
fn wrong_state_lengths_name_the_option() {
    fails_with(
        &twv(&["sim", "--x0", "0.1,0,0"]),
        &["--x0", "3 values", "phi"],
    );
    fails_with(&twv(&["linear", "--at", "1,2"]), &["--at", "2 values"]);
}

/// The help text of `option` in `help`: from its flag line to the next option's.
fn option_help<'a>(help: &'a str, option: &str) -> &'a str {
    let is_flag = |l: &str| {
        let t = l.trim_start();
        t.starts_with("--")
            || (t.starts_with('-') && t.chars().nth(1).is_some_and(char::is_alphabetic))
    };
    let lines: Vec<&str> = help.lines().collect();
    let start = lines
        .iter()
        .position(|l| is_flag(l) && l.trim_start().split([' ', ',']).any(|w| w == option))
        .unwrap_or_else(|| panic!("{option} missing from help:\n{help}"));
    let end = lines[start + 1..]
        .iter()
        .position(|l| is_flag(l))
        .map_or(lines.len(), |i| start + 1 + i);
    let from = help.find(lines[start]).unwrap();
    let to = if end < lines.len() {
        help.find(lines[end]).unwrap()
    } else {
        help.len()
    };
    &help[from..to]
}

#[test]
fn every_control_subcommand_documents_its_options_with_units_and_defaults() {
    // (subcommand, [(option, every substring its help must contain)]).
    type Expect<'a> = (&'a str, Vec<(&'a str, Vec<&'a str>)>);
    let run_options = || {
        vec![
            ("--t-end", vec!["[s]", "default"]),
            ("--sample", vec!["[s]", "default: 0.01"]),
            ("--h", vec!["[s]", "default"]),
            ("--fall-angle", vec!["[rad]", "default"]),
            ("--f-max", vec!["[N]", "default"]),
            ("--rate-filter", vec!["[s]", "default"]),
            ("--gains", vec!["[N/rad", "default"]),
            ("--model", vec!["default: vehicle8"]),
            ("--out", vec!["DIR"]),
            ("--json", vec!["JSON"]),
        ]
    };
    let cases: Vec<Expect> = vec![
        ("sim", {
            let mut v = run_options();
            v.push(("--tilt", vec!["[rad]", "default: 0.1"]));
            v.push(("--v-cruise", vec!["[m/s]", "default: 2"]));
            v.push(("--scenario", vec!["default: tilt", "maneuver"]));
            v
        }),
        ("disturb", {
            let mut v = run_options();
            v.push(("--tilt", vec!["[rad]", "default: 0.1"]));
            v.push(("--direction", vec!["forward", "backward"]));
            v
        }),
        ("phase", {
            let mut v = run_options();
            v.push(("--force", vec!["[N, N m]"]));
            v.push(("--x0", vec!["default"]));
            v
        }),
        (
            "linear",
            vec![
                ("--at", vec!["upright", "hanging", "default: upright"]),
                ("--gains", vec!["[N/rad", "default: kp=3860,ki=0,kd=1980"]),
                ("--lag", vec!["[s]", "default: 0"]),
                ("--delay", vec!["[s]", "default: 0"]),
                ("--lqr-r", vec!["default"]),
            ],
        ),
        (
            "tune",
            vec![
                ("--spec", vec!["dpm", "default: dpm>=45"]),
                ("--target", vec!["[N/rad"]),
                ("--lag", vec!["[s]", "default: 0"]),
                ("--delay", vec!["[s]", "default: 0"]),
                ("--objective", vec!["min_gain", "default"]),
            ],
        ),
    ];
    for (cmd, expect) in cases {
        let help = ok(&[cmd, "--help"]);
        for (option, needles) in expect {
            let text = option_help(&help, option);
            for n in needles {
                assert!(
                    text.contains(n),
                    "`twv {cmd} --help`, {option}: `{n}` missing from\n{text}"
                );
            }
        }
        // Every option has a description, not just its flag.
        for line in help.lines().filter(|l| l.trim_start().starts_with("--")) {
            let option = line.split_whitespace().next().unwrap();
            let text = option_help(&help, option);
            let words = text.split_whitespace().count();
            assert!(
                words >= 3,
                "`twv {cmd} --help`: {option} is undocumented:\n{text}"
            );
        }
    }
}
