//! Writing results: a reused folder keeps no stale files, a failed run leaves nothing.

use std::fs;

use twv_analysis::output::*;

#[test]
fn a_reused_folder_keeps_no_stale_files() {
    let dir = std::env::temp_dir().join(format!("twv-output-stale-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    let mut first = Files::new();
    first.text("a.csv", "1");
    first.text("v_y.svg", "<svg/>");
    first.write(&dir).unwrap();
    fs::write(dir.join("mine.txt"), "kept").unwrap();
    let mut second = Files::new();
    second.text("a.csv", "2");
    second.write(&dir).unwrap();
    assert!(
        !dir.join("v_y.svg").exists(),
        "the earlier run's figure is gone"
    );
    assert_eq!(fs::read_to_string(dir.join("a.csv")).unwrap(), "2");
    assert!(
        dir.join("mine.txt").exists(),
        "files twv did not write stay"
    );
    fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn uncommitted_output_is_removed() {
    let base = std::env::temp_dir().join(format!("twv-output-test-{}", std::process::id()));
    let dir = base.join("run");
    {
        let mut out = OutputDir::create(&dir).unwrap();
        out.write("a.csv", b"1,2\n").unwrap();
        assert!(dir.join("a.csv").exists());
    }
    assert!(!dir.exists(), "a failed run leaves nothing behind");
    let mut out = OutputDir::create(&dir).unwrap();
    out.write("b.json", b"{}").unwrap();
    let kept = out.commit();
    assert_eq!(fs::read(&kept[0]).unwrap(), b"{}");
    fs::remove_dir_all(&base).unwrap();
}
