//! Hostile input, by running the real binary: every case ends in bounded time with one clear
//! line and a non-zero exit — never a hang, an abort, a panic, a NaN printed as a result or a
//! half-written folder — and an interrupted sweep resumes where it stopped.

mod common;

use std::io::Read;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::{fails_with, twv};

const X8: &str = "0.1,0,0,0,0,0,0,0";

/// Runs the binary, killing it after `limit`: a hang fails the test instead of the CI run.
fn bounded(args: &[&str], limit: Duration) -> Output {
    let child = Command::new(env!("CARGO_BIN_EXE_twv"))
        .args(args)
        .env_remove("RUST_BACKTRACE")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    wait_within(child, limit, &format!("twv {args:?}"))
}

/// Waits for `child`, killing it after `limit`: a hang fails the test (naming `what`).
fn wait_within(mut child: std::process::Child, limit: Duration, what: &str) -> Output {
    let start = Instant::now();
    loop {
        if child.try_wait().unwrap().is_some() {
            return child.wait_with_output().unwrap();
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            panic!("{what} still running after {limit:?}");
        }
        std::thread::sleep(Duration::from_millis(10));
    }
}

/// Waits until `child` has used `cpu` of processor time (user + system, from /proc), so that a
/// signal sent next lands in the middle of its work however fast the build or busy the machine
/// is (a 40 × 40 map is about a second of work in the release build). At most 60 s.
fn busy_for(child: &std::process::Child, cpu: Duration) {
    let stat = format!("/proc/{}/stat", child.id());
    let tick = 0.01; // USER_HZ: 100 on Linux
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(60) {
        let used = std::fs::read_to_string(&stat).ok().and_then(|text| {
            // Fields after the command's closing parenthesis: state is the first, utime the
            // 12th and stime the 13th.
            let rest = &text[text.rfind(')')? + 2..];
            let f: Vec<&str> = rest.split_whitespace().collect();
            Some((f.get(11)?.parse::<f64>().ok()? + f.get(12)?.parse::<f64>().ok()?) * tick)
        });
        match used {
            Some(seconds) if seconds >= cpu.as_secs_f64() => return,
            None => return, // it has ended: the caller's checks say how
            _ => std::thread::sleep(Duration::from_millis(5)),
        }
    }
}

fn scratch(name: &str) -> common::Scratch {
    common::scratch("hostile", name)
}

fn paper_with(dir: &Path, from: &str, to: &str) -> PathBuf {
    let repo = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(repo.join("vehicles/paper.toml")).unwrap();
    assert!(text.contains(from));
    let path = dir.join("vehicle.toml");
    std::fs::write(&path, text.replace(from, to)).unwrap();
    path
}

const SECONDS: Duration = Duration::from_secs(30);

#[test]
fn absurd_steps_are_refused_up_front() {
    let out = bounded(&["lyap", "--x0", X8, "--h", "1e-300"], SECONDS);
    fails_with(&out, &["RK4 steps", "1e9"]);
    let out = bounded(&["sim", "--h", "1e-300"], SECONDS);
    fails_with(&out, &["RK4 steps", "1e9"]);
    // 10⁹ intervals once asked for 64 GB and aborted (exit 134).
    let out = bounded(&["lyap", "--x0", X8, "--iterations", "1000000000"], SECONDS);
    fails_with(&out, &["RK4 steps"]);
    // A sweep of 10¹² points (56 TB of results) is refused before anything is made.
    let base = scratch("huge");
    let dir = base.join("map");
    let out = bounded(
        &[
            "sweep",
            "--kp",
            "0:8000:1000000",
            "--kd",
            "0:4000:1000000",
            "--metric",
            "max-lyapunov",
            "--out",
            dir.to_str().unwrap(),
        ],
        SECONDS,
    );
    fails_with(&out, &["settings field `grid`", "1000000000000 points"]);
    assert!(!dir.exists(), "no folder left behind");
}

