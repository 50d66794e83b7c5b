//! Issue 6's report on stored clouds: the box study's frames are rendered and projected once
//! into a cache folder, then the finder is scored on them as often as it is changed (the
//! render and projection are ≈ 10× the finder's time).
//!
//! `cargo run --release -p bodyseg-lab --example boxes_cache write DIR PRESET FIRST_SEED
//! SEEDS [FRAMES]` renders seeds FIRST_SEED.. (FRAMES frames 4 apart, default 25) into DIR
//! (≈ 5.6 MB a `robot_cell` frame); `... boxes_cache score DIR PRESET FIRST_SEED SEEDS
//! [MODE]` scores MODE (`geometry`, default, or `labels`) on them as `boxes_report` does
//! (the same figures: 100 frames in ≈ 2 s instead of ≈ 60 s) and lists the bad frames;
//! `... boxes_cache show DIR PRESET SEED FRAME` describes one frame's true and found boxes
//! (geometry mode; `RUST_LOG=bodyseg_people=trace` for the head candidates) and draws them
//! over a top view, true left, found right, into DIR/show.png.
//! A cached frame is its cloud's positions (f32), labels and colours, raw little-endian,
//! and its true boxes as JSON. A frame file of the wrong size is an error.

mod common;

use anyhow::{Context, Result, bail};
use bodyseg_core::{Label, LabeledCloud, PersonBoxes, PointOrigin};
use bodyseg_lab::{BoxStats, describe_box as describe, match_boxes, study_frame};
use bodyseg_people::{BoxMode, BoxesConfig, find_boxes};
use bodyseg_project::FrameProjector;
use bodyseg_synth::{Synth, preset};
use rayon::prelude::*;
use std::path::{Path, PathBuf};

fn frame_path(dir: &Path, name: &str, seed: u64, index: usize) -> PathBuf {
    dir.join(format!("{name}_{seed}_{index:03}"))
}

fn write_frame(path: &Path, cloud: &LabeledCloud, truth: &PersonBoxes) -> Result<()> {
    let n = cloud.len();
    let mut bytes = Vec::with_capacity(8 + n * 16);
    bytes.extend_from_slice(&(n as u64).to_le_bytes());
    for p in &cloud.positions_m {
        for c in p {
            bytes.extend_from_slice(&c.to_le_bytes());
        }
    }
    bytes.extend(cloud.labels.iter().map(|l| l.id()));
    let colors = cloud.colors.as_deref().context("a coloured cloud")?;
    bytes.extend(colors.iter().flatten());
    std::fs::write(path.with_extension("bin"), bytes)?;
    std::fs::write(path.with_extension("json"), serde_json::to_vec(truth)?)?;
    Ok(())
}

fn read_frame(path: &Path) -> Result<(LabeledCloud, PersonBoxes)> {
    let bytes =
        std::fs::read(path.with_extension("bin")).with_context(|| format!("{}", path.display()))?;
    let Some(head) = bytes.get(..8) else {
        bail!("{}: {} bytes, no point count", path.display(), bytes.len());
    };
    let n = u64::from_le_bytes(head.try_into()?) as usize;
    // 8 bytes of count, then 12 of position, 1 of label and 3 of colour per point.
    if n.checked_mul(16).and_then(|b| b.checked_add(8)) != Some(bytes.len()) {
        bail!("{}: {} bytes for {n} points", path.display(), bytes.len());
    }
    let (pos, rest) = bytes[8..].split_at(12 * n);
    let (labels, colors) = rest.split_at(n);
    let f = |b: &[u8]| f32::from_le_bytes(b.try_into().expect("4 bytes"));
    let positions_m = pos
        .chunks_exact(12)
        .map(|c| [f(&c[0..4]), f(&c[4..8]), f(&c[8..12])])
        .collect();
    let labels = labels
        .iter()
        .map(|&l| Label::from_id_or_unknown(l))
        .collect();
    let colors = colors.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    let cloud = LabeledCloud {
        positions_m,
        labels,
        colors: Some(colors),
        origins: (0..n as u32)
            .map(|pixel| PointOrigin { camera: 0, pixel })
            .collect(),
    };
    let truth = serde_json::from_slice(&std::fs::read(path.with_extension("json"))?)?;
    Ok((cloud, truth))
}

