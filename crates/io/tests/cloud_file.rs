//! Cloud files read as they are ([`bodyseg_io::CloudFile`]): without labels, with another
//! tool's label ids, organised (PCD `HEIGHT`, PCL's organised PLY with `range_grid`).

mod common;

use bodyseg_core::Label;
use bodyseg_io::{CloudGrid, FileLabels, IoError, parse_pcd_file, parse_ply_file, read_cloud_file};
use common::{Enc, PlyBuilder};
use std::path::Path;

const P: &str = "test.ply";

#[test]
fn a_ply_without_label_reads_unlabelled() {
    let header = "element vertex 2\nproperty float x\nproperty float y\nproperty float z\n\
                  property uchar red\nproperty uchar green\nproperty uchar blue\n";
    for enc in Enc::ALL {
        let mut b = PlyBuilder::new(enc, header);
        b.xyz_rgb_rows(2, |k| ([k, 1.0, 2.0], [10.0, 20.0, 30.0]));
        let file = parse_ply_file(&b.bytes(), Path::new(P)).expect("no label is fine");
        assert_eq!(file.labels, FileLabels::Absent, "{enc:?}");
        assert_eq!(file.cloud.labels, vec![Label::UNKNOWN; 2]);
        assert_eq!(file.cloud.positions_m[1], [1.0, 1.0, 2.0]);
        assert_eq!(file.cloud.colors, Some(vec![[10, 20, 30]; 2]));
        assert_eq!(file.grid, None);
    }
}

#[test]
fn another_tools_label_ids_read_as_foreign_and_all_unknown() {
    // PCL's PointXYZRGBL writes `uint label` segment ids: 0, 3, 40.
    for enc in Enc::ALL {
        let b = PlyBuilder::labels_at_origin(enc, "uint", &[0.0, 3.0, 40.0]);
        let file = parse_ply_file(&b.bytes(), Path::new(P)).expect("foreign ids");
        assert_eq!(
            file.labels,
            FileLabels::Foreign {
                index: 2,
                value: "40".into()
            },
            "{enc:?}"
        );
        // A segment id 3 is no upper arm: every label unknown.
        assert_eq!(file.cloud.labels, vec![Label::UNKNOWN; 3], "{enc:?}");
    }
    // The fast path (uchar labels) too.
    let b = PlyBuilder::labels_at_origin(Enc::Le, "uchar", &[2.0, 9.0]);
    let file = parse_ply_file(&b.bytes(), Path::new(P)).expect("foreign ids");
    assert_eq!(
        file.labels,
        FileLabels::Foreign {
            index: 1,
            value: "9".into()
        }
    );
    assert_eq!(file.cloud.labels, vec![Label::UNKNOWN; 2]);
    // Where labels are needed: refused, naming the vertex and the fix.
    let e = file
        .into_class_labels("vertex", Path::new(P))
        .expect_err("foreign");
    assert!(matches!(e, IoError::ForeignLabels { index: 1, .. }), "{e}");
    assert!(
        e.to_string().contains("bodyseg boxes --mode geometry"),
        "{e}"
    );
}

#[test]
fn a_pcl_organised_ply_keeps_its_grid_through_the_range_grid() {
    // 3×2 grid, cells 1 and 4 invalid (no vertex): 4 vertices, range_grid of 6 cells.
    let header = "obj_info num_cols 3\nobj_info num_rows 2\nelement vertex 4\n\
                  property float x\nproperty float y\nproperty float z\n\
                  property uchar red\nproperty uchar green\nproperty uchar blue\n\
                  element face 0\nproperty list uchar int vertex_indices\n\
                  element range_grid 6\nproperty list uchar int vertex_indices\n";
    for enc in Enc::ALL {
        let mut b = PlyBuilder::new(enc, header);
        b.xyz_rgb_rows(4, |k| ([k, 0.0, 1.0], [10.0 * k, 0.0, 0.0]));
        for cell in [Some(0.0), None, Some(1.0), Some(2.0), None, Some(3.0)] {
            match cell {
                Some(v) => b.row(&[("uchar", 1.0), ("int", v)]),
                None => b.row(&[("uchar", 0.0)]),
            };
        }
        let file = parse_ply_file(&b.bytes(), Path::new(P)).expect("organised PLY");
        let pixels: Vec<u32> = file.cloud.origins.iter().map(|o| o.pixel).collect();
        assert_eq!(pixels, vec![0, 2, 3, 5], "{enc:?}");
        assert_eq!(
            file.grid,
            Some(CloudGrid {
                width: 3,
                height: 2,
                colors: Some(vec![
                    [0, 0, 0],
                    [0, 0, 0],
                    [10, 0, 0],
                    [20, 0, 0],
                    [0, 0, 0],
                    [30, 0, 0]
                ]),
            }),
            "{enc:?}"
        );
    }
    // num_cols × num_rows vertices without a range_grid: row-major as they come.
    let header = "obj_info num_cols 2\nobj_info num_rows 2\nelement vertex 4\n\
                  property float x\nproperty float y\nproperty float z\n";
    let mut b = PlyBuilder::new(Enc::Ascii, header);
    for _ in 0..4 {
        b.row(&[("float", 0.0), ("float", 0.0), ("float", 1.0)]);
    }
    let file = parse_ply_file(&b.bytes(), Path::new(P)).expect("organised PLY");
    assert_eq!(file.grid.map(|g| (g.width, g.height)), Some((2, 2)));
    // ... another count: no grid (the vertices cannot be placed).
    let header = "obj_info num_cols 2\nobj_info num_rows 3\nelement vertex 4\n\
                  property float x\nproperty float y\nproperty float z\n";
    let mut b = PlyBuilder::new(Enc::Ascii, header);
    for _ in 0..4 {
        b.row(&[("float", 0.0), ("float", 0.0), ("float", 1.0)]);
    }
    assert_eq!(
        parse_ply_file(&b.bytes(), Path::new(P))
            .expect("a plain cloud")
            .grid,
        None
    );
}

