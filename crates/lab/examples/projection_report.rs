//! Issue 4's report: naive vs DSA label projection on synthetic recordings of the three
//! presets, with and without calibration error, against the exact truth of every depth
//! pixel. The parser is perfect here (predictions = 2D truth), so every wrong point is a
//! depth-segmentation association error.
//!
//! `cargo run --release -p bodyseg-lab --example projection_report [FRAMES]`

use bodyseg_lab::projection_stats;
use bodyseg_project::ProjectConfig;
use bodyseg_synth::{ParserMistakesConfig, Synth, preset};

fn main() -> anyhow::Result<()> {
    let frames: usize = std::env::args()
        .nth(1)
        .and_then(|n| n.parse().ok())
        .unwrap_or(10);
    let indices: Vec<usize> = (0..frames).map(|i| i * 3).collect();
    println!(
        "| preset | calibration error | points | naive wrong | DSA wrong | naive unknown | DSA unknown | DSA correct of labelled | body points | naive wrong (body) | DSA wrong (body) | DSA unknown (body) |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for name in ["single", "handover", "robot_cell"] {
        for calib in [false, true] {
            let mut config = preset(name)?;
            config.parsing = ParserMistakesConfig::none();
            if calib {
                config.dsa.color_from_depth_rotation_deg = 0.5;
                config.dsa.color_from_depth_translation_m = 0.01;
            }
            let synth = Synth::new(config, 11)?;
            let stats = projection_stats(
                &synth,
                &indices,
                &[ProjectConfig::naive(), ProjectConfig::default()],
            )?;
            let (naive, dsa) = (stats[0], stats[1]);
            println!(
                "| {name} | {} | {} | {:.2}% | {:.2}% | {:.2}% | {:.2}% | {:.3}% | {} | {:.2}% | {:.2}% | {:.2}% |",
                if calib { "0.5°, 1 cm" } else { "none" },
                dsa.points,
                100.0 * naive.wrong_fraction(),
                100.0 * dsa.wrong_fraction(),
                100.0 * naive.unknown_fraction(),
                100.0 * dsa.unknown_fraction(),
                100.0 * dsa.labelled_accuracy(),
                dsa.body_points,
                100.0 * naive.body_wrong_fraction(),
                100.0 * dsa.body_wrong_fraction(),
                100.0 * dsa.body_unknown as f64 / dsa.body_points.max(1) as f64,
            );
        }
    }
    Ok(())
}
