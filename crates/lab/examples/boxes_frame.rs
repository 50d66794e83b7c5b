//! Describes the boxes of single synthetic frames (issue 6's failures, one at a time): the
//! true boxes, each mode's found boxes and their IoU with the truth.
//!
//! `cargo run --release -p bodyseg-lab --example boxes_frame PRESET SEED FRAME...`
//! (`RUST_LOG=bodyseg_people=trace` for the finder's reasons).

mod common;

use bodyseg_lab::{describe_box as describe, match_boxes, study_frame};
use bodyseg_people::{BoxMode, BoxesConfig, box_iou, find_boxes};
use bodyseg_project::FrameProjector;
use bodyseg_synth::{Synth, preset};

fn main() -> anyhow::Result<()> {
    common::init_logging();
    let mut args = std::env::args().skip(1);
    let name = args.next().unwrap_or_else(|| "handover".into());
    let seed: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(100);
    let frames: Vec<usize> = args.filter_map(|s| s.parse().ok()).collect();
    let synth = Synth::new(preset(&name)?, seed)?;
    let projector = FrameProjector::new(synth.written_rig())?;
    for p in synth.people() {
        println!("person pose {}", p.pose().name());
    }
    for index in frames {
        let (frame, cloud) = study_frame(&synth, &projector, index)?;
        println!("== {name} seed {seed} frame {index}");
        for t in &frame.boxes.boxes {
            println!("  true  {}", describe(t));
        }
        for mode in [BoxMode::Labels, BoxMode::Geometry] {
            let cfg = BoxesConfig {
                mode,
                ..BoxesConfig::default()
            };
            let found = find_boxes(&cloud, &cfg)?;
            let m = match_boxes(&frame.boxes.boxes, &found.boxes);
            println!(
                "  {} good={} matched {}/{} found {}",
                mode.name(),
                m.is_good(),
                m.matched,
                m.people,
                m.found
            );
            for f in &found.boxes {
                let ious: Vec<String> = frame
                    .boxes
                    .boxes
                    .iter()
                    .map(|t| format!("{:.2}", box_iou(t, f)))
                    .collect();
                println!("    found {} iou [{}]", describe(f), ious.join(" "));
            }
        }
    }
    Ok(())
}
