//! PLY reader and writer: round trips, hand-written files in every encoding, errors.

mod common;

use bodyseg_core::{Class, Label, LabeledCloud, PointOrigin};
use bodyseg_io::{
    IoError, PlyColors, PlyFormat, PlyWriteOptions, parse_ply, ply_bytes, read_ply, write_ply,
};
use common::{Enc, PlyBuilder, sample_cloud};
use std::path::Path;

const P: &str = "test.ply";

fn parse(bytes: &[u8]) -> Result<LabeledCloud, IoError> {
    parse_ply(bytes, Path::new(P))
}

fn bits(c: &LabeledCloud) -> Vec<[u32; 3]> {
    c.positions_m.iter().map(|p| p.map(f32::to_bits)).collect()
}

fn round_trip(format: PlyFormat) {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("cloud.ply");
    let cloud = sample_cloud(500, 7);
    let opts = PlyWriteOptions {
        format,
        colors: PlyColors::Camera,
        ..Default::default()
    };
    write_ply(&path, &cloud, &opts).expect("write");
    let back = read_ply(&path).expect("read");
    // Bit-exact, not approximately equal: -0.0, subnormals and f32::MAX included.
    assert_eq!(bits(&back), bits(&cloud));
    assert_eq!(back.labels, cloud.labels);
    assert_eq!(back.origins, cloud.origins);
    assert_eq!(back.colors, cloud.colors);
    assert_eq!(
        std::fs::read(&path).expect("read bytes"),
        ply_bytes(&cloud, &opts, &path).expect("bytes")
    );
}

#[test]
fn binary_round_trip_is_bit_exact() {
    round_trip(PlyFormat::BinaryLittleEndian);
}

#[test]
fn ascii_round_trip_is_exact() {
    round_trip(PlyFormat::Ascii);
}

#[test]
fn default_options_write_formats_md_layout_with_palette_colors() {
    let cloud = sample_cloud(10, 3);
    let bytes = ply_bytes(&cloud, &PlyWriteOptions::default(), Path::new(P)).expect("bytes");
    let end = b"end_header\n";
    let header_len = bytes
        .windows(end.len())
        .position(|w| w == end)
        .expect("end_header")
        + end.len();
    let header = std::str::from_utf8(&bytes[..header_len]).expect("ascii header");
    let lines: Vec<&str> = header.lines().collect();
    assert_eq!(lines[..2], ["ply", "format binary_little_endian 1.0"]);
    assert!(lines[2].starts_with("comment ") && lines[2].contains("bodyseg"));
    assert_eq!(
        lines[3..],
        [
            "element vertex 10",
            "property float x",
            "property float y",
            "property float z",
            "property uchar red",
            "property uchar green",
            "property uchar blue",
            "property uchar label",
            "property uchar camera",
            "property uint pixel",
            "end_header",
        ]
    );
    // 3 × 4 + 3 + 1 + 1 + 4 bytes per point.
    assert_eq!(bytes.len(), header_len + 10 * 21);
    // Point 1, little-endian: x = f32::MAX, then the palette colour of label id 1 (head).
    let rec = &bytes[header_len + 21..header_len + 42];
    assert_eq!(rec[..4], f32::MAX.to_le_bytes());
    assert_eq!(rec[12..15], Class::Head.color());
    assert_eq!(rec[15], 1);
    assert_eq!(rec[16], cloud.origins[1].camera);
    assert_eq!(rec[17..21], u32::MAX.to_le_bytes());

    // Unknown (id 255, point 7) is white.
    let rec = &bytes[header_len + 7 * 21..header_len + 8 * 21];
    assert_eq!(rec[12..15], [255, 255, 255]);

    // The palette is read back as no colours (a camera colour is expected there).
    let back = parse(&bytes).expect("parse");
    assert_eq!(back.colors, None);
    assert_eq!(back.labels, cloud.labels);
    // The same bytes without the comment read the palette as colours.
    let text = std::str::from_utf8(&bytes[..header_len]).expect("ascii header");
    let plain = text.replace("class palette", "something");
    let mut other = plain.into_bytes();
    other.extend_from_slice(&bytes[header_len..]);
    let palette: Vec<[u8; 3]> = cloud.labels.iter().map(|l| l.color()).collect();
    assert_eq!(parse(&other).expect("parse").colors, Some(palette));
}

