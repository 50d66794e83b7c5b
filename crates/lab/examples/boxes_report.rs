//! Issue 6's report: person boxes found in synthetic recordings of the three presets, per
//! mode (labels with the simulated parser's predicted labels; geometry, labels unused,
//! with the points' colours and without them),
//! against the true boxes: the fraction of frames where every person is matched by
//! exactly one box with 3D IoU ≥ 0.5 (exact oriented-box IoU) and no box is extra.
//!
//! `cargo run --release -p bodyseg-lab --example boxes_report [FRAMES] [SEEDS]
//! [FIRST_SEED]` (default 25 frames × 2 seeds from seed 100 = 50 frames per preset, frames
//! 4 apart: 0.27 s at 15 fps; seeds FIRST_SEED, FIRST_SEED + 1, ...).

use bodyseg_lab::box_stats;
use bodyseg_people::{BoxMode, BoxesConfig};
use bodyseg_synth::{Synth, preset};

/// A row's mode: geometry without colours is the same split on positions only.
fn row_name(cfg: &BoxesConfig) -> String {
    match (cfg.mode, cfg.color_split) {
        (BoxMode::Geometry, false) => "geometry (no colours)".into(),
        (mode, _) => mode.name().into(),
    }
}

fn main() -> anyhow::Result<()> {
    let mut args = std::env::args().skip(1);
    let frames: usize = args.next().and_then(|n| n.parse().ok()).unwrap_or(25);
    let seeds: u64 = args.next().and_then(|n| n.parse().ok()).unwrap_or(2);
    let first_seed: u64 = args.next().and_then(|n| n.parse().ok()).unwrap_or(100);
    let indices: Vec<usize> = (0..frames).map(|i| i * 4).collect();
    let configs = [
        BoxesConfig::default(),
        BoxesConfig {
            mode: BoxMode::Geometry,
            ..BoxesConfig::default()
        },
        BoxesConfig {
            mode: BoxMode::Geometry,
            color_split: false,
            ..BoxesConfig::default()
        },
    ];
    println!("| preset | mode | frames | good frames | people | matched | boxes | mean best IoU |");
    println!("|---|---|---:|---:|---:|---:|---:|---:|");
    for name in ["single", "handover", "robot_cell"] {
        let mut totals = vec![bodyseg_lab::BoxStats::default(); configs.len()];
        for seed in first_seed..first_seed + seeds {
            let synth = Synth::new(preset(name)?, seed)?;
            for (t, s) in totals
                .iter_mut()
                .zip(&box_stats(&synth, &indices, &configs)?)
            {
                t.absorb(s, seed as usize * 10_000);
            }
        }
        for (cfg, s) in configs.iter().zip(&totals) {
            println!(
                "| {name} | {} | {} | {:.1}% | {} | {} | {} | {:.3} |",
                row_name(cfg),
                s.frames,
                100.0 * s.good_fraction(),
                s.people,
                s.matched,
                s.found,
                s.mean_iou()
            );
            if !s.bad_frames.is_empty() {
                eprintln!(
                    "{name} {}: bad (seed*10000+frame) {:?}",
                    row_name(cfg),
                    s.bad_frames
                );
            }
        }
    }
    Ok(())
}
