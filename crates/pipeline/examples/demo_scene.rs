//! Writes a synthetic demo scene for `bodyseg refine` and `bodyseg eval` (scripts/demo.sh):
//! seeded human-shaped people with the label errors of 2D parsing + projection.
//!
//! ```text
//! cargo run --release -p bodyseg-pipeline --example demo_scene -- \
//!     --out demo_out --points 100000 --people 2 --seed 1
//! ```
//! Files in the output folder: `in.ply` (predicted labels, with errors), `gt.ply` (the same
//! points with their true labels), `boxes.json` (one box per person).

use bodyseg_core::{PersonBox, PersonBoxes};
use bodyseg_io::{PlyWriteOptions, write_boxes, write_ply};
use bodyseg_testkit::{concat, people_cloud};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut out = PathBuf::from("demo_out");
    let mut points = 100_000usize;
    let mut people = 1usize;
    let mut seed = 1u64;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "--out" => out = value()?.into(),
            "--points" => points = value()?.parse()?,
            "--people" => people = value()?.parse()?,
            "--seed" => seed = value()?.parse()?,
            "-h" | "--help" => {
                println!("demo_scene [--out DIR] [--points N per person] [--people K] [--seed S]");
                return Ok(());
            }
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    if people == 0 {
        return Err("--people must be at least 1".into());
    }
    std::fs::create_dir_all(&out)?;
    let persons = people_cloud(points, people, seed);
    let (cloud, truth) = concat(&persons);
    let boxes = PersonBoxes {
        frame: format!("demo_seed{seed}"),
        boxes: persons
            .iter()
            .enumerate()
            .map(|(i, p)| PersonBox {
                id: i as u32,
                ..p.person_box.clone()
            })
            .collect(),
    };
    let opts = PlyWriteOptions::default();
    write_ply(&out.join("in.ply"), &cloud, &opts)?;
    write_ply(&out.join("gt.ply"), &cloud.with_labels(truth), &opts)?;
    write_boxes(&out.join("boxes.json"), &boxes)?;
    println!(
        "wrote {} points of {people} people to {}: in.ply, gt.ply, boxes.json",
        cloud.len(),
        out.display()
    );
    Ok(())
}
