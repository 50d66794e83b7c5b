//! Text files: read as UTF-8, errors naming the file.

use bodyseg_io::{IoError, read_text, write_bytes_atomic};

#[test]
fn reads_utf8_text_as_is() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("a.toml");
    let text = "[refine]\r\neps_m = 0.05 # 5 cm, µ ≠ m\n";
    write_bytes_atomic(&path, text.as_bytes()).expect("write");
    assert_eq!(read_text(&path).expect("read"), text);

    let empty = dir.path().join("empty.toml");
    write_bytes_atomic(&empty, b"").expect("write");
    assert_eq!(read_text(&empty).expect("read"), "");
}

#[test]
fn missing_file_is_a_read_error_naming_it() {
    let err = read_text(std::path::Path::new("/nonexistent/c.toml")).expect_err("missing");
    assert!(matches!(err, IoError::Read { .. }), "{err}");
    assert!(
        err.to_string()
            .starts_with("/nonexistent/c.toml: cannot read: "),
        "{err}"
    );
}

#[test]
fn invalid_utf8_names_the_file_line_and_offset() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("latin1.toml");
    // "é" in Latin-1 on the second line.
    write_bytes_atomic(&path, b"[refine]\n# caf\xe9\n").expect("write");
    let err = read_text(&path).expect_err("not UTF-8");
    assert!(
        matches!(
            err,
            IoError::NotUtf8 {
                line: 2,
                offset: 14,
                ..
            }
        ),
        "{err:?}"
    );
    assert_eq!(
        err.to_string(),
        format!(
            "{}: not UTF-8 text: invalid byte sequence on line 2 (byte offset 14)",
            path.display()
        )
    );
}
