//! The `twv` binary end to end: results on stdout, and for bad input one clear message naming
//! the file, field or value, a non-zero exit, no panic or backtrace, and no partial output.

mod common;

use std::path::{Path, PathBuf};
use std::process::Output;

use common::{fails_with, negative_with, twv};

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn scratch(name: &str) -> common::Scratch {
    common::scratch("cli", name)
}

fn paper_with(dir: &Path, edit: impl Fn(&str) -> String) -> PathBuf {
    let text = std::fs::read_to_string(repo().join("vehicles/paper.toml")).unwrap();
    let path = dir.join("vehicle.toml");
    std::fs::write(&path, edit(&text)).unwrap();
    path
}

const X8: &str = "0.1,0,0,0,0,0,0,0";

fn eval_with_params(params: &Path) -> Output {
    twv(&[
        "eval",
        "--model",
        "vehicle8",
        "--params",
        params.to_str().unwrap(),
        "--x",
        X8,
    ])
}

#[test]
fn eval_prints_f_and_jacobians_as_json() {
    let out = twv(&[
        "eval", "--model", "vehicle8", "--x", X8, "--u", "50,0", "--jac",
    ]);
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["f"].as_array().unwrap().len(), 8);
    assert_eq!(v["jac_x"].as_array().unwrap().len(), 8);
    assert_eq!(v["jac_u"][0].as_array().unwrap().len(), 2);
    // The pitch acceleration at a forward tilt is positive (the pendulum falls forward).
    assert!(v["f"][4].as_f64().unwrap() > 0.0);
}

/// `--isa` with a build this CPU cannot run says what runs instead (an aarch64 build on x86-64,
/// an x86-64 one on aarch64), the best one below it, with the same results; `--quiet` hides it.
#[test]
fn an_isa_this_cpu_lacks_is_named_with_the_one_used() {
    use twv_kernels::isa::{available, Isa};
    let args = ["eval", "--model", "lorenz", "--x", "1,2,3"];
    let missing = [Isa::Neon, Isa::Avx2, Isa::Avx512]
        .into_iter()
        .find(|isa| !available(*isa))
        .expect("no CPU has both NEON and AVX2");
    let flag = missing.name().to_lowercase().replace('-', "");
    let reference = twv(&args);
    let out = twv(&[&["--isa", flag.as_str()], &args[..]].concat());
    assert!(out.status.success());
    let stderr = String::from_utf8_lossy(&out.stderr);
    let used = twv_kernels::isa::ALL
        .into_iter()
        .filter(|isa| *isa < missing && available(*isa))
        .max()
        .unwrap();
    assert!(
        stderr.contains(&format!(
            "this CPU has no {} build; the kernels use {}",
            missing.name(),
            used.name()
        )),
        "{stderr}"
    );
    assert_eq!(
        out.stdout, reference.stdout,
        "same results under --isa {flag}"
    );
    let quiet = twv(&[&["--quiet", "--isa", flag.as_str()], &args[..]].concat());
    assert!(
        quiet.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&quiet.stderr)
    );
    // A build every CPU has: nothing said.
    let baseline = twv(&[&["--isa", "baseline"], &args[..]].concat());
    assert!(!String::from_utf8_lossy(&baseline.stderr).contains("--isa"));
}

#[test]
fn interpreter_and_generated_code_agree_through_the_cli() {
    let ir = repo().join("generated/ir/segway7.json");
    let x = "0.3,1,2,0.5,-1,2,3";
    let a = twv(&[
        "eval", "--model", "segway7", "--x", x, "--u", "3,-2", "--jac",
    ]);
    let b = twv(&[
        "eval",
        "--ir",
        ir.to_str().unwrap(),
        "--x",
        x,
        "--u",
        "3,-2",
        "--jac",
    ]);
    assert!(a.status.success() && b.status.success());
    assert_eq!(a.stdout, b.stdout, "bit-identical JSON");
}

