//! Writes the input of the geometry-mode PCD fixture (`scripts/gen_pcd_fixtures.py`
//! turns it into an organised `binary_compressed` PCD): frame 6 of the handover preset
//! (seed 3), its three depth cameras back-projected every 4th pixel (world frame), points
//! outside the people's workspace (|x|, |y| > 1.8 m: walls) dropped, as ASCII PLY with
//! each point's camera and pixel; and the frame's true boxes as JSON.
//!
//! `cargo run --release -p bodyseg-lab --example pcd_scene -- OUT.ply OUT_BOXES.json`

use anyhow::Context;
use bodyseg_calib::{BackProjectOptions, CloudFrame};
use bodyseg_core::{Label, LabeledCloud, PointOrigin};
use bodyseg_io::{PlyFormat, PlyWriteOptions, write_boxes, write_ply};
use bodyseg_synth::{Synth, preset};
use std::path::PathBuf;

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let ply = PathBuf::from(args.next().context("usage: pcd_scene OUT.ply OUT.json")?);
    let json = PathBuf::from(args.next().context("usage: pcd_scene OUT.ply OUT.json")?);
    let synth = Synth::new(preset("handover")?, 3)?;
    let frame = synth.frame(6);
    let rig = synth.written_rig();
    let opts = BackProjectOptions {
        stride: 4,
        frame: CloudFrame::World,
        ..BackProjectOptions::default()
    };
    let mut cloud = LabeledCloud::default();
    for (c, (camera, images)) in rig.cameras.iter().zip(&frame.cameras).enumerate() {
        let points = bodyseg_calib::DepthBackProjector::new(camera, c as u8)?
            .back_project(&images.depth_mm, &opts)?;
        for (p, o) in points.points_m.iter().zip(&points.origins) {
            if p[0].abs() > 1.8 || p[1].abs() > 1.8 {
                continue;
            }
            cloud.positions_m.push(*p);
            cloud.labels.push(Label::UNKNOWN);
            cloud.origins.push(PointOrigin {
                camera: c as u8,
                pixel: o.pixel,
            });
        }
    }
    let write = PlyWriteOptions {
        format: PlyFormat::Ascii,
        ..Default::default()
    };
    write_ply(&ply, &cloud, &write)?;
    write_boxes(&json, &frame.boxes)?;
    println!("{} points, {} people", cloud.len(), frame.boxes.boxes.len());
    Ok(())
}