#[test]
fn writer_refuses_bad_input_and_writes_nothing() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("cloud.ply");
    let mut cloud = sample_cloud(5, 1);
    cloud.colors = None;
    let camera = PlyWriteOptions {
        colors: PlyColors::Camera,
        ..Default::default()
    };
    let err = write_ply(&path, &cloud, &camera).expect_err("no colours");
    assert!(matches!(err, IoError::NoCameraColors { .. }), "{err}");
    assert!(err.to_string().starts_with(&path.display().to_string()));

    cloud.origins.pop();
    let err = write_ply(&path, &cloud, &PlyWriteOptions::default()).expect_err("short origins");
    assert!(matches!(err, IoError::InvalidCloud { .. }), "{err}");
    assert_eq!(std::fs::read_dir(dir.path()).expect("ls").count(), 0);
}

#[test]
fn empty_cloud_round_trips() {
    for format in [PlyFormat::BinaryLittleEndian, PlyFormat::Ascii] {
        let opts = PlyWriteOptions {
            format,
            ..Default::default()
        };
        let bytes = ply_bytes(&LabeledCloud::default(), &opts, Path::new(P)).expect("bytes");
        let back = parse(&bytes).expect("parse");
        assert!(back.is_empty());
        // Default options write the class palette, read back as no colours.
        assert_eq!(back.colors, None);
    }
}

/// A hand-written file as other tools write them: comments, obj_info, extra vertex
/// properties (normals, a double intensity), properties in another order, no camera or
/// pixel, no colours, `face` elements before and after the vertices.
const HAND_WRITTEN: &str = "ply\r
format ascii 1.0
comment made by hand
obj_info scanner none
element face 2
property list uchar int vertex_indices
property uchar flags
element vertex 4
property uchar label
property float x
property float nx
property float ny
property float nz
property float y
property double intensity
property float z
property list uint8 float32 weights
element edge 1
property int vertex1
property int vertex2
end_header
3 0 1 2 7
4 0 1 2 3 8

1 0.5 0 0 1 -1.25 0.123456789012 2 0
2\t1e-3 0 0 1 1 0.25 3.5 2 0.5 0.5
255 -0 0 0 1 7 0.5 1E2 0
6 1 0 0 1 2 0.5 3 1 9
0 1
";

#[test]
fn reads_hand_written_ascii_with_extra_properties_and_elements() {
    let c = parse(HAND_WRITTEN.as_bytes()).expect("parse");
    assert_eq!(
        c.positions_m,
        vec![
            [0.5, -1.25, 2.0],
            [1e-3, 1.0, 3.5],
            [-0.0, 7.0, 100.0],
            [1.0, 2.0, 3.0]
        ]
    );
    assert_eq!(c.positions_m[2][0].to_bits(), (-0.0f32).to_bits());
    let ids: Vec<u8> = c.labels.iter().map(|l| l.id()).collect();
    assert_eq!(ids, [1, 2, 255, 6]);
    assert!(c.labels[2].is_unknown());
    assert_eq!(c.colors, None);
    // Core's documented default: camera 0, pixel = vertex index.
    let want: Vec<PointOrigin> = (0..4)
        .map(|pixel| PointOrigin { camera: 0, pixel })
        .collect();
    assert_eq!(c.origins, want);
}