#[test]
fn absurd_parameters_are_refused_naming_the_field() {
    let dir = scratch("params");
    let p = paper_with(&dir, "m1 = 115.0", "m1 = 1e308");
    for cmd in [
        vec!["eval", "--x", X8, "--params"],
        vec!["audit", "--model", "vehicle7", "--params"],
        vec!["report", "--quick", "--out", "unused", "--params"],
    ] {
        let mut args = cmd.clone();
        args.push(p.to_str().unwrap());
        let out = bounded(&args, SECONDS);
        fails_with(&out, &["vehicle.toml", "m1", "plausible mass"]);
    }
    assert!(!Path::new("unused").exists());
}

#[test]
fn non_finite_results_are_errors() {
    let out = twv(&["eval", "--model", "lorenz", "--x", "1e308,1e308,1e308"]);
    let stderr = fails_with(&out, &["f is not finite", "1e308"]);
    assert!(
        out.stdout.is_empty(),
        "nothing printed as a result: {stderr}"
    );
}

#[test]
fn a_full_stdout_is_an_error_not_a_panic() {
    let full = std::fs::File::options()
        .write(true)
        .open("/dev/full")
        .unwrap();
    for args in [
        vec!["eval", "--x", X8],
        vec!["codegen", "--model", "lorenz"],
        vec![
            "lyap",
            "--model",
            "lorenz",
            "--x0",
            "1,1,20",
            "--iterations",
            "10",
        ],
        vec!["audit", "--model", "vehicle7", "--samples", "5"],
        vec!["linear"],
        vec!["tune"],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_twv"))
            .args(&args)
            .stdout(full.try_clone().unwrap())
            .stderr(Stdio::piped())
            .output()
            .unwrap();
        fails_with(&out, &["cannot write to stdout"]);
    }
}

