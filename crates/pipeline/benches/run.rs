//! Guards issue 7's throughput target: `bodyseg run` with recorded predictions at ≥ 30
//! frames/s for 3 Kinect v2 cameras and 2 people on 2 cores, PNG decoding of the inputs
//! excluded and everything else included (projection, boxes, refinement, evaluation,
//! writing the refined PLY, the boxes JSON and the three label PNGs, each atomically).
//!
//! Setup: a synthetic `handover` recording (2 people, 3 cameras, colour 960×540) of
//! [`FRAMES`] frames is rendered into a temporary folder and every frame's inputs are
//! decoded into memory and parsed ([`FrameProcessor::read`], [`FrameProcessor::parse`]:
//! the recorded predictions). One iteration processes all of them
//! ([`FrameProcessor::process`]) in parallel on a 2-thread rayon pool, as the frame loop
//! of `bodyseg run` does. Elements = frames, so criterion's throughput is frames/s.
//!
//! Cases: `production` (no ground truth: the configured refinement only, as on a real
//! recording) and `with_eval` (ground truth: the paper's five configurations refined and
//! scored per frame, as `bodyseg run` does on synthetic recordings).

// criterion_group!/criterion_main! generate undocumented items.
#![allow(missing_docs)]

use bodyseg_pipeline::{
    FrameProcessor, FrameWriter, ParsedFrame, ParserChoice, PipelineConfig, SceneSource,
    SynthOptions, synth_recording,
};
use criterion::{BatchSize, BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use rayon::prelude::*;

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Frames per iteration.
const FRAMES: usize = 8;

fn bench(c: &mut Criterion) {
    // As the `bodyseg` binary does.
    bodyseg_pipeline::keep_freed_memory();
    let dir = tempfile::tempdir().unwrap_or_else(|e| panic!("temp dir: {e}"));
    let rec = dir.path().join("rec");
    let synth = SynthOptions {
        scene: SceneSource::Preset("handover".into()),
        overrides: Vec::new(),
        seed: 7,
        frames: FRAMES,
        out: rec.clone(),
        force: false,
        previews: false,
        chessboard: None,
    };
    synth_recording(&synth, &|_| {}).unwrap_or_else(|e| panic!("synth: {e:#}"));
    let out = dir.path().join("out");
    std::fs::create_dir_all(&out).unwrap_or_else(|e| panic!("{}: {e}", out.display()));
    let processor = FrameProcessor::open(&rec, &PipelineConfig::default(), ParserChoice::Auto)
        .unwrap_or_else(|e| panic!("{e:#}"));
    let frames = processor
        .recording()
        .frames()
        .unwrap_or_else(|e| panic!("{e:#}"))
        .complete;
    let with_truth: Vec<ParsedFrame> = frames
        .iter()
        .map(|f| {
            let frame = processor
                .read(f, &mut Vec::new())
                .unwrap_or_else(|e| panic!("{e:#}"));
            processor
                .parse(frame, &mut Vec::new())
                .unwrap_or_else(|e| panic!("{e:#}"))
        })
        .collect();
    let without_truth: Vec<ParsedFrame> = with_truth
        .iter()
        .cloned()
        .map(|mut f| {
            f.frame.truth = None;
            f
        })
        .collect();

    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap_or_else(|e| panic!("thread pool: {e}"));
    let mut group = c.benchmark_group("run_frames");
    group.sample_size(10);
    group.throughput(Throughput::Elements(FRAMES as u64));
    for (name, inputs) in [("production", &without_truth), ("with_eval", &with_truth)] {
        group.bench_function(BenchmarkId::new(name, "2_threads"), |b| {
            // Each iteration writes into a fresh folder, as `bodyseg run` does: no output
            // replaces an earlier file (on ext4 a rename over an existing file flushes and
            // evicts the old one, work a run never does). Criterion drops the folder, so
            // its removal, outside the timing.
            b.iter_batched(
                || tempfile::tempdir_in(&out).unwrap_or_else(|e| panic!("temp dir: {e}")),
                |folder| {
                    two.install(|| {
                        inputs.par_iter().with_max_len(1).for_each(|f| {
                            let mut writer = FrameWriter::new(folder.path());
                            processor
                                .process(f, &mut writer, &mut Vec::new())
                                .unwrap_or_else(|e| panic!("{e:#}"));
                        });
                    });
                    folder
                },
                BatchSize::PerIteration,
            );
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
