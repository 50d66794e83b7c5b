//! Error messages: one line starting with the file, the cause printed exactly once when
//! the error is shown with its `source()` chain (as anyhow's `{:#}` does).

mod common;

use bodyseg_io::{
    IoError, PlyWriteOptions, parse_boxes, read_boxes, read_ply, read_text, write_atomic, write_ply,
};
use common::sample_cloud;
use std::error::Error as _;
use std::path::Path;

/// The error and its `source()` chain joined by ": ", as anyhow's `{:#}` prints it.
fn chain(err: &IoError) -> String {
    let mut s = err.to_string();
    let mut next = err.source();
    while let Some(e) = next {
        s.push_str(&format!(": {e}"));
        next = e.source();
    }
    s
}

/// `err` prints as one line starting with `path`, holds `cause` exactly once with its
/// chain, and its `to_string()` alone already holds `cause`.
fn assert_cause_once(err: &IoError, path: &Path, cause: &str) {
    let msg = err.to_string();
    let full = chain(err);
    assert!(!full.contains('\n'), "{full:?}");
    assert!(msg.starts_with(&path.display().to_string()), "{msg}");
    assert!(msg.contains(cause), "{cause:?} not in {msg:?}");
    assert_eq!(full.matches(cause).count(), 1, "{full}");
    assert!(err.source().is_none(), "{full}");
}

#[test]
fn read_error_prints_the_os_error_once() {
    let path = Path::new("/nonexistent/dir/x.ply");
    let os = std::fs::read(path).expect_err("no file").to_string();
    let err = read_ply(path).expect_err("no file");
    assert!(matches!(err, IoError::Read { .. }), "{err}");
    assert_cause_once(&err, path, &os);
    assert!(err.to_string().contains("cannot read"), "{err}");

    let err = read_boxes(Path::new("/nonexistent/b.json")).expect_err("no file");
    assert_cause_once(&err, Path::new("/nonexistent/b.json"), &os);
    let err = read_text(Path::new("/nonexistent/c.toml")).expect_err("no file");
    assert_cause_once(&err, Path::new("/nonexistent/c.toml"), &os);
}

#[test]
fn write_error_prints_the_cause_once() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("out.bin");
    let err = write_atomic(&path, |_| {
        Err(std::io::Error::other("disk full (simulated)"))
    })
    .expect_err("must fail");
    assert!(matches!(err, IoError::Write { .. }), "{err}");
    assert_cause_once(&err, &path, "disk full (simulated)");

    let missing = dir.path().join("no/such/dir/o.ply");
    let err = write_ply(&missing, &sample_cloud(3, 1), &PlyWriteOptions::default())
        .expect_err("no folder");
    assert!(matches!(err, IoError::Write { .. }), "{err}");
    assert!(err.to_string().contains("cannot write"), "{err}");
    assert!(err.source().is_none(), "{}", chain(&err));
}

#[test]
fn invalid_cloud_prints_the_cloud_error_once() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("cloud.ply");
    let mut cloud = sample_cloud(5, 1);
    cloud.positions_m[2][0] = f32::NAN;
    let err = write_ply(&path, &cloud, &PlyWriteOptions::default()).expect_err("NaN");
    assert!(matches!(err, IoError::InvalidCloud { .. }), "{err}");
    let cause = cloud.validate().expect_err("NaN").to_string();
    assert_cause_once(&err, &path, &cause);
}

#[test]
fn bad_boxes_json_prints_serdes_message_once() {
    let path = Path::new("bad.json");
    let err = parse_boxes(b"{\"boxes\": [", path).expect_err("truncated JSON");
    assert!(matches!(err, IoError::BoxesJson { .. }), "{err}");
    assert_cause_once(&err, path, "EOF while parsing a list at line 1 column 11");
}