fn main() -> Result<()> {
    common::init_logging();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [verb, dir, name, first, count, rest @ ..] = args.as_slice() else {
        bail!("usage: boxes_cache write|score DIR PRESET FIRST_SEED SEEDS [FRAMES|MODE]");
    };
    let dir = Path::new(dir);
    let first: u64 = first.parse()?;
    let count: u64 = count.parse()?;
    let seeds: Vec<u64> = (first..first + count).collect();
    match verb.as_str() {
        "write" => {
            let frames: usize = rest.first().map_or(Ok(25), |s| s.parse())?;
            std::fs::create_dir_all(dir)?;
            seeds.par_iter().try_for_each(|&seed| -> Result<()> {
                let synth = Synth::new(preset(name)?, seed)?;
                let projector = FrameProjector::new(synth.written_rig())?;
                for index in (0..frames).map(|i| i * 4) {
                    let (frame, cloud) = study_frame(&synth, &projector, index)?;
                    write_frame(&frame_path(dir, name, seed, index), &cloud, &frame.boxes)?;
                }
                eprintln!("seed {seed} written");
                Ok(())
            })
        }
        "score" => {
            let mode = match rest.first().map(String::as_str) {
                None | Some("geometry") => BoxMode::Geometry,
                Some("labels") => BoxMode::Labels,
                Some(other) => bail!("mode {other}: geometry or labels"),
            };
            let cfg = BoxesConfig {
                mode,
                ..BoxesConfig::default()
            };
            let mut paths = Vec::new();
            for &seed in &seeds {
                for index in (0..).map(|i| i * 4) {
                    let p = frame_path(dir, name, seed, index);
                    if !p.with_extension("bin").exists() {
                        break;
                    }
                    paths.push((seed, index, p));
                }
            }
            let stats: Vec<(u64, usize, BoxStats)> = paths
                .par_iter()
                .map(|(seed, index, p)| -> Result<_> {
                    let (cloud, truth) = read_frame(p)?;
                    let found = find_boxes(&cloud, &cfg)?;
                    let mut s = BoxStats::default();
                    s.add_frame(*index, &match_boxes(&truth.boxes, &found.boxes));
                    Ok((*seed, *index, s))
                })
                .collect::<Result<_>>()?;
            let mut total = BoxStats::default();
            for (seed, _, s) in &stats {
                total.absorb(s, *seed as usize * 10_000);
            }
            println!(
                "{name} {} seeds {first}..{}: {} frames, good {:.1}%, people {}, matched {}, boxes {}, mean best IoU {:.3}",
                mode.name(),
                first + count - 1,
                total.frames,
                100.0 * total.good_fraction(),
                total.people,
                total.matched,
                total.found,
                total.mean_iou()
            );
            println!("bad: {:?}", total.bad_frames);
            Ok(())
        }
        "show" => {
            // boxes_cache show DIR PRESET SEED FRAME: true and found boxes (geometry), and a
            // top view with the true boxes (left) and the found ones (right) in DIR/show.png.
            let path = frame_path(dir, name, first, count as usize);
            let (cloud, truth) = read_frame(&path)?;
            let cfg = BoxesConfig {
                mode: BoxMode::Geometry,
                ..BoxesConfig::default()
            };
            let found = find_boxes(&cloud, &cfg)?;
            let m = match_boxes(&truth.boxes, &found.boxes);
            for b in &truth.boxes {
                println!("true  {}", describe(b));
            }
            for b in &found.boxes {
                let iou: Vec<String> = truth
                    .boxes
                    .iter()
                    .map(|t| format!("{:.2}", bodyseg_people::box_iou(t, b)))
                    .collect();
                println!("found {} iou {}", describe(b), iou.join(" "));
            }
            println!("good {}", m.is_good());
            let (w, h, left) = bodyseg_pipeline::top_view(&cloud, &truth.boxes);
            let (w2, h2, right) = bodyseg_pipeline::top_view(&cloud, &found.boxes);
            if (w, h) == (w2, h2) {
                let mut rgb = Vec::with_capacity(left.len() * 2);
                for row in 0..h as usize {
                    let r = 3 * w as usize;
                    rgb.extend_from_slice(&left[row * r..(row + 1) * r]);
                    rgb.extend_from_slice(&right[row * r..(row + 1) * r]);
                }
                bodyseg_io::write_rgb_png(&dir.join("show.png"), 2 * w, h, &rgb)?;
            }
            Ok(())
        }
        other => bail!("{other}: write, score or show"),
    }
}
