//! CPU time per frame of the `run` bench's production path (or with `eval`, the five
//! configurations scored), next to the wall time: CPU time stays meaningful on a loaded
//! machine where criterion's wall-clock figures do not.
//!
//! `cargo run --release -p bodyseg-lab --example cpu_per_frame [ROUNDS] [eval]`
//!
//! The bench's setup (8 synthetic `handover` frames decoded in memory, a 2-thread pool,
//! mimalloc keeping freed memory, a fresh output folder per pass); ROUNDS (default 6)
//! passes over the 8 frames after one warm-up pass. `PURGE=1` leaves mimalloc's default (freed memory handed back to the OS)
//! for comparison. Linux only (reads `/proc/self/stat`).
#![allow(missing_docs)]

use anyhow::{Context, Result};
use bodyseg_pipeline::{
    FrameProcessor, FrameWriter, ParsedFrame, ParserChoice, PipelineConfig, SceneSource,
    SynthOptions, synth_recording,
};
use rayon::prelude::*;
use std::time::Instant;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// User + system CPU time of this process so far, seconds.
fn cpu_s() -> Result<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").context("/proc/self/stat")?;
    // Fields after the command name (which may hold spaces) end with ')'.
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .context("/proc/self/stat: no ')'")?
        .split_whitespace()
        .collect();
    let ticks = |i: usize| -> Result<f64> {
        fields
            .get(i)
            .context("/proc/self/stat: too short")?
            .parse::<f64>()
            .context("/proc/self/stat: not a number")
    };
    // utime and stime (fields 14 and 15 of proc(5)), in clock ticks of 1/100 s.
    Ok((ticks(11)? + ticks(12)?) / 100.0)
}

fn main() -> Result<()> {
    if std::env::var_os("PURGE").is_none() {
        bodyseg_pipeline::keep_freed_memory();
    }
    let mut args = std::env::args().skip(1);
    let rounds: usize = args.next().map_or(Ok(6), |a| a.parse()).context("ROUNDS")?;
    let eval = args.next().is_some_and(|a| a == "eval");
    let dir = tempfile::tempdir()?;
    let rec = dir.path().join("rec");
    let synth = SynthOptions {
        scene: SceneSource::Preset("handover".into()),
        overrides: Vec::new(),
        seed: 7,
        frames: 8,
        out: rec.clone(),
        force: false,
        previews: false,
        chessboard: None,
    };
    synth_recording(&synth, &|_| {})?;
    let out = dir.path().join("out");
    let processor = FrameProcessor::open(&rec, &PipelineConfig::default(), ParserChoice::Auto)?;
    let frames = processor.recording().frames()?.complete;
    let inputs = frames
        .iter()
        .map(|f| {
            let frame = processor.read(f, &mut Vec::new())?;
            let mut parsed = processor.parse(frame, &mut Vec::new())?;
            if !eval {
                parsed.frame.truth = None;
            }
            Ok(parsed)
        })
        .collect::<Result<Vec<ParsedFrame>>>()?;
    let two = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    // Each pass writes into a fresh folder, as `bodyseg run` does (no file replaced);
    // the folders are removed after the timing.
    std::fs::create_dir_all(&out)?;
    let pass = || -> Result<tempfile::TempDir> {
        let folder = tempfile::tempdir_in(&out)?;
        two.install(|| {
            inputs.par_iter().with_max_len(1).try_for_each(|f| {
                let mut writer = FrameWriter::new(folder.path());
                processor.process(f, &mut writer, &mut Vec::new())?;
                anyhow::Ok(())
            })
        })?;
        Ok(folder)
    };
    drop(pass()?);
    let mut written = Vec::with_capacity(rounds);
    let (cpu0, t0) = (cpu_s()?, Instant::now());
    for _ in 0..rounds {
        written.push(pass()?);
    }
    let wall = t0.elapsed().as_secs_f64();
    let cpu = cpu_s()? - cpu0;
    drop(written);
    let n = (rounds * inputs.len()) as f64;
    println!(
        "{}: cpu {:.1} ms/frame, wall {:.1} ms/frame ({:.1} frames/s), {n} frames",
        if eval { "with_eval" } else { "production" },
        cpu * 1e3 / n,
        wall * 1e3 / n,
        n / wall
    );
    Ok(())
}
