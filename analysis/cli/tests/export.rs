//! `twv export` end to end: what it writes, and every bad input refused with one line, a
//! non-zero exit and nothing written. (The archives' contents are checked by their real
//! importers, FMPy and CasADi, in python/tests/test_export.py.)

mod common;

use std::io::Read;
use std::path::Path;
use std::process::Command;

use common::{fails_with, twv};

fn scratch(name: &str) -> common::Scratch {
    common::scratch("export", name)
}

/// The names of the files in a zip archive, in order, from its local headers (`PK\x03\x04`,
/// the sizes at offsets 18 and 26–29, then the name).
fn zip_names(bytes: &[u8]) -> Vec<String> {
    let mut names = Vec::new();
    let mut i = 0;
    while i + 30 <= bytes.len() {
        if bytes[i..i + 4] == *b"PK\x03\x04" {
            let len = u16::from_le_bytes([bytes[i + 26], bytes[i + 27]]) as usize;
            let extra = u16::from_le_bytes([bytes[i + 28], bytes[i + 29]]) as usize;
            let size = u32::from_le_bytes(bytes[i + 18..i + 22].try_into().unwrap()) as usize;
            names.push(String::from_utf8_lossy(&bytes[i + 30..i + 30 + len]).to_string());
            i += 30 + len + extra + size;
        } else {
            i += 1;
        }
    }
    names
}

#[test]
fn an_fmu_has_the_standard_layout_and_a_casadi_library_its_model() {
    let dir = scratch("layout");
    let out = twv(&[
        "export",
        "--fmu",
        "--out",
        dir.join("fmu").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(dir.join("fmu/twv_vehicle8.fmu")).unwrap();
    assert_eq!(
        zip_names(&bytes),
        [
            "modelDescription.xml",
            "binaries/linux64/twv_vehicle8.so",
            "resources/bundle.json",
            "documentation/index.html"
        ]
    );
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains("generated code"), "{summary}");

    let out = twv(&[
        "export",
        "--casadi",
        "--out",
        dir.join("ca").to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let lib = dir.join("ca/libtwv_vehicle8.so");
    let bundle = twv_ir::Bundle::from_trailer(&lib).unwrap();
    let (ir, params) = bundle.model().unwrap();
    assert_eq!(ir.model(), "vehicle8");
    assert_eq!(params.len(), ir.np());
    let mut head = [0u8; 5];
    std::fs::File::open(&lib)
        .unwrap()
        .read_exact(&mut head)
        .unwrap();
    assert_eq!(&head, b"\x7fELF\x02", "a 64-bit shared library");
}

/// Only the folder the test made is there: nothing was written.
fn nothing_in(dir: &Path) {
    assert_eq!(
        std::fs::read_dir(dir).unwrap().count(),
        0,
        "nothing written into {}",
        dir.display()
    );
}

#[test]
fn bad_input_is_one_line_and_writes_nothing() {
    let dir = scratch("bad");
    let out_dir = dir.join("out");
    let out = out_dir.to_str().unwrap();
    fails_with(
        &twv(&["export", "--model", "vehicle9", "--out", out]),
        &["unknown model `vehicle9`"],
    );
    fails_with(
        &twv(&["export", "--rk4-step", "0", "--out", out]),
        &["--rk4-step", "0"],
    );
    fails_with(
        &twv(&["export", "--casadi", "--tunable", "--out", out]),
        &["--tunable", "CasADi"],
    );
    fails_with(
        &twv(&["export", "--name", "1st model", "--out", out]),
        &["--name", "not an identifier"],
    );
    let params = dir.join("bad.toml");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let text = std::fs::read_to_string(repo.join("vehicles/paper.toml")).unwrap();
    let m2 = text
        .lines()
        .find(|l| l.starts_with("m2"))
        .expect("paper.toml sets m2");
    std::fs::write(&params, text.replace(m2, "m2 = -3.0")).unwrap();
    fails_with(
        &twv(&["export", "--params", params.to_str().unwrap(), "--out", out]),
        &["m2"],
    );
    std::fs::remove_file(&params).unwrap();
    // Under a file: the folder cannot be made.
    let file = dir.join("a-file");
    std::fs::write(&file, "").unwrap();
    fails_with(
        &twv(&["export", "--out", file.join("sub").to_str().unwrap()]),
        &["a-file"],
    );
    std::fs::remove_file(&file).unwrap();
    // A runtime that is not there is named.
    let missing = Command::new(env!("CARGO_BIN_EXE_twv"))
        .args(["export", "--out", out])
        .env("TWV_EXPORT_RUNTIME", dir.join("nowhere.so"))
        .env_remove("RUST_BACKTRACE")
        .output()
        .unwrap();
    fails_with(&missing, &["TWV_EXPORT_RUNTIME", "nowhere.so"]);
    nothing_in(&dir);
}
