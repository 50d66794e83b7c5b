//! Writes a seeded human-shaped cloud to disk, clusters it with our DBSCAN and with the
//! whole refinement, and prints the timings as one JSON line. Used by
//! `scripts/bench_dbscan_peers.py`, which runs the peers on the same files in the same run.
//!
//! ```text
//! cargo run --release -p bodyseg-refine --example dbscan_cloud -- \
//!     --cloud synth --points 100000 --seed 1 --eps 0.05 --min-points 40 --repeat 5 --out DIR
//! ```
//! `--cloud synth` (default): the sensor-like cloud of `bodyseg-synth` the criterion benches
//! use (`benches/common/synth_cloud.rs`: Kinect-v2-like views, flying pixels, the parser's
//! label errors); `--cloud testkit`: the capsule cloud of `bodyseg-testkit`.
//! Files in DIR: `points.f32` (n×3 little-endian f32, metres), `labels.u8` (class ids,
//! 255 = unknown), `ours_clusters.i32` (cluster id per point, −1 = noise),
//! `ours_core.u8` (1 = core point).

/// The same allocator as the `bodyseg` binary.
#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

use bodyseg_refine::{DbscanParams, RefineConfig, dbscan, refine};
use bodyseg_testkit::human_cloud;

#[path = "../benches/common/synth_cloud.rs"]
mod synth_cloud;

#[path = "../benches/common/alloc.rs"]
mod alloc;
use std::io::Write;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // As `bodyseg refine` runs (crates/cli/main.rs).
    alloc::keep_freed_memory();
    let mut points = 100_000usize;
    let mut seed = 1u64;
    let mut eps = 0.05f32;
    let mut min_points = 40usize;
    let mut repeat = 5usize;
    let mut out = std::path::PathBuf::from("target/dbscan_cloud");
    let mut kind = String::from("synth");
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut v = || args.next().ok_or_else(|| format!("{a} needs a value"));
        match a.as_str() {
            "--points" => points = v()?.parse()?,
            "--seed" => seed = v()?.parse()?,
            "--eps" => eps = v()?.parse()?,
            "--min-points" => min_points = v()?.parse()?,
            "--repeat" => repeat = v()?.parse()?,
            "--out" => out = v()?.into(),
            "--cloud" => kind = v()?,
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    std::fs::create_dir_all(&out)?;
    // (cloud, box, cameras, flying pixels, labels unlike the truth)
    let (cloud, person_box, cameras, flying, mislabelled) = match kind.as_str() {
        "synth" => {
            let p = synth_cloud::synth_person_cloud(points, seed)?;
            (p.cloud, p.person_box, p.cameras, p.flying, p.mislabelled)
        }
        "testkit" => {
            let p = human_cloud(points, seed);
            let wrong = p
                .cloud
                .labels
                .iter()
                .zip(&p.truth)
                .filter(|(a, b)| a != b)
                .count();
            (p.cloud, p.person_box, 0, 0, wrong)
        }
        other => return Err(format!("unknown --cloud {other} (synth or testkit)").into()),
    };
    let cloud = &cloud;
    let mut f = std::io::BufWriter::new(std::fs::File::create(out.join("points.f32"))?);
    for p in &cloud.positions_m {
        for c in p {
            f.write_all(&c.to_le_bytes())?;
        }
    }
    f.flush()?;
    let ids: Vec<u8> = cloud.labels.iter().map(|l| l.id()).collect();
    std::fs::write(out.join("labels.u8"), ids)?;

    let params = DbscanParams {
        eps_m: eps,
        min_points,
        label_penalty_m: f32::INFINITY,
    };
    let mut dbscan_s = Vec::new();
    let mut result = None;
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        let r = dbscan(&cloud.positions_m, &cloud.labels, &params);
        dbscan_s.push(t.elapsed().as_secs_f64());
        result = Some(r);
    }
    let r = result.ok_or("no run")?;
    let clusters: Vec<u8> = r
        .cluster_of
        .iter()
        .flat_map(|c| c.map_or(-1i32, |c| c as i32).to_le_bytes())
        .collect();
    std::fs::write(out.join("ours_clusters.i32"), clusters)?;
    std::fs::write(
        out.join("ours_core.u8"),
        r.is_core.iter().map(|&c| u8::from(c)).collect::<Vec<_>>(),
    )?;

    let cfg = RefineConfig {
        eps_m: eps,
        min_points,
        ..Default::default()
    };
    let boxes = [person_box];
    let mut refine_s = Vec::new();
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        let refined = refine(cloud, &boxes, &cfg)?;
        refine_s.push(t.elapsed().as_secs_f64());
        std::hint::black_box(refined);
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    println!(
        "{{\"points\": {}, \"clusters\": {}, \"noise\": {}, \"core\": {}, \"dbscan_median_s\": {:.6}, \"dbscan_min_s\": {:.6}, \"refine_median_s\": {:.6}, \"threads\": {}, \"cloud\": \"{}\", \"cameras\": {}, \"flying\": {}, \"mislabelled\": {}}}",
        cloud.len(),
        r.num_clusters(),
        r.num_noise(),
        r.is_core.iter().filter(|&&c| c).count(),
        median(&mut dbscan_s.clone()),
        dbscan_s.iter().copied().fold(f64::INFINITY, f64::min),
        median(&mut refine_s),
        rayon::current_num_threads(),
        kind,
        cameras,
        flying,
        mislabelled,
    );
    Ok(())
}
