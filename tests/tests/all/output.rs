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

/// A manifest someone edited, a file the user changed, a subfolder that is a symbolic link:
/// a rerun removes only regular files inside the folder with the bytes twv wrote there, and
/// says what it left (issue 38).
#[test]
fn a_rerun_removes_only_its_own_unchanged_files_and_never_follows_a_link() {
    let base = std::env::temp_dir().join(format!("twv-output-own-{}", std::process::id()));
    let _ = fs::remove_dir_all(&base);
    let (dir, outside) = (base.join("out"), base.join("outside"));
    fs::create_dir_all(&outside).unwrap();
    fs::write(outside.join("precious.txt"), "the user's").unwrap();
    let mut first = Files::new();
    first.text("a.csv", "1");
    first.text("figures/old.svg", "<svg/>");
    first.text("changed.txt", "twv's");
    first.write(&dir).unwrap();
    // The user: edits one of twv's files, adds own files to the manifest (one through a link
    // to a folder outside, one climbing out), and keeps a file of their own.
    fs::write(dir.join("changed.txt"), "the user's now").unwrap();
    fs::write(dir.join("mine.txt"), "the user's").unwrap();
    std::os::unix::fs::symlink(&outside, dir.join("linked")).unwrap();
    let manifest = fs::read_to_string(dir.join(".twv-files")).unwrap();
    assert_eq!(manifest.lines().count(), 3);
    assert!(
        manifest
            .lines()
            .all(|l| l.split_once("  ").unwrap().0.len() == 64),
        "{manifest}"
    );
    let hash_of_theirs = manifest.lines().next().unwrap().split_once("  ").unwrap().0;
    let forged = format!(
        "{manifest}{hash_of_theirs}  mine.txt\n{hash_of_theirs}  linked/precious.txt\n\
         {hash_of_theirs}  ../outside/precious.txt\n"
    );
    fs::write(dir.join(".twv-files"), forged).unwrap();

    let mut second = Files::new();
    second.text("a.csv", "2");
    let written = second.write(&dir).unwrap();
    assert!(
        !dir.join("figures/old.svg").exists(),
        "twv's own stale file is gone"
    );
    assert_eq!(
        fs::read_to_string(dir.join("changed.txt")).unwrap(),
        "the user's now"
    );
    assert!(dir.join("mine.txt").exists());
    assert_eq!(
        fs::read_to_string(outside.join("precious.txt")).unwrap(),
        "the user's"
    );
    let notes = written.left.join("\n");
    assert!(
        notes.contains("changed.txt in place: it changed since twv wrote it"),
        "{notes}"
    );
    assert!(notes.contains("mine.txt in place: it changed"), "{notes}");
    assert!(notes.contains("symbolic link"), "{notes}");
    assert!(notes.contains("not a plain name"), "{notes}");

    // Writing through a linked subfolder is refused, and nothing of that run is left.
    let mut through = Files::new();
    through.text("linked/precious.txt", "overwritten");
    let err = through.write(&dir).unwrap_err().to_string();
    assert!(err.contains("linked"), "{err}");
    assert_eq!(
        fs::read_to_string(outside.join("precious.txt")).unwrap(),
        "the user's"
    );
    fs::remove_dir_all(&base).unwrap();
}