#[test]
fn a_range_grid_cut_short_is_a_truncation() {
    let header = "obj_info num_cols 2\nobj_info num_rows 1\nelement vertex 1\n\
                  property float x\nproperty float y\nproperty float z\n\
                  element range_grid 2\nproperty list uchar int vertex_indices\n";
    let mut b = PlyBuilder::new(Enc::Le, header);
    b.row(&[("float", 0.0), ("float", 0.0), ("float", 1.0)]);
    b.row(&[("uchar", 1.0), ("int", 0.0)]);
    b.row(&[("uchar", 5.0)]); // claims 5 items, holds none
    let e = parse_ply_file(&b.bytes(), Path::new(P)).expect_err("cut");
    assert!(
        matches!(&e, IoError::Truncated { element, read: 1, .. } if element == "range_grid"),
        "{e}"
    );
}

/// A PCD of `w`×`h` points x y z rgb label, ASCII; `nan` cells have NaN coordinates.
fn pcd(w: usize, h: usize, labels: &[u32], nan: &[usize]) -> Vec<u8> {
    let mut text = format!(
        "VERSION 0.7\nFIELDS x y z rgb label\nSIZE 4 4 4 4 4\nTYPE F F F U U\nCOUNT 1 1 1 1 1\n\
         WIDTH {w}\nHEIGHT {h}\nPOINTS {}\nDATA ascii\n",
        w * h
    );
    for i in 0..w * h {
        let xyz = if nan.contains(&i) {
            "nan nan nan".to_string()
        } else {
            format!("{i} 0 1")
        };
        text.push_str(&format!(
            "{xyz} {} {}\n",
            0x0A_0000 * (i as u32 + 1),
            labels[i]
        ));
    }
    text.into_bytes()
}

#[test]
fn a_pcd_with_segment_ids_or_a_grid() {
    let path = Path::new("x.pcd");
    // Class ids: read as they are; organised 2×2 with one NaN point.
    let file = parse_pcd_file(&pcd(2, 2, &[1, 2, 255, 0], &[1]), path).expect("pcd");
    assert_eq!(file.labels, FileLabels::Classes);
    assert_eq!(file.cloud.len(), 3);
    let pixels: Vec<u32> = file.cloud.origins.iter().map(|o| o.pixel).collect();
    assert_eq!(pixels, vec![0, 2, 3]);
    // The grid keeps the NaN point's colour.
    let grid = file.grid.expect("organised");
    assert_eq!((grid.width, grid.height), (2, 2));
    assert_eq!(
        grid.colors,
        Some(vec![[10, 0, 0], [20, 0, 0], [30, 0, 0], [40, 0, 0]])
    );
    // PCL's segment ids: foreign, all unknown; unorganised (HEIGHT 1): no grid.
    let file = parse_pcd_file(&pcd(4, 1, &[0, 3, 40, 3], &[]), path).expect("pcd");
    assert_eq!(
        file.labels,
        FileLabels::Foreign {
            index: 2,
            value: "40".into()
        }
    );
    assert_eq!(file.cloud.labels, vec![Label::UNKNOWN; 4]);
    assert_eq!(file.grid, None);
}

#[test]
fn cloud_files_are_read_by_extension() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("c.PCD");
    std::fs::write(&path, pcd(2, 1, &[1, 1], &[])).expect("write");
    assert_eq!(read_cloud_file(&path).expect("pcd").cloud.len(), 2);
    let e = read_cloud_file(&dir.path().join("c.xyz")).expect_err("unknown");
    assert!(e.to_string().contains("give a .ply or .pcd file"), "{e}");
}
