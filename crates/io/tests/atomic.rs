//! Atomic writes: a failed write leaves the destination as it was and no temporary.

use bodyseg_core::{LabeledCloud, PersonBoxes};
use bodyseg_io::{
    Durability, IoError, PlyWriteOptions, sync_file_system, write_atomic, write_atomic_with,
    write_boxes, write_bytes_atomic, write_ply,
};
use std::io::{self, Write};
use std::path::Path;

/// Names of the entries in `dir`, sorted.
fn listing(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .expect("read_dir")
        .map(|e| e.expect("entry").file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

/// Writes part of the data, then fails, as a writer hitting a full disk would.
fn fail_midway(w: &mut dyn Write) -> io::Result<()> {
    w.write_all(&[7u8; 100_000])?;
    Err(io::Error::other("disk full (simulated)"))
}

/// `path` holds `want` and is the only entry of its folder (no temporary left behind).
fn assert_only_file(path: &Path, want: &[u8]) {
    assert_eq!(std::fs::read(path).expect("read"), want);
    let folder = path.parent().expect("a file in a folder");
    let name = path.file_name().expect("a file name").to_string_lossy();
    assert_eq!(listing(folder), [name]);
}

/// The message opens with the path of the file or folder that failed.
fn assert_names_path(err: &IoError, path: &Path) {
    let msg = err.to_string();
    assert!(msg.starts_with(&path.display().to_string()), "{msg}");
}

#[test]
fn successful_write_replaces_the_file_and_leaves_no_temporary() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("out.bin");
    write_atomic(&path, |w| w.write_all(b"first")).expect("write");
    assert_eq!(std::fs::read(&path).expect("read"), b"first");
    write_bytes_atomic(&path, b"second, longer").expect("overwrite");
    assert_only_file(&path, b"second, longer");
}

#[test]
fn unsynced_writes_are_atomic_too_and_a_bulk_sync_follows() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("out.bin");
    std::fs::write(&path, b"previous result").expect("seed");
    write_atomic_with(&path, Durability::Renamed, fail_midway).expect_err("must fail");
    assert_only_file(&path, b"previous result");
    write_atomic_with(&path, Durability::Renamed, |w| w.write_all(b"new")).expect("write");
    assert_only_file(&path, b"new");
    sync_file_system(dir.path()).expect("sync");
    let missing = dir.path().join("missing");
    let err = sync_file_system(&missing).expect_err("no such folder");
    assert_names_path(&err, &missing);
}

#[test]
fn failing_writer_leaves_no_file_and_no_temporary() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("out.bin");
    let err = write_atomic(&path, fail_midway).expect_err("must fail");
    assert!(matches!(err, IoError::Write { .. }), "{err}");
    assert!(err.to_string().contains("disk full (simulated)"), "{err}");
    assert_names_path(&err, &path);
    assert!(listing(dir.path()).is_empty(), "{:?}", listing(dir.path()));
}

#[test]
fn failing_writer_leaves_an_existing_destination_untouched() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("out.ply");
    std::fs::write(&path, b"previous result").expect("seed");
    write_atomic(&path, fail_midway).expect_err("must fail");
    assert_only_file(&path, b"previous result");
}

#[test]
fn writers_that_refuse_their_input_leave_the_destination_untouched() {
    let dir = tempfile::tempdir().expect("tempdir");
    let ply = dir.path().join("cloud.ply");
    let json = dir.path().join("boxes.json");
    std::fs::write(&ply, b"old cloud").expect("seed");
    std::fs::write(&json, b"old boxes").expect("seed");
    let mut bad_cloud = LabeledCloud::default();
    bad_cloud.positions_m.push([0.0; 3]); // no label, no origin
    write_ply(&ply, &bad_cloud, &PlyWriteOptions::default()).expect_err("invalid cloud");
    let bad_boxes: PersonBoxes = serde_json::from_str(
        r#"{"boxes": [{"id": 1, "center_m": [0, 0, 0], "half_extents_m": [0, 1, 1]}]}"#,
    )
    .expect("json");
    write_boxes(&json, &bad_boxes).expect_err("invalid box");
    assert_eq!(std::fs::read(&ply).expect("read"), b"old cloud");
    assert_eq!(std::fs::read(&json).expect("read"), b"old boxes");
    assert_eq!(listing(dir.path()), ["boxes.json", "cloud.ply"]);
}

#[test]
fn missing_directory_is_a_write_error_naming_the_path() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("no/such/dir/out.bin");
    let err = write_atomic(&path, |w| w.write_all(b"x")).expect_err("no dir");
    assert!(matches!(err, IoError::Write { .. }), "{err}");
    assert_names_path(&err, &path);
}

#[test]
fn destination_that_is_a_directory_fails_cleanly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("taken");
    std::fs::create_dir(&path).expect("mkdir");
    std::fs::write(path.join("inside"), b"keep").expect("seed");
    let err = write_atomic(&path, |w| w.write_all(b"x")).expect_err("is a directory");
    assert!(matches!(err, IoError::Write { .. }), "{err}");
    assert_eq!(listing(dir.path()), ["taken"]);
    assert_eq!(std::fs::read(path.join("inside")).expect("read"), b"keep");
}

#[cfg(unix)]
#[test]
fn new_files_get_the_permissions_of_file_create() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().expect("tempdir");
    let reference = dir.path().join("reference");
    std::fs::File::create(&reference).expect("create");
    let path = dir.path().join("atomic");
    write_bytes_atomic(&path, b"x").expect("write");
    let mode = |p: &Path| std::fs::metadata(p).expect("stat").permissions().mode() & 0o777;
    // Not the 0o600 of a bare temporary file: what the umask allows, as File::create.
    assert_eq!(mode(&path), mode(&reference));
}