#[test]
fn every_scalar_type_converts_in_every_encoding() {
    let header = "element face 1\nproperty list uchar int vertex_indices\n\
        element vertex 2\n\
        property double x\nproperty float32 y\nproperty short z\n\
        property int8 ignored_char\nproperty uint16 ignored_ushort\nproperty int ignored_int\n\
        property char label\n\
        property uchar red\nproperty ushort green\nproperty float blue\n\
        property uint8 camera\nproperty uint pixel\n\
        element face2 1\nproperty list ushort double values\n";
    for enc in Enc::ALL {
        let mut b = PlyBuilder::new(enc, header);
        b.row(&[
            ("uchar", 3.0),
            ("int", 0.0),
            ("int", -1.0),
            ("int", 70000.0),
        ]);
        b.row(&[
            ("double", 0.1),
            ("float32", -2.5),
            ("short", -3.0),
            ("int8", -128.0),
            ("uint16", 65535.0),
            ("int", -2147483648.0),
            ("char", 5.0),
            ("uchar", 255.0),
            ("ushort", 17.0),
            ("float", 0.5),
            ("uint8", 3.0),
            ("uint", 4294967295.0),
        ]);
        b.row(&[
            ("double", 1.0),
            ("float32", 0.25),
            ("short", 32767.0),
            ("int8", 127.0),
            ("uint16", 0.0),
            ("int", 2147483647.0),
            ("char", 0.0),
            ("uchar", 0.0),
            ("ushort", 0.0),
            ("float", 1.0),
            ("uint8", 0.0),
            ("uint", 0.0),
        ]);
        b.row(&[("ushort", 2.0), ("double", 1e300), ("double", -1e-300)]);
        let c = parse(&b.bytes()).unwrap_or_else(|e| panic!("{enc:?}: {e}"));
        // double 0.1 is stored as the nearest f32.
        assert_eq!(
            c.positions_m,
            vec![[0.1f64 as f32, -2.5, -3.0], [1.0, 0.25, 32767.0]],
            "{enc:?}"
        );
        assert_eq!(
            c.labels,
            vec![Label::from(Class::UpperLegs), Label::BACKGROUND]
        );
        // Float colours are 0..=1, scaled by 255 (0.5 → 127.5 → 128).
        assert_eq!(c.colors, Some(vec![[255, 17, 128], [0, 0, 255]]), "{enc:?}");
        assert_eq!(
            c.origins,
            vec![
                PointOrigin {
                    camera: 3,
                    pixel: u32::MAX
                },
                PointOrigin {
                    camera: 0,
                    pixel: 0
                }
            ],
            "{enc:?}"
        );
    }
}

#[test]
fn big_endian_file_reads() {
    let header = "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n\
                  property uchar label\nproperty uchar camera\nproperty uint pixel\n";
    let mut b = PlyBuilder::new(Enc::Be, header);
    b.xyz_row(
        [1.5, -2.0, 0.75],
        &[("uchar", 4.0), ("uchar", 2.0), ("uint", 0x0102_0304 as f64)],
    );
    b.xyz_row(
        [0.0, 0.0, 1.0],
        &[("uchar", 255.0), ("uchar", 1.0), ("uint", 7.0)],
    );
    let bytes = b.bytes();
    // Big-endian float 1.5 is 3F C0 00 00.
    assert_eq!(
        bytes[b.header_len()..b.header_len() + 4],
        [0x3F, 0xC0, 0, 0]
    );
    let c = parse(&bytes).expect("parse");
    assert_eq!(c.positions_m, vec![[1.5, -2.0, 0.75], [0.0, 0.0, 1.0]]);
    assert_eq!(
        c.labels,
        vec![Label::from(Class::LowerArms), Label::UNKNOWN]
    );
    assert_eq!(
        c.origins,
        vec![
            PointOrigin {
                camera: 2,
                pixel: 0x0102_0304
            },
            PointOrigin {
                camera: 1,
                pixel: 7
            }
        ]
    );
    assert_eq!(c.colors, None);
}

#[test]
fn vertex_element_with_a_list_property_is_walked() {
    let header = "element vertex 2\nproperty float x\nproperty list uchar float normals\n\
                  property float y\nproperty float z\nproperty uchar label\n";
    for enc in Enc::ALL {
        let mut b = PlyBuilder::new(enc, header);
        b.row(&[
            ("float", 1.0),
            ("uchar", 2.0),
            ("float", 9.0),
            ("float", 9.0),
            ("float", 2.0),
            ("float", 3.0),
            ("uchar", 1.0),
        ]);
        b.row(&[
            ("float", 4.0),
            ("uchar", 0.0),
            ("float", 5.0),
            ("float", 6.0),
            ("uchar", 2.0),
        ]);
        let c = parse(&b.bytes()).unwrap_or_else(|e| panic!("{enc:?}: {e}"));
        assert_eq!(
            c.positions_m,
            vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]],
            "{enc:?}"
        );
        assert_eq!(
            c.labels,
            vec![Label::from(Class::Head), Label::from(Class::Torso)]
        );
    }
}

