//! Rules of the workspace's layout that a build does not enforce.

use crate::common::repo;

/// The workspace's member folders, as the root Cargo.toml lists them.
fn members() -> Vec<String> {
    let root: toml::Table = std::fs::read_to_string(repo("Cargo.toml"))
        .expect("the workspace's Cargo.toml")
        .parse()
        .expect("Cargo.toml is TOML");
    root["workspace"]["members"]
        .as_array()
        .expect("workspace.members")
        .iter()
        .map(|m| m.as_str().expect("a member is a path").to_string())
        .collect()
}

/// Every .rs file under `dir`.
fn rust_files(dir: &std::path::Path, found: &mut Vec<std::path::PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("a source folder").flatten() {
        let path = entry.path();
        if path.is_dir() {
            rust_files(&path, found);
        } else if path.extension().is_some_and(|e| e == "rs") {
            found.push(path);
        }
    }
}

/// A library without a test harness (`[lib] test = false`, so that its crate is not compiled a
/// second time) must not hold unit tests: they would compile in no command and never run. Its
/// tests belong in tests/tests/all/ or in doc examples.
#[test]
fn a_library_without_a_test_harness_has_no_unit_tests() {
    let mut checked = 0;
    for member in members() {
        let manifest: toml::Table = std::fs::read_to_string(repo(&member).join("Cargo.toml"))
            .expect("a member's Cargo.toml")
            .parse()
            .expect("a member's Cargo.toml is TOML");
        let lib = manifest.get("lib").and_then(|l| l.as_table());
        if lib.and_then(|l| l.get("test")).and_then(|t| t.as_bool()) != Some(false) {
            continue;
        }
        let mut files = Vec::new();
        rust_files(&repo(&member).join("src"), &mut files);
        for file in files {
            let text = std::fs::read_to_string(&file).expect("a source file");
            assert!(
                !text.contains("#[test]") && !text.contains("#[cfg(test)]"),
                "{} has unit tests, but {member}'s library has no test harness (test = false): \
                 they never run; move them to tests/tests/all/",
                file.display()
            );
        }
        checked += 1;
    }
    // twv-analysis and twv-python have no harness today: the rule was applied to something.
    assert!(
        checked >= 2,
        "only {checked} libraries without a test harness"
    );
}