#[test]
fn a_closed_pipe_ends_quietly() {
    let mut child = Command::new(env!("CARGO_BIN_EXE_twv"))
        .args(["codegen", "--model", "vehicle8"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Read one line, then hang up, as `| head -1` does.
    let mut first = [0u8; 64];
    child
        .stdout
        .as_mut()
        .unwrap()
        .read_exact(&mut first)
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.is_empty(), "quiet: {stderr}");
    #[cfg(unix)]
    {
        use std::os::unix::process::ExitStatusExt;
        assert_eq!(
            out.status.signal(),
            Some(13),
            "ended by SIGPIPE like any Unix tool"
        );
    }
}

#[test]
fn negative_numbers_parse_and_out_of_range_ones_are_named() {
    fails_with(&twv(&["lyap", "--x0", X8, "--h", "-1"]), &["h = -1"]);
    fails_with(
        &twv(&["lyap", "--x0", X8, "--transient", "-5"]),
        &["transient = -5"],
    );
    fails_with(&twv(&["sim", "--t-end", "-2"]), &["t_end", "-2"]);
    // A negative gain range is a valid map (every point unstable), not a parse error.
    let base = scratch("negative");
    let dir = base.join("map");
    let out = twv(&[
        "sweep",
        "--kp",
        "-100:100:3",
        "--kd",
        "0:1:2",
        "--metric",
        "spectral-abscissa",
        "--out",
        dir.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // A speed range that starts below zero is a range, not an option (issue 38): the bicycle
    // runs backwards there, and is nowhere self-stable (exit 3, a verdict, not a parse error).
    let out = twv(&[
        "steady",
        "--model",
        "whipple",
        "--speed",
        "-10:0:0.5",
        "--quiet",
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(3), "{stdout}");
    assert!(stdout.contains("21 speeds -10…0 m/s"), "{stdout}");
}

#[test]
fn a_failed_run_leaves_no_folder() {
    let base = scratch("failed");
    let dir = base.join("sim");
    fails_with(
        &twv(&["sim", "--h", "0.5", "--out", dir.to_str().unwrap()]),
        &["sample interval"],
    );
    assert!(!dir.exists());
}

#[test]
fn a_folder_holds_one_sweep() {
    let base = scratch("two-sweeps");
    let dir = base.join("map");
    let d = dir.to_str().unwrap();
    let first = twv(&[
        "sweep",
        "--kp",
        "0:2400:5",
        "--kd",
        "100:1000:2",
        "--metric",
        "spectral-abscissa",
        "--out",
        d,
        "--quiet",
    ]);
    assert!(first.status.success());
    let second = twv(&[
        "sweep",
        "--kp",
        "0:2400:7",
        "--kd",
        "100:1000:2",
        "--metric",
        "spectral-abscissa",
        "--out",
        d,
        "--quiet",
    ]);
    fails_with(&second, &["holds another sweep"]);
}

/// Ctrl-C in the middle of a shard: exit 130, the finished points in a checkpoint, and the
/// same command resumes and writes what an uninterrupted run writes.
#[test]
fn an_interrupted_sweep_resumes() {
    let base = scratch("sigint");
    let grid = [
        "--kp",
        "800:8000:40",
        "--kd",
        "200:4000:40",
        "--metric",
        "max-lyapunov",
        "--quiet",
    ];
    let whole = base.join("whole");
    let mut args = vec!["sweep", "--out", whole.to_str().unwrap()];
    args.extend_from_slice(&grid);
    assert!(bounded(&args, Duration::from_secs(120)).status.success());

    let dir = base.join("interrupted");
    let mut args = vec!["sweep", "--out", dir.to_str().unwrap()];
    args.extend_from_slice(&grid);
    let child = Command::new(env!("CARGO_BIN_EXE_twv"))
        .args(&args)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Interrupted once it has computed for a while, whatever the build's speed.
    busy_for(&child, Duration::from_millis(150));
    let pid = child.id().to_string();
    assert!(Command::new("kill")
        .args(["-INT", &pid])
        .status()
        .unwrap()
        .success());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(
        stderr.contains("run the same command again to resume"),
        "{stderr}"
    );
    assert!(dir.join("checkpoint-0-of-1.json").exists());
    assert!(!dir.join("shard-0-of-1.json").exists());

    let resumed = bounded(&args, Duration::from_secs(120));
    assert!(resumed.status.success());
    assert_eq!(
        std::fs::read(dir.join("shard-0-of-1.json")).unwrap(),
        std::fs::read(whole.join("shard-0-of-1.json")).unwrap()
    );
    assert!(!dir.join("checkpoint-0-of-1.json").exists());
}

#[test]
fn every_command_takes_quiet_and_prints_no_progress_off_a_terminal() {
    let out = twv(&[
        "lyap",
        "--model",
        "lorenz",
        "--x0",
        "1,1,20",
        "--iterations",
        "40000",
        "--quiet",
    ]);
    assert!(out.status.success());
    assert!(out.stderr.is_empty());
    // Not a terminal: no bar even for a run of several seconds.
    let out = twv(&[
        "lyap",
        "--model",
        "lorenz",
        "--x0",
        "1,1,20",
        "--iterations",
        "40000",
    ]);
    assert!(out.status.success());
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for cmd in [
        "eval", "codegen", "audit", "lyap", "sim", "disturb", "phase", "linear", "tune", "report",
        "sweep", "merge",
    ] {
        let out = twv(&[cmd, "--quiet", "--help"]);
        assert!(out.status.success(), "{cmd} --quiet");
    }
}

/// One Ctrl-C stops any long command within a second, exit 130, nothing half-written (issue 38:
/// a 10⁵-speed `steady`, a `tune` of thousands of subproblems and the `report` used to run on).
#[test]
fn one_ctrl_c_stops_every_long_command_within_a_second() {
    let base = scratch("ctrl-c");
    let report = base.join("report");
    let heavy_tune = base.join("tune.json");
    std::fs::write(
        &heavy_tune,
        r#"{"options": {"points_per_decade": 2000, "max_iterations": 5000}, "spec": "dpm>=89.9,dgm>=60dB"}"#,
    )
    .unwrap();
    let cases: [&[&str]; 4] = [
        &["steady", "--model", "whipple", "--speed", "0:9.9:0.0001"],
        &["tune", "--settings", heavy_tune.to_str().unwrap()],
        &["report", "--out", report.to_str().unwrap()],
        &["sim", "--t-end", "1000", "--h", "1e-5"],
    ];
    for args in cases {
        let mut child = Command::new(env!("CARGO_BIN_EXE_twv"))
            .args(args)
            .arg("--quiet")
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(1500));
        assert!(
            child.try_wait().unwrap().is_none(),
            "{args:?} ended too soon to be interrupted"
        );
        let sent = Instant::now();
        let pid = child.id().to_string();
        assert!(Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .unwrap()
            .success());
        let out = wait_within(
            child,
            Duration::from_secs(10),
            &format!("{args:?} after Ctrl-C"),
        );
        let took = sent.elapsed();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(130), "{args:?}: {stderr}");
        assert!(stderr.contains("interrupted"), "{args:?}: {stderr}");
        assert!(
            took < Duration::from_secs(1),
            "{args:?} took {took:?} after Ctrl-C"
        );
    }
    assert!(!report.exists(), "an interrupted report writes nothing");
}

/// Messages name options that exist (the canonical flag, not an alias or a settings field
/// dressed as a flag) and print numbers a person can read (issue 38).
#[test]
fn messages_name_real_options_and_readable_numbers() {
    let out = bounded(&["lyap", "--x0", X8, "--repeat", "0"], SECONDS);
    let stderr = fails_with(&out, &["--timing"]);
    assert!(!stderr.contains("--repeat"), "{stderr}");
    // --phi0 is an alias of sim's --tilt.
    let out = bounded(&["sim", "--phi0", "1e300"], SECONDS);
    let stderr = fails_with(&out, &["--tilt", "1e300"]);
    assert!(stderr.len() < 300, "{stderr}");
    assert!(!stderr.contains("000000000000000000000000"), "{stderr}");
    let out = bounded(&["tune", "--tilt", "1e300"], SECONDS);
    let stderr = fails_with(&out, &["--tilt", "1e300"]);
    assert!(!stderr.contains("--phi0"), "{stderr}");
    // A field the settings file sets and no flag does is named as the field it is.
    let dir = scratch("messages");
    let file = dir.join("tune.json");
    std::fs::write(&file, r#"{"options": {"points_per_decade": 1}}"#).unwrap();
    let out = bounded(&["tune", "--settings", file.to_str().unwrap()], SECONDS);
    fails_with(
        &out,
        &["settings field `points_per_decade`", "between 2 and 10000"],
    );
}

/// A second Ctrl-C right after the first, while the sweep finishes its chunk and writes its
/// checkpoint: the checkpoint is written whole and renamed into place before twv exits, and no
/// temporary file is left (issue 38: all progress was lost).

#[test]
fn a_second_ctrl_c_during_the_checkpoint_keeps_it() {
    let dir = scratch("second-sigint");
    let out = dir.join("map");
    let child = Command::new(env!("CARGO_BIN_EXE_twv"))
        .args([
            "sweep",
            "--out",
            out.to_str().unwrap(),
            "--kp",
            "800:8000:40",
            "--kd",
            "200:4000:40",
            "--metric",
            "max-lyapunov",
            "--quiet",
        ])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    busy_for(&child, Duration::from_millis(300));
    let pid = child.id().to_string();
    for pause in [50, 0] {
        assert!(Command::new("kill")
            .args(["-INT", &pid])
            .status()
            .unwrap()
            .success());
        std::thread::sleep(Duration::from_millis(pause));
    }
    let done = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&done.stderr);
    assert_eq!(done.status.code(), Some(130), "{stderr}");
    let checkpoint = out.join("checkpoint-0-of-1.json");
    let text = std::fs::read_to_string(&checkpoint).expect("the checkpoint is there");
    let json: serde_json::Value = serde_json::from_str(&text).expect("whole JSON");
    assert!(!json["points"].as_array().unwrap().is_empty());
    let leftovers: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}