#[test]
fn missing_label_property_is_an_error_naming_the_file() {
    let text = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                property float z\nproperty uchar red\nend_header\n0 0 0 1\n";
    let err = parse(text.as_bytes()).expect_err("no label");
    assert!(
        matches!(&err, IoError::MissingProperty { property, .. } if property == "label"),
        "{err}"
    );
    assert_eq!(
        err.to_string(),
        "test.ply: PLY vertex element has no 'label' property"
    );
    let no_vertex = "ply\nformat ascii 1.0\nelement face 0\nend_header\n";
    assert!(matches!(
        parse(no_vertex.as_bytes()),
        Err(IoError::MissingElement { .. })
    ));
}

#[test]
fn label_out_of_range_is_an_error_naming_the_vertex() {
    for enc in Enc::ALL {
        let b = PlyBuilder::labels_at_origin(enc, "uchar", &[0.0, 6.0, 17.0]);
        let err = parse(&b.bytes()).expect_err("label 17");
        assert!(
            matches!(&err, IoError::ForeignLabels { index: 2, value, .. } if value == "17"),
            "{enc:?}: {err}"
        );
        assert!(
            err.to_string().starts_with(
                "test.ply: vertex 2: label is 17, not a bodyseg class id (0..=6, 255 = unknown)"
            ),
            "{err}"
        );
        assert!(err.to_string().contains("--mode geometry"), "{err}");
    }
}

#[test]
fn other_bad_values_are_errors() {
    // (z type, z value, label type, label value, the property the error names)
    let cases = [
        ("float", 0.0, "float", 2.5, "label"),
        ("float", 0.0, "char", -1.0, "label"),
        ("float", 0.0, "int", 256.0, "label"),
        ("double", 1e300, "uchar", 0.0, "z"), // beyond f32
    ];
    for (z_ty, z, label_ty, label, name) in cases {
        for enc in Enc::ALL {
            let header = format!(
                "element vertex 2\nproperty float x\nproperty float y\nproperty {z_ty} z\n\
                 property {label_ty} label\n"
            );
            let mut b = PlyBuilder::new(enc, &header);
            b.row(&[("float", 0.0), ("float", 0.0), (z_ty, 0.0), (label_ty, 0.0)]);
            b.row(&[("float", 0.0), ("float", 0.0), (z_ty, z), (label_ty, label)]);
            let err = parse(&b.bytes()).expect_err("bad value");
            // A label that is no class id is another tool's id (ForeignLabels), a
            // coordinate out of range a bad value.
            let named = match &err {
                IoError::BadValue {
                    index: 1, property, ..
                } => property.as_str(),
                IoError::ForeignLabels { index: 1, .. } => "label",
                _ => "",
            };
            assert_eq!(named, name, "{enc:?} {name}: {err}");
        }
    }
    // ASCII-only: tokens that are not numbers of the declared type, wrong value counts.
    let base = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
                property float z\nproperty uchar label\nend_header\n";
    for (data, want_line_error) in [
        ("0 0 zero 1\n", false),
        ("0 0 0 1.0\n", false),
        ("0 0 0 300\n", false),
        ("0 0 0\n", true),
        ("0 0 0 1 1\n", true),
    ] {
        let err = parse(format!("{base}{data}").as_bytes()).expect_err(data);
        match err {
            IoError::BadAsciiLine { line, .. } => {
                assert!(want_line_error, "{data:?}");
                assert_eq!(line, 9);
            }
            IoError::BadValue { .. } => assert!(!want_line_error, "{data:?}"),
            other => panic!("{data:?}: {other}"),
        }
    }
}

