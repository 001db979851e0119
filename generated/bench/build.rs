//! Writes CasADi's own C code for vehicle8 into OUT_DIR (the Python modeling step, `export-c`)
//! and compiles it at -O3: the peers the generated Rust kernels are measured against — the C of
//! twv's own derivation, and of the same physics written by hand in CasADi (`export-c --hand`).
//! With the feature `bicycle-peer`, also the Whipple bicycle's C, the peer of its JIT.
//!
//! Every `cargo clippy --all-targets` / `cargo test --workspace` builds this script, so it stays
//! small: one Python call (~0.5 s) and one C file; it reruns only when the model's inputs change.

use std::path::{Path, PathBuf};
use std::process::Command;

const MODEL: &str = "vehicle8";

fn main() {
    let manifest = PathBuf::from(env("CARGO_MANIFEST_DIR"));
    let root = manifest
        .parent()
        .and_then(Path::parent)
        .unwrap_or_else(|| fail("generated/bench is not two levels below the workspace root"));
    let out = PathBuf::from(env("OUT_DIR"));

    // What the exported C depends on: the model code, its pinned CasADi version and the parameter
    // file its defaults come from (the IR is listed too: it is what the Rust side is built from,
    // so a changed IR without a rebuilt C would fail the benchmark's correctness gate).
    println!("cargo:rerun-if-changed=build.rs");
    for path in [
        "generated/ir/vehicle8.json",
        "modeling/requirements.txt",
        "vehicles/paper.toml",
    ] {
        println!("cargo:rerun-if-changed={}", root.join(path).display());
    }
    // Each Python source on its own rather than the directory: the directory also holds
    // __pycache__/, which any Python run may rewrite and would make this script rerun.
    watch_python(&root.join("modeling/twv_modeling"));

    let python = root.join(".venv/bin/python");
    if !python.is_file() {
        fail(&format!(
            "{} is missing: the benchmark needs CasADi's C from the Python modeling step. \
             Run `bash .ci/setup-python.sh` at the workspace root once (it creates .venv/), \
             then rebuild.",
            python.display()
        ));
    }
    export_c(&python, root, &out, MODEL, &["--hand"]);
    let c_file = out.join(format!("{MODEL}_casadi.c"));
    // The second peer: the same physics written by hand in CasADi (`hand_peer.py`).
    let hand_file = out.join(format!("{MODEL}_hand_casadi.c"));
    compile(&[c_file, hand_file], "vehicle8_casadi");

    // The bicycle's peer (feature `bicycle-peer`, which `.ci/speed-report.sh` turns on): its
    // ∂f/∂x has ~18 000 operations and gcc -O3 takes ~20 s of one core over it, which every
    // build of the workspace's tests would pay for a table only the benchmark prints. J·W with
    // 9 tangent vectors, the bicycle's state count; runtime parameters only.
    if std::env::var_os("CARGO_FEATURE_BICYCLE_PEER").is_some() {
        println!(
            "cargo:rerun-if-changed={}",
            root.join("generated/ir/whipple.json").display()
        );
        export_c(
            &python,
            root,
            &out,
            "whipple",
            &["--tangents", "9", "--runtime-only"],
        );
        compile(&[out.join("whipple_casadi.c")], "whipple_casadi");
    }
}

/// Runs `python -m twv_modeling export-c --model MODEL EXTRA... --out-dir OUT`.
fn export_c(python: &Path, root: &Path, out: &Path, model: &str, extra: &[&str]) {
    let output = Command::new(python)
        .args(["-m", "twv_modeling", "export-c", "--model", model])
        .args(extra)
        .arg("--out-dir")
        .arg(out)
        .current_dir(root)
        // Keep the watched source tree free of fresh .pyc files.
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .unwrap_or_else(|e| fail(&format!("cannot run {}: {e}", python.display())));
    if !output.status.success() {
        fail(&format!(
            "`{} -m twv_modeling export-c --model {model}` failed ({}):\n{}{}\
             (if a module is missing, rerun `bash .ci/setup-python.sh`)",
            python.display(),
            output.status,
            String::from_utf8_lossy(&output.stdout),
            String::from_utf8_lossy(&output.stderr),
        ));
    }
}

/// Compiles `files` into the static library `name`.
fn compile(files: &[PathBuf], name: &str) {
    // -O3 and no -ffast-math: the C must round exactly as written so the benchmark can check it
    // bit for bit against the Rust kernels. No -march=native either: the Rust side is built for
    // the default target too, so both use the same instruction set.
    cc::Build::new()
        .files(files)
        .opt_level(3)
        .flag("-O3")
        .flag_if_supported("-fno-fast-math")
        .flag_if_supported("-ffp-contract=off")
        .warnings(false)
        .compile(name);
}

fn watch_python(dir: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        fail(&format!("cannot read {}", dir.display()));
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            if path.file_name().is_some_and(|n| n != "__pycache__") {
                watch_python(&path);
            }
        } else if path.extension().is_some_and(|e| e == "py") {
            println!("cargo:rerun-if-changed={}", path.display());
        }
    }
}

fn env(name: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| fail(&format!("cargo did not set {name}")))
}

/// A build error with a message (no panic backtrace noise).
fn fail(message: &str) -> ! {
    eprintln!("error: twv-bench: {message}");
    std::process::exit(1)
}
