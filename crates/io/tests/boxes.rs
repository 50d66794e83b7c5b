//! Person boxes JSON: round trip, tolerant reading, errors.

use bodyseg_core::{PersonBox, PersonBoxes};
use bodyseg_io::{IoError, parse_boxes, read_boxes, write_boxes};
use std::path::Path;

fn sample() -> PersonBoxes {
    PersonBoxes {
        frame: "000012".into(),
        boxes: vec![
            PersonBox {
                id: 0,
                center_m: [0.1, 0.4, 0.9],
                half_extents_m: [0.45, 0.45, 0.95],
                yaw_rad: 0.3,
            },
            PersonBox {
                id: 7,
                center_m: [-1.0e-3, 2.5, 0.95],
                half_extents_m: [0.3, 0.6, 1.0],
                yaw_rad: -std::f32::consts::PI,
            },
        ],
        world_from_cloud: None,
    }
}

#[test]
fn boxes_round_trip_as_pretty_json() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("000012.json");
    write_boxes(&path, &sample()).expect("write");
    // serde_json writes f32 with the shortest round-tripping decimal: exact equality.
    assert_eq!(read_boxes(&path).expect("read"), sample());
    let text = std::fs::read_to_string(&path).expect("text");
    assert!(text.starts_with("{\n  \"frame\": \"000012\""), "{text}");
    assert!(text.ends_with("}\n"));
    let names: Vec<_> = std::fs::read_dir(dir.path()).expect("ls").collect();
    assert_eq!(names.len(), 1);
}

#[test]
fn reads_formats_md_example_ignoring_unknown_keys() {
    let text = r#"{"frame": "000012", "tracker": {"version": 2},
        "boxes": [{"id": 0, "center_m": [0.1, 0.4, 0.9], "half_extents_m": [0.45, 0.45, 0.95],
                   "yaw_rad": 0.3, "score": 0.98},
                  {"id": 1, "center_m": [1, 2, 1], "half_extents_m": [0.5, 0.5, 1]}]}"#;
    let b = parse_boxes(text.as_bytes(), Path::new("b.json")).expect("parse");
    assert_eq!(b.frame, "000012");
    assert_eq!(b.boxes[0], sample().boxes[0]);
    assert_eq!(b.boxes[1].yaw_rad, 0.0); // absent: 0
    let no_frame = parse_boxes(br#"{"boxes": []}"#, Path::new("b.json")).expect("parse");
    assert_eq!(no_frame, PersonBoxes::default());
}

#[test]
fn bad_json_names_the_file_line_and_column() {
    let path = Path::new("rec/boxes/000012.json");
    let err = parse_boxes(b"{\"frame\": \"1\",\n \"boxes\": [}", path).expect_err("bad json");
    assert!(matches!(err, IoError::BoxesJson { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.starts_with("rec/boxes/000012.json: bad boxes JSON: "),
        "{msg}"
    );
    assert!(msg.contains("line 2 column"), "{msg}");

    let wrong_shape = parse_boxes(br#"{"boxes": [{"id": 0}]}"#, path).expect_err("no centre");
    assert!(
        wrong_shape.to_string().contains("center_m"),
        "{wrong_shape}"
    );
    assert!(matches!(
        parse_boxes(b"", path),
        Err(IoError::BoxesJson { .. })
    ));
}

#[test]
fn invalid_box_is_an_error_naming_it() {
    let text = br#"{"boxes": [{"id": 0, "center_m": [0, 0, 0], "half_extents_m": [1, 1, 1]},
                               {"id": 5, "center_m": [0, 0, 0], "half_extents_m": [1, -1, 1]}]}"#;
    let err = parse_boxes(text, Path::new("b.json")).expect_err("negative extent");
    assert!(matches!(err, IoError::InvalidBox { index: 1, .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.starts_with("b.json: boxes[1]: box 5: half_extents_m"),
        "{msg}"
    );
}

#[test]
fn non_finite_box_is_refused_on_write() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("b.json");
    let mut boxes = sample();
    boxes.boxes[1].center_m[2] = f32::NAN; // JSON has no NaN: the file could not be read back
    let err = write_boxes(&path, &boxes).expect_err("NaN");
    assert!(matches!(err, IoError::InvalidBox { index: 1, .. }), "{err}");
    assert!(!path.exists());
}

#[test]
fn missing_file_is_a_read_error() {
    let err = read_boxes(Path::new("/nonexistent/boxes.json")).expect_err("missing");
    assert!(matches!(err, IoError::Read { .. }), "{err}");
    assert!(
        err.to_string()
            .starts_with("/nonexistent/boxes.json: cannot read")
    );
}