#[test]
fn header_errors() {
    assert!(matches!(
        parse(b"{\"frame\": 1}"),
        Err(IoError::NotPly { .. })
    ));
    assert!(matches!(parse(b""), Err(IoError::NotPly { .. })));
    assert!(matches!(
        parse(b"ply\nformat binary_middle_endian 1.0\nend_header\n"),
        Err(IoError::UnsupportedFormat { .. })
    ));
    assert!(matches!(
        parse(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n"),
        Err(IoError::UnterminatedHeader { .. })
    ));
    assert!(matches!(
        parse(b"ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n"),
        Err(IoError::BadHeader { line: 3, .. })
    ));
    let missing = Path::new("/nonexistent/dir/x.ply");
    let err = read_ply(missing).expect_err("no file");
    assert!(matches!(err, IoError::Read { .. }), "{err}");
    assert!(
        err.to_string()
            .starts_with("/nonexistent/dir/x.ply: cannot read")
    );
}

#[test]
fn huge_declared_counts_are_truncation_not_allocation() {
    for enc in Enc::ALL {
        let header = "element vertex 1000000000000000\nproperty float x\nproperty float y\n\
                      property float z\nproperty uchar label\n";
        let mut b = PlyBuilder::new(enc, header);
        b.xyz_row([0.0, 0.0, 0.0], &[("uchar", 1.0)]);
        let err = parse(&b.bytes()).expect_err("truncated");
        assert!(
            matches!(
                err,
                IoError::Truncated {
                    expected: 1_000_000_000_000_000,
                    read: 1,
                    ..
                }
            ),
            "{enc:?}: {err}"
        );
    }
    // A list claiming 2³²−1 items.
    let header = "element vertex 1\nproperty float x\nproperty float y\nproperty float z\n\
                  property uchar label\nelement face 1\nproperty list uint int idx\n";
    let mut b = PlyBuilder::new(Enc::Le, header);
    b.xyz_row([0.0, 0.0, 0.0], &[("uchar", 1.0)]);
    b.row(&[("uint", u32::MAX as f64), ("int", 1.0)]);
    assert!(matches!(
        parse(&b.bytes()),
        Err(IoError::Truncated { read: 0, .. })
    ));
    // A negative list count.
    let header = "element face 1\nproperty list char int idx\nelement vertex 0\n\
                  property float x\nproperty float y\nproperty float z\nproperty uchar label\n";
    for enc in Enc::ALL {
        let mut b = PlyBuilder::new(enc, header);
        b.row(&[("char", -1.0)]);
        let err = parse(&b.bytes()).expect_err("negative count");
        assert!(matches!(err, IoError::BadValue { .. }), "{enc:?}: {err}");
    }
}

/// A small file of each encoding, with a face element before and after the vertices.
fn small_file(enc: Enc) -> (Vec<u8>, usize) {
    let header = "comment small\nelement face 1\nproperty list uchar int vertex_indices\n\
                  element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                  property uchar red\nproperty uchar green\nproperty uchar blue\n\
                  property uchar label\nproperty uchar camera\nproperty uint pixel\n\
                  element tail 2\nproperty list uchar uchar bytes\n";
    let mut b = PlyBuilder::new(enc, header);
    b.row(&[("uchar", 3.0), ("int", 0.0), ("int", 1.0), ("int", 2.0)]);
    for i in 0..3 {
        let f = i as f64;
        b.xyz_row(
            [0.125 + f, -1.5 * f, 1000.0 + f],
            &[
                ("uchar", 10.0),
                ("uchar", 20.0),
                ("uchar", 30.0),
                ("uchar", f + 1.0),
                ("uchar", f),
                ("uint", 12345.0 * f),
            ],
        );
    }
    b.row(&[("uchar", 1.0), ("uchar", 9.0)]);
    b.row(&[("uchar", 0.0)]);
    (b.bytes(), b.header_len())
}

#[test]
fn every_proper_prefix_is_an_error() {
    for enc in Enc::ALL {
        let (bytes, header_len) = small_file(enc);
        let full = parse(&bytes).unwrap_or_else(|e| panic!("{enc:?} full file: {e}"));
        assert_eq!(full.len(), 3);
        assert_eq!(
            full.origins[2],
            PointOrigin {
                camera: 2,
                pixel: 24690
            }
        );
        for cut in 0..bytes.len() {
            let result = parse(&bytes[..cut]);
            let err = match result {
                Ok(c) => panic!(
                    "{enc:?}: prefix of {cut}/{} bytes parsed: {c:?}",
                    bytes.len()
                ),
                Err(e) => e,
            };
            if cut >= header_len {
                // Cut into the data: a truncation naming what is missing.
                match err {
                    IoError::Truncated { expected, read, .. } => {
                        assert!(read < expected, "{enc:?} cut {cut}: {read} / {expected}")
                    }
                    other => panic!("{enc:?} cut {cut}: {other}"),
                }
            }
        }
    }
}

#[test]
fn truncation_message_says_expected_and_read() {
    let (bytes, header_len) = small_file(Enc::Le);
    // The face (1 + 3 × 4 bytes) and one full vertex (21 bytes) plus a few bytes.
    let err = parse(&bytes[..header_len + 13 + 21 + 5]).expect_err("cut");
    assert_eq!(
        err.to_string(),
        "test.ply: truncated PLY: header declares 3 vertex entries, data holds only 1"
    );
}