/// A `twv` built without the `jit` feature (`--no-default-features`) says so for `--runtime jit`
/// and names the way out.
#[cfg(not(feature = "jit"))]
#[test]
fn without_the_jit_feature_runtime_jit_names_the_feature() {
    let ir = repo().join("generated/ir/lorenz.json");
    let out = twv(&[
        "eval",
        "--ir",
        ir.to_str().unwrap(),
        "--x",
        "1,2,3",
        "--runtime",
        "jit",
    ]);
    fails_with(
        &out,
        &[
            "without the JIT",
            "default features",
            "--runtime interpreter",
        ],
    );
}

/// `--runtime`: an IR file's closed-loop spectrum (Dopri5, a saturated PID) compiled by the
/// JIT writes the same bytes as the interpreter's, and the spectrum of the shipped model.
#[cfg(feature = "jit")]
#[test]
fn the_jit_and_the_interpreter_write_the_same_files() {
    let dir = scratch("runtime");
    let ir = repo().join("generated/ir/vehicle7.json");
    let paper = repo().join("vehicles/paper.toml");
    let spectrum = |model: &[&str], out: &str| {
        let out_dir = dir.join(out);
        let mut args = vec!["lyap"];
        args.extend_from_slice(model);
        args.extend_from_slice(&[
            "--params",
            paper.to_str().unwrap(),
            "--x0",
            "0.05,0,0,0,0,0,0",
            "--gains",
            "3000,100,1500",
            "--f-max",
            "400",
            "--integrator",
            "dopri",
            "--iterations",
            "20",
            "--quiet",
            "--out",
            out_dir.to_str().unwrap(),
        ]);
        let run = twv(&args);
        assert!(
            run.status.success(),
            "{}",
            String::from_utf8_lossy(&run.stderr)
        );
        out_dir
    };
    let ir = ir.to_str().unwrap();
    let jit = spectrum(&["--ir", ir, "--runtime", "jit"], "jit");
    let interpreted = spectrum(&["--ir", ir, "--runtime", "interpreter"], "interpreter");
    let shipped = spectrum(&["--model", "vehicle7"], "shipped");
    for file in ["lyapunov.json", "running.csv"] {
        let read = |d: &std::path::Path| std::fs::read(d.join(file)).unwrap();
        assert_eq!(read(&jit), read(&interpreted), "{file}: JIT vs interpreter");
    }
    let exponents = |d: &std::path::Path| {
        let v: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.join("lyapunov.json")).unwrap()).unwrap();
        (v["exponents"].clone(), v["mean_trace"].clone())
    };
    // The spectrum and ⟨tr J⟩ (the Σλ check) to the last bit.
    assert_eq!(
        exponents(&jit),
        exponents(&shipped),
        "JIT vs generated code"
    );
    assert!(exponents(&jit).0.as_array().is_some_and(|e| !e.is_empty()));
    // An unknown runtime is a usage error naming the value.
    let bad = twv(&[
        "eval",
        "--ir",
        ir,
        "--x",
        "0,0,0,0,0,0,0",
        "--runtime",
        "llvm",
    ]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("llvm"));
}

#[test]
fn malformed_toml_names_the_file() {
    let dir = scratch("malformed");
    let p = paper_with(&dir, |t| t.replace("m1 = 115.0", "m1 = = 115"));
    fails_with(&eval_with_params(&p), &["vehicle.toml"]);
}

#[test]
fn unknown_and_missing_keys_are_named() {
    let dir = scratch("keys");
    let p = paper_with(&dir, |t| format!("{t}\nwheelbase = 1.0\n"));
    fails_with(&eval_with_params(&p), &["vehicle.toml", "wheelbase"]);
    let p = paper_with(&dir, |t| t.replace("m2 = 8.0", ""));
    fails_with(&eval_with_params(&p), &["vehicle.toml", "m2"]);
}

#[test]
fn non_positive_mass_is_rejected() {
    let dir = scratch("mass");
    for bad in ["m1 = -115.0", "m1 = 0.0"] {
        let p = paper_with(&dir, |t| t.replace("m1 = 115.0", bad));
        fails_with(&eval_with_params(&p), &["vehicle.toml", "m1"]);
    }
}

