//! Every crash the fuzz targets (`fuzz/`, `scripts/fuzz.sh`) found in this crate's
//! readers, with the input that found it (kept in `fuzz/regressions/<target>/`, which
//! the fuzzer replays first) and a typed minimal case.

use bodyseg_io::{IoError, parse_pcd};
use std::path::Path;

/// The PCD of a fuzz crash: a `z` field of `SIZE 8 TYPE F` holding 4.3e69, finite as
/// f64, read as +inf once stored as f32: the cloud held an infinite coordinate, which
/// [`bodyseg_core::LabeledCloud::validate`] refuses.
#[test]
fn pcd_coordinate_beyond_f32_is_an_error() {
    let found = include_bytes!("../../../fuzz/regressions/pcd/coordinate_beyond_f32.pcd");
    let typed = |data: &str, z: &[u8]| {
        let mut bytes = format!(
            "FIELDS x y z\nSIZE 4 4 8\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA {data}\n"
        )
        .into_bytes();
        bytes.extend_from_slice(z);
        bytes
    };
    let mut binary = Vec::new();
    for z in [1.0f64, 1e300] {
        binary.extend_from_slice(&[0; 8]);
        binary.extend_from_slice(&z.to_le_bytes());
    }
    let cases = [
        (found.to_vec(), ": z is "),
        (typed("binary", &binary), "point 1: z is "),
        (typed("ascii", b"0 0 1\n0 0 1e39\n"), "point 1: z is "),
    ];
    for (bytes, needle) in cases {
        let err = parse_pcd(&bytes, Path::new("far.pcd")).expect_err("an infinite f32");
        assert!(matches!(err, IoError::BadValue { .. }), "{err}");
        let text = err.to_string();
        assert!(text.contains("far.pcd") && text.contains(needle), "{text}");
        assert!(text.contains("f32's range"), "{text}");
    }
    // The largest finite f32 still reads.
    let mut edge = Vec::new();
    edge.extend_from_slice(&[0; 8]);
    edge.extend_from_slice(&f64::from(f32::MAX).to_le_bytes());
    edge.extend_from_slice(&[0; 8]);
    edge.extend_from_slice(&(-f64::from(f32::MAX)).to_le_bytes());
    let cloud = parse_pcd(&typed("binary", &edge), Path::new("edge.pcd")).expect("finite");
    assert_eq!(cloud.positions_m[0][2], f32::MAX);
    assert_eq!(cloud.positions_m[1][2], -f32::MAX);
}
