//! Writing a recording (`--out` of `example`, `simulate`, `import`, `apply`): a symbolic link is written through
//! to its target, a FIFO in place, a directory and a read-only file are refused with the reason; nothing that is
//! not a regular file is ever replaced, and no scratch file is left (docs/formats.md#writing).

#![cfg(unix)]

use std::os::unix::fs::{FileTypeExt, PermissionsExt};
use std::path::Path;

use sinscal_host::io::recording::Recording;
use sinscal_host::model::synth::Scenario;

fn recording() -> Recording {
    Scenario { dwell_s: 2.0, ..Scenario::example() }.recording(1, "example.csv")
}

fn scratch_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".partial"))
        .collect()
}

#[test]
fn a_symbolic_link_is_written_through_to_its_target() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("target.csv");
    std::fs::write(&target, "old").unwrap();
    let link = dir.path().join("link.csv");
    std::os::unix::fs::symlink("target.csv", &link).unwrap();
    let rec = recording();
    rec.write(&link).expect("written through the link");
    assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink(), "the link is still a link");
    assert_eq!(std::fs::read_to_string(&target).unwrap(), rec.to_csv(), "the target holds the recording");
    // A link whose target does not exist yet: the target is created, the link kept.
    let dangling = dir.path().join("dangling.csv");
    std::os::unix::fs::symlink("new.csv", &dangling).unwrap();
    rec.write(&dangling).expect("written through the dangling link");
    assert!(std::fs::symlink_metadata(&dangling).unwrap().file_type().is_symlink());
    assert_eq!(std::fs::read_to_string(dir.path().join("new.csv")).unwrap(), rec.to_csv());
    assert!(scratch_files(dir.path()).is_empty());
}

#[test]
fn a_fifo_is_written_in_place_not_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("pipe.csv");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().expect("mkfifo runs");
    assert!(made.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap())
    };
    let rec = recording();
    rec.write(&fifo).expect("written into the FIFO");
    assert_eq!(reader.join().unwrap(), rec.to_csv(), "the reader got the recording");
    assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo(), "the FIFO is still a FIFO");
    assert!(scratch_files(dir.path()).is_empty());
}

#[test]
fn a_directory_and_a_read_only_file_are_refused_with_the_reason() {
    let dir = tempfile::tempdir().unwrap();
    let rec = recording();
    let err = rec.write(dir.path()).expect_err("a directory").to_string();
    assert!(err.contains("is a directory"), "{err}");
    let locked = dir.path().join("locked.csv");
    std::fs::write(&locked, "keep").unwrap();
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o444)).unwrap();
    let err = rec.write(&locked).expect_err("a read-only file").to_string();
    assert!(err.contains("read-only"), "{err}");
    assert_eq!(std::fs::read_to_string(&locked).unwrap(), "keep", "left as it was");
    // Through a link to it, the same.
    let link = dir.path().join("to-locked.csv");
    std::os::unix::fs::symlink(&locked, &link).unwrap();
    let err = rec.write(&link).expect_err("a link to a read-only file").to_string();
    assert!(err.contains("read-only"), "{err}");
    assert!(scratch_files(dir.path()).is_empty());
}