#[test]
fn inertia_violating_the_triangle_inequality_is_rejected() {
    let dir = scratch("triangle");
    let p = paper_with(&dir, |t| {
        t.replace("I2 = [0.81, 0.81, 0.03]", "I2 = [0.81, 0.3, 0.03]")
    });
    fails_with(&eval_with_params(&p), &["vehicle.toml", "I2"]);
}

#[test]
fn nan_parameter_and_nan_state_are_rejected() {
    let dir = scratch("nan");
    let p = paper_with(&dir, |t| t.replace("b = 0.55", "b = nan"));
    fails_with(&eval_with_params(&p), &["vehicle.toml", "b"]);
    let out = twv(&["eval", "--model", "vehicle8", "--x", "0,0,0,0,0,0,0,NaN"]);
    fails_with(&out, &["--x", "w_z"]);
}

#[test]
fn wrong_state_length_names_the_states() {
    let out = twv(&["eval", "--model", "vehicle7", "--x", X8]);
    fails_with(&out, &["--x: 8 values", "7", "phi"]);
}

fn write_ir(dir: &Path, name: &str, edit: impl Fn(&str) -> String) -> PathBuf {
    let text = std::fs::read_to_string(repo().join("generated/ir/lorenz.json")).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, twv_ir::rehash(&edit(&text))).unwrap();
    path
}

/// An edit of an IR text.
type Edit = Box<dyn Fn(&str) -> String>;

#[test]
fn malformed_ir_of_each_kind_is_a_clear_error() {
    let dir = scratch("ir");
    let cases: [(&str, Edit, &str); 4] = [
        (
            "version.json",
            Box::new(|t: &str| t.replace("twv-ir/1", "twv-ir/9")),
            "twv-ir/9",
        ),
        (
            "op.json",
            Box::new(|t: &str| t.replacen("\"sub\"", "\"frobnicate\"", 1)),
            "frobnicate",
        ),
        (
            "index.json",
            Box::new(|t: &str| t.replacen("[3, \"sub\", 1, 2]", "[3, \"sub\", 1, 99]", 1)),
            "99",
        ),
        (
            "truncated.json",
            Box::new(|t: &str| t[..t.len() / 2].to_string()),
            "truncated.json",
        ),
    ];
    for (name, edit, needle) in cases {
        let path = write_ir(&dir, name, edit);
        let out = twv(&["eval", "--ir", path.to_str().unwrap(), "--x", "1,2,3"]);
        fails_with(&out, &[name, needle]);
    }
    // A file whose content does not match its hash was edited by hand.
    let text = std::fs::read_to_string(repo().join("generated/ir/lorenz.json")).unwrap();
    let tampered = dir.join("tampered.json");
    std::fs::write(&tampered, text.replacen("10.0", "11.0", 1)).unwrap();
    let out = twv(&["eval", "--ir", tampered.to_str().unwrap(), "--x", "1,2,3"]);
    fails_with(&out, &["tampered.json", "hash"]);
}

