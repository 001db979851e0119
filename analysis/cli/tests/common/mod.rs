//! Helpers shared by the end-to-end tests of the `twv` binary.
#![allow(dead_code)] // each test binary uses its own subset

use std::ops::Deref;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Run the real binary (no backtrace requested).
pub fn twv(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_twv"))
        .args(args)
        .env_remove("RUST_BACKTRACE")
        .output()
        .expect("the twv binary runs")
}

/// A fresh scratch folder per test (`group` keeps test binaries apart), removed when the test
/// passes and kept for a look when it fails (dropped while panicking).
pub fn scratch(group: &str, name: &str) -> Scratch {
    let dir = scratch_path(group, name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A scratch folder's path that may not exist yet (for commands that must create it
/// themselves), with the same clean-up as [`scratch`].
pub fn scratch_path(group: &str, name: &str) -> Scratch {
    Scratch(Scratch::path_for(group, name))
}

/// A test's scratch folder; derefs to its path.
pub struct Scratch(PathBuf);

impl Scratch {
    fn path_for(group: &str, name: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("twv-{group}-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        dir
    }
}

impl Deref for Scratch {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for Scratch {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// Expect failure with a one-line message containing every `needle`: exit code 1, no panic or
/// backtrace, the `twv: error:` prefix.
pub fn fails_with(out: &Output, needles: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success(),
        "expected failure, got success; stderr: {stderr}"
    );
    assert_eq!(out.status.code(), Some(1), "exit code; stderr: {stderr}");
    assert!(
        !stderr.contains("panicked") && !stderr.contains("backtrace"),
        "{stderr}"
    );
    assert!(stderr.starts_with("twv: error:"), "{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "`{n}` missing from: {stderr}");
    }
    stderr
}

/// Expect a completed run with a negative verdict: exit code 3, a `twv:` line naming it, no
/// panic.
pub fn negative_with(out: &Output, needles: &[&str]) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(3), "exit code; stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "`{n}` missing from: {stderr}");
    }
    stderr
}
