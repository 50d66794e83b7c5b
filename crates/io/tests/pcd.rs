//! PCD reading against files written by another implementation (Python `pypcd4`, see
//! `scripts/gen_pcd_fixtures.py`), and every bad-input case naming the file.

use bodyseg_core::Label;
use bodyseg_io::{IoError, parse_pcd, read_pcd};
use serde_json::Value;
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join("data")
        .join(name)
}

fn sidecar() -> Value {
    let text = std::fs::read_to_string(data("pcd_fixtures.json")).expect("sidecar");
    serde_json::from_str(&text).expect("sidecar JSON")
}

#[test]
fn fixtures_read_as_the_script_wrote_them() {
    let sidecar = sidecar();
    let files = sidecar.as_object().expect("object");
    assert_eq!(files.len(), 4);
    for (file, spec) in files {
        let cloud = read_pcd(&data(file)).unwrap_or_else(|e| panic!("{e}"));
        let want = spec["expected"].as_array().expect("expected");
        assert_eq!(cloud.len(), want.len(), "{file}: NaN points are skipped");
        let colors = cloud.colors.as_ref().expect("rgb read");
        for (k, w) in want.iter().enumerate() {
            let index = w["index"].as_u64().expect("index") as u32;
            assert_eq!(cloud.origins[k].pixel, index, "{file} point {k}");
            for a in 0..3 {
                // Exact: the values are float32 in every file (ASCII with 10 decimals,
                // more than a float32 needs to round-trip).
                let v = w["xyz"][a].as_f64().expect("xyz") as f32;
                assert_eq!(cloud.positions_m[k][a], v, "{file} point {index} axis {a}");
            }
            let rgb: Vec<u8> = (0..3)
                .map(|a| w["rgb"][a].as_u64().expect("rgb") as u8)
                .collect();
            assert_eq!(colors[k].to_vec(), rgb, "{file} point {index} colour");
            let label = match w.get("label") {
                Some(l) => Label::from_id(l.as_u64().expect("label") as u8).expect("label id"),
                None => Label::UNKNOWN,
            };
            assert_eq!(cloud.labels[k], label, "{file} point {index}");
        }
    }
}

#[test]
fn organised_scene_reads_its_valid_pixels() {
    let cloud = read_pcd(&data("scene_handover.pcd")).expect("scene");
    // 3 cameras x 128 x 106 grid cells, of which pcd_scene wrote 17456 points.
    assert_eq!(cloud.len(), 17_456);
    assert!(cloud.origins.iter().all(|o| o.pixel < 128 * 318));
    assert!(cloud.colors.is_none());
}

/// A header with `kind` as DATA, WIDTH 2, HEIGHT 1 and POINTS `points`.
fn header(kind: &str, points: usize) -> String {
    format!(
        "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n\
         WIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {points}\nDATA {kind}\n"
    )
}

fn error(bytes: &[u8]) -> IoError {
    parse_pcd(bytes, Path::new("bad.pcd")).expect_err("bad input")
}

#[test]
fn bad_input_is_a_clear_error_naming_the_file() {
    let e = error(header("binary_lz4", 2).as_bytes());
    assert!(matches!(e, IoError::PcdDataKind { .. }), "{e}");
    assert_eq!(
        e.to_string(),
        "bad.pcd: unsupported PCD DATA kind 'binary_lz4' (expected ascii, binary or binary_compressed)"
    );

    let e = error(header("binary", 3).as_bytes());
    assert_eq!(
        e.to_string(),
        "bad.pcd: PCD header says WIDTH 2 x HEIGHT 1 = 2 but POINTS 3"
    );

    // Binary: 2 points need 24 bytes, 20 given.
    let mut b = header("binary", 2).into_bytes();
    b.extend_from_slice(&[0u8; 20]);
    let e = error(&b);
    assert!(matches!(e, IoError::PcdTruncated { .. }), "{e}");
    assert!(
        e.to_string()
            .starts_with("bad.pcd: truncated PCD data: header declares 2 points of 12 bytes"),
        "{e}"
    );

    // ASCII: one line of two.
    let e = error(format!("{}1 2 3\n", header("ascii", 2)).as_bytes());
    assert!(
        e.to_string()
            .contains("header declares 2 points, ASCII data holds 1"),
        "{e}"
    );
    let e = error(format!("{}1 2\n4 5 6\n", header("ascii", 2)).as_bytes());
    assert!(e.to_string().contains("point 0 has 2 values"), "{e}");
    let e = error(format!("{}1 2 x\n4 5 6\n", header("ascii", 2)).as_bytes());
    assert!(matches!(e, IoError::BadValue { .. }), "{e}");

    // Compressed: the real fixture cut short, and with a corrupt size.
    let full = std::fs::read(data("xyzrgb_binary_compressed.pcd")).expect("fixture");
    let e = error(&full[..full.len() - 10]);
    assert!(matches!(e, IoError::PcdTruncated { .. }), "{e}");
    let e = error(&full[..full.len() - 700]);
    assert!(
        matches!(e, IoError::PcdTruncated { .. } | IoError::PcdHeader { .. }),
        "{e}"
    );

    // No DATA line; no x field; unknown key.
    let e = error(b"VERSION 0.7\nFIELDS x y z\n");
    assert!(
        e.to_string()
            .starts_with("bad.pcd: PCD header line 3: no DATA line"),
        "{e}"
    );
    let e = error(
        header("ascii", 2)
            .replace("FIELDS x y z", "FIELDS a y z")
            .as_bytes(),
    );
    assert!(e.to_string().contains("no 'x' field"), "{e}");
    let e = error(b"ply\nformat ascii 1.0\n");
    assert!(e.to_string().contains("unknown header key 'PLY'"), "{e}");

    // A missing file is named too.
    let e = read_pcd(Path::new("/nonexistent/x.pcd")).expect_err("missing");
    assert!(
        e.to_string().starts_with("/nonexistent/x.pcd: cannot read"),
        "{e}"
    );
}

#[test]
fn labels_out_of_range_are_rejected() {
    let text = "VERSION 0.7\nFIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n\
                WIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA ascii\n0 0 0 6\n1 1 1 17\n";
    let e = error(text.as_bytes());
    assert!(
        e.to_string().starts_with(
            "bad.pcd: point 1: label is 17, not a bodyseg class id (0..=6, 255 = unknown)"
        ),
        "{e}"
    );
}