#[test]
fn blown_up_integration_names_the_time_and_state() {
    let dir = scratch("blowup");
    // β < 0 makes z grow like e^{100 t}: it overflows within the run.
    let params = dir.join("lorenz.toml");
    std::fs::write(&params, "sigma = 10.0\nrho = 28.0\nbeta = -100.0\n").unwrap();
    let out_dir = dir.join("out");
    let out = twv(&[
        "lyap",
        "--model",
        "lorenz",
        "--params",
        params.to_str().unwrap(),
        "--x0",
        "1,1,1",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    fails_with(&out, &["t = ", "x = "]);
    assert!(!out_dir.exists(), "no partial output");
}

#[test]
fn unwritable_output_directory_is_an_error_without_output() {
    let dir = scratch("unwritable");
    let file = dir.join("a-file");
    std::fs::write(&file, "").unwrap();
    let target = file.join("sub");
    let out = twv(&[
        "lyap",
        "--model",
        "lorenz",
        "--x0",
        "1,1,1",
        "--iterations",
        "10",
        "--out",
        target.to_str().unwrap(),
    ]);
    fails_with(&out, &["a-file"]);
    assert_eq!(
        std::fs::read_dir(&dir).unwrap().count(),
        1,
        "nothing written besides the file"
    );
}

#[test]
fn lyap_writes_json_csv_and_figure() {
    let base = scratch("lyap");
    let dir = base.join("out");
    let out = twv(&[
        "lyap",
        "--model",
        "lorenz",
        "--x0",
        "1,1,20",
        "--iterations",
        "50",
        "--out",
        dir.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    for key in [
        "exponents",
        "stderr",
        "sum",
        "mean_trace",
        "kaplan_yorke",
        "classification",
        "t_total",
    ] {
        assert!(v.get(key).is_some(), "{key}");
    }
    let csv = std::fs::read_to_string(dir.join("running.csv")).unwrap();
    assert_eq!(csv.lines().count(), 51, "header + one row per interval");
    assert!(std::fs::read_to_string(dir.join("running.svg"))
        .unwrap()
        .starts_with("<svg"));
}

#[test]
fn audit_passes_and_fails_cleanly() {
    let out = twv(&["audit", "--model", "vehicle7", "--samples", "20"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(String::from_utf8_lossy(&out.stdout).contains("PASSED"));
    let out = twv(&["audit", "--model", "lorenz"]);
    fails_with(&out, &["lorenz"]);
}

#[test]
fn every_subcommand_has_help() {
    for cmd in ["eval", "codegen", "audit", "lyap"] {
        let out = twv(&[cmd, "--help"]);
        assert!(out.status.success(), "{cmd}");
        assert!(
            String::from_utf8_lossy(&out.stdout).contains("--model"),
            "{cmd}"
        );
    }
}

/// `twv audit --hand`: the example hand files pass; a planted error exits 3 naming the entry and
/// printing the planted term; every kind of bad hand file is one line naming file, line and name.
#[test]
fn audit_of_a_users_hand_file() {
    let hand = |m: &str| {
        format!(
            "{}/../../examples/hand/{m}.toml",
            env!("CARGO_MANIFEST_DIR")
        )
    };
    for m in ["vehicle8", "vehicle7", "segway7", "lorenz"] {
        let out = twv(&["audit", "--hand", &hand(m)]);
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert!(out.status.success(), "{m}: {stdout}");
        assert!(stdout.contains("PASSED: every entry agrees"), "{stdout}");
    }
    let ir = format!(
        "{}/../../generated/ir/vehicle7.json",
        env!("CARGO_MANIFEST_DIR")
    );
    assert!(twv(&["audit", "--ir", &ir, "--hand", &hand("vehicle7")])
        .status
        .success());

    let dir = scratch("hand");
    let text = std::fs::read_to_string(hand("vehicle7")).unwrap();
    let write = |name: &str, from: &str, to: &str| {
        assert_eq!(text.matches(from).count(), 1, "`{from}` occurs once");
        let path = dir.join(name);
        std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
        path.display().to_string()
    };
    let planted = write("planted.toml", "(w_y^2 + w_z^2)", "w_y^2");
    let out = twv(&["audit", "--hand", &planted]);
    negative_with(
        &out,
        &["planted.toml disagrees with the derivation of vehicle7"],
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("first: Cp[v_x] (line 18)"), "{stdout}");
    assert!(stdout.contains("Cp[v_x] = m2*b*sin(phi)*w_z^2"), "{stdout}");

    let cases = [
        (
            "state.toml",
            "m2*b*cos(phi)\",   \"m1",
            "m2*b*cos(psi)\",   \"m1",
            vec![":13:", "M[v_x,w_y]", "column 18", "`psi`"],
        ),
        (
            "param.toml",
            "I2_xx - I2_zz + m2*b^2\"\n",
            "I2_xx - I9_zz + m2*b^2\"\n",
            vec![":9:", "let K", "`I9_zz`"],
        ),
        (
            "missing.toml",
            "theta = \"w_z\"\n",
            "",
            vec![":31:", "[qdot] has no entry for `theta`"],
        ),
        (
            "shape.toml",
            "\"m2*b*cos(phi)\", \"0\"]",
            "\"m2*b*cos(phi)\"]",
            vec![":12:", "M[w_y] has 2 entries", "3 speeds"],
        ),
        (
            "syntax.toml",
            "\"-m2*g*b*sin(phi)\"",
            "\"-m2*g*b*sin(phi\"",
            vec![":22:", "F[w_y]", "expected `)`"],
        ),
        (
            "unknown.toml",
            "[Q]\n",
            "[Q]\nv_y = 0\n",
            vec![":27:", "[Q]: `v_y` is not one of w_y, v_x, w_z"],
        ),
        ("toml.toml", "[F]\n", "[F\n", vec![":21:", "unclosed table"]),
        (
            "table.toml",
            "[qdot]\n",
            "[qdott]\n",
            vec![":31:", "unknown field `qdott`"],
        ),
        (
            "function.toml",
            "v_x = \"F1\"",
            "v_x = \"F1 + sinh(phi)\"",
            vec![":28:", "unknown function `sinh`"],
        ),
        (
            "model.toml",
            "model = \"vehicle7\"",
            "model = \"vehicle8\"",
            vec![":6:", "the audited model is `vehicle7`"],
        ),
    ];
    for (name, from, to, needles) in cases {
        let path = write(name, from, to);
        // model.toml names vehicle8; the others are read against vehicle7 by their own `model`.
        let args: Vec<&str> = match name {
            "model.toml" => vec!["audit", "--hand", &path, "--model", "vehicle7"],
            _ => vec!["audit", "--hand", &path],
        };
        let mut all = vec![name];
        all.extend(needles);
        fails_with(&twv(&args), &all);
    }
    fails_with(
        &twv(&["audit", "--hand", &hand("lorenz"), "--model", "vehicle8"]),
        &["lorenz.toml:4:", "the audited model is `vehicle8`"],
    );
    fails_with(
        &twv(&[
            "audit",
            "--hand",
            &hand("vehicle7"),
            "--param-spread",
            "0.5",
        ]),
        &["--param-spread", "0.5 must be in [1, 100]"],
    );
    let huge = dir.join("huge.toml");
    std::fs::write(&huge, vec![b'#'; 2 << 20]).unwrap();
    fails_with(
        &twv(&[
            "audit",
            "--hand",
            &huge.display().to_string(),
            "--model",
            "vehicle7",
        ]),
        &["huge.toml", "more than a hand file's"],
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `twv steady --model whipple --speed LO:HI:STEP --out DIR`: the bicycle's eigenvalues against
/// speed as CSV, figure and JSON; exit 3 when the grid holds no self-stable speed.
#[test]
fn linear_speed_sweep_of_the_bicycle() {
    let dir = scratch("speed");
    let out = twv(&[
        "steady",
        "--model",
        "whipple",
        "--speed",
        "0:10:0.01",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    assert!(
        stdout.contains("self-stable from 4.29238253634"),
        "{stdout}"
    );
    assert!(stdout.contains("to 6.02426201538"), "{stdout}");
    let csv = std::fs::read_to_string(dir.join("eigenvalues.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 1001);
    assert!(csv.starts_with("speed,re1,im1,re2,im2,re3,im3,re4,im4\n"));
    for name in ["eigenvalues.svg", "eigenvalues.png", "steady.json"] {
        assert!(dir.join(name).exists(), "{name}");
    }
    negative_with(
        &twv(&["steady", "--model", "whipple", "--speed", "0:3:0.1"]),
        &["whipple is nowhere self-stable on the grid"],
    );
    fails_with(
        &twv(&["steady", "--model", "whipple", "--speed", "0:10"]),
        &["--speed: wants three numbers LO:HI:STEP"],
    );
    fails_with(
        &twv(&["steady", "--model", "whipple", "--speed", "5:1:0.1"]),
        &["--speed", "needs finite LO < HI"],
    );
    fails_with(
        &twv(&["steady", "--model", "vehicle8", "--speed", "0:1:0.5"]),
        &["vehicle8", "no steady motion"],
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `twv ride`: the uncontrolled bicycle from its straight running at a speed with a push in
/// lean rate — recovers inside the self-stable range (files written, JSON equal to the
/// library's job), falls below it; bad pushes named; a model with no pitch points `twv sim`
/// users to it.
#[test]
fn ride_of_the_uncontrolled_bicycle() {
    let dir = scratch("ride");
    let out = twv(&[
        "ride",
        "--model",
        "whipple",
        "--speed",
        "5",
        "--perturb",
        "w_phi=0.05",
        "--t-end",
        "6",
        "--out",
        dir.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["verdict"], "recovered");
    assert!(v["tail_peak"].as_f64().unwrap() <= 0.1 * v["peak"].as_f64().unwrap());
    for f in ["ride.csv", "ride.json", "phi.svg", "phi.png", "delta.svg"] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(dir.join("ride.csv")).unwrap();
    assert!(csv.starts_with("t,psi,x,y,phi,theta,delta,w_phi,w_R,w_delta\n"));
    assert_eq!(csv.lines().count(), 602);

    let slow = twv(&[
        "ride",
        "--model",
        "whipple",
        "--speed",
        "3",
        "--perturb",
        "w_phi=0.05",
        "--t-end",
        "6",
        "--fall-angle",
        "0.5",
    ]);
    assert!(slow.status.success());
    let text = String::from_utf8_lossy(&slow.stdout);
    assert!(text.contains("FELL: |phi| passed 0.5"), "{text}");

    fails_with(
        &twv(&[
            "ride",
            "--model",
            "whipple",
            "--speed",
            "5",
            "--perturb",
            "lean=1",
        ]),
        &["perturb", "`lean` is not a state of whipple"],
    );
    fails_with(
        &twv(&["ride", "--model", "whipple", "--perturb", "w_phi"]),
        &["--perturb: `w_phi` is not NAME=VALUE"],
    );
    fails_with(
        &twv(&["sim", "--model", "whipple"]),
        &["no pitch to control", "twv ride"],
    );
}

/// `twv sweep --param NAME=A:B:N`: a map over model parameters at the study's PD (no --kp or
/// --kd needed), merged with the parameters as columns and axes; bad axes named.
#[test]
fn sweep_over_model_parameters() {
    let dir = scratch("param-sweep");
    let out = dir.join("map");
    let run = twv(&[
        "sweep",
        "--param",
        "m2=4:20:3",
        "--param",
        "b=0.2:1.0:3",
        "--metric",
        "spectral-abscissa",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let merged = twv(&["merge", out.to_str().unwrap()]);
    assert!(
        merged.status.success(),
        "{}",
        String::from_utf8_lossy(&merged.stderr)
    );
    let csv = std::fs::read_to_string(out.join("map.csv")).unwrap();
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("index,kp,ki,kd,m2,b,value,status"));
    // Row 4: m2 = 12 (the second m2), b = 0.2 + 0.8/2 (the second b, as computed), the PD.
    assert!(lines
        .nth(4)
        .unwrap()
        .starts_with("4,3860,0,1980,12,0.6000000000000001,"));
    let svg = std::fs::read_to_string(out.join("map.svg")).unwrap();
    assert!(
        svg.contains("\nm2\n") && svg.contains("\nb\n"),
        "axes named after the parameters"
    );

    fails_with(
        &twv(&[
            "sweep",
            "--param",
            "mass=1:2:2",
            "--metric",
            "spectral-abscissa",
            "--out",
            dir.join("bad").to_str().unwrap(),
        ]),
        &["`mass` is not a parameter of vehicle8"],
    );
    // Without axes the map is the library's default grid, 100 × 100 (Kp 0…8000, Kd 0…4000).
    let settings = twv(&["sweep", "--print-settings"]);
    let grid: serde_json::Value = serde_json::from_slice(&settings.stdout).unwrap();
    assert_eq!(
        grid["grid"]["kp"],
        serde_json::json!({"lo": 0.0, "hi": 8000.0, "n": 100})
    );
    assert_eq!(
        grid["grid"]["kd"],
        serde_json::json!({"lo": 0.0, "hi": 4000.0, "n": 100})
    );
    fails_with(
        &twv(&[
            "sweep",
            "--kp",
            "0:8000:3",
            "--kd",
            "0:4000:3",
            "--metric",
            "spectral-abscissa",
            "--full-horizon",
            "--out",
            dir.join("bad").to_str().unwrap(),
        ]),
        &["--full-horizon: applies to metric max-lyapunov only"],
    );
    assert!(
        !dir.join("bad").exists(),
        "nothing written for a refused sweep"
    );
}

/// `twv linear --out` writes the pitch loop's frequency response and its Bode and Nyquist
/// figures; the JSON's margins are the ones printed without `--out`.
#[test]
fn linear_writes_bode_and_nyquist_figures() {
    let dir = scratch("linear-figures");
    let out = twv(&[
        "linear",
        "--frequency-points",
        "500",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("linear.json")).unwrap()).unwrap();
    let response = &report["pitch"]["response"];
    assert_eq!(response["w"].as_array().unwrap().len(), 500);
    let crossover = response["gain_crossovers"][0].as_f64().unwrap();
    let pm = &report["pitch"]["margins"]["phase_margin"];
    assert_eq!(pm["frequency"].as_f64().unwrap(), crossover);
    for name in ["bode", "nyquist"] {
        let svg = std::fs::read_to_string(dir.join(format!("{name}.svg"))).unwrap();
        roxmltree::Document::parse(&svg).unwrap();
        assert!(svg.contains(&format!("{crossover:.3}")) || name == "nyquist");
        let png = std::fs::read(dir.join(format!("{name}.png"))).unwrap();
        assert!(png.starts_with(b"\x89PNG"));
    }
    // Without --out: no response in the JSON (the bytes of before).
    let plain = twv(&["linear", "--json"]);
    let plain: serde_json::Value = serde_json::from_slice(&plain.stdout).unwrap();
    assert!(plain["pitch"].get("response").is_none());
    assert_eq!(plain["pitch"]["margins"], report["pitch"]["margins"]);
}

/// `twv <job> --print-settings` with no flags is the library's default settings for every job
/// of the registry: the command line adds no default of its own.
#[test]
fn every_job_runs_the_librarys_default_settings() {
    for job in twv_analysis::jobs::registry() {
        let mut args = vec![job.name().to_string(), "--print-settings".to_string()];
        let mut expected = job.default_settings();
        for o in job.options().iter().filter(|o| o.required) {
            args.push(format!("--{}", o.name.replace('_', "-")));
            args.push("0.1,0,0".into());
            expected[o.name] = serde_json::json!([0.1, 0.0, 0.0]);
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = twv(&args);
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let printed: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
        if job.name() == "lyapunov" {
            // The one thing the command line decides: running estimates only when written.
            expected["lyapunov"]["record_running"] = false.into();
        }
        assert_eq!(printed, expected, "twv {}", job.name());
        // And `--help` names every option with the library's default.
        let help = twv(&[job.name(), "--help"]);
        let help = String::from_utf8_lossy(&help.stdout);
        for o in job.options() {
            let flag = format!("--{}", o.name.replace('_', "-"));
            assert!(
                help.contains(&flag),
                "twv {} --help: {flag} missing",
                job.name()
            );
        }
    }
}

/// No default is written in the command line's source: every one is the library's (a test, so
/// that a default added to a flag later fails here).
#[test]
fn the_command_line_restates_no_default() {
    let src = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = vec![];
    let mut dirs = vec![src];
    while let Some(dir) = dirs.pop() {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                dirs.push(path);
            } else if path.extension().is_some_and(|e| e == "rs") {
                files.push(path);
            }
        }
    }
    assert!(files.len() >= 8, "{files:?}");
    let numeric_default = |line: &str| {
        ["unwrap_or(", "default_value_t", "default_value ="]
            .iter()
            .any(|pattern| {
                line.find(pattern).is_some_and(|i| {
                    let rest = line[i + pattern.len()..].trim_start_matches([' ', '=', '"']);
                    pattern.starts_with("default") || rest.starts_with(|c: char| c.is_ascii_digit())
                })
            })
    };
    for path in files {
        let text = std::fs::read_to_string(&path).unwrap();
        for (n, line) in text.lines().enumerate() {
            assert!(
                !numeric_default(line) || line.trim_start().starts_with("//"),
                "{}:{}: a default written in the CLI: {line}",
                path.display(),
                n + 1
            );
        }
    }
}
