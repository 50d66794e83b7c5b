#!/usr/bin/env bash
# The main job on the embedded default, in a few minutes: installs what is missing (ONNX
# Runtime from PyPI), builds the release binary, renders a synthetic recording (two people
# handing over an object, three Kinect v2 cameras, exact ground truth) and runs the whole
# pipeline on it with the default 2D parser (BlazePose full, models/blazepose_full.onnx, on
# the people found from depth, body parts from BodyPix, models/bodypix_mobilenet_v1_075_quant.onnx;
# --set parsing.body_parts=landmarks for BlazePose alone, parsing.segmenter=onnx for the
# synthetic-trained model):
# people from depth -> parse -> DSA projection -> person boxes -> clustering refinement ->
# evaluation. Prints the paper-style table (Reference, M, N,
# M-N, M-R-N against the ground truth) and the path of the Figure-5-style picture.
#
#   scripts/demo.sh [OUT_DIR] [FRAMES] [RUN ARGS...]   (default: demo_out/ in the repository,
#                                                   24 frames; e.g. --set parsing.segmenter=onnx)
#
# Files in OUT_DIR: rec/ (the recording), run/ (clouds/ refined PLY per frame, boxes/,
# labels/ per camera, figures/, report.md, report.json, config.resolved.toml, run.json).
# Open the PLY files in any point-cloud viewer (MeshLab, CloudCompare): colours are the
# class palette. Running the demo again reuses the recording's finished frames.
#
# run/run.rrd: every stage of every frame as a Rerun recording (cameras, images, 2D labels,
# clouds, boxes, scores on a timeline): `pip install rerun-sdk==0.36.3`, then
# `rerun demo_out/run/run.rrd`. Building the `rerun` feature for it adds the Rerun SDK's
# dependencies to the first build (several minutes); DEMO_RERUN=0 skips it.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
out="${1:-demo_out}"
frames="${2:-24}"

if ! command -v cargo >/dev/null; then
    echo "error: cargo not found: install Rust (https://rustup.rs), then run $0 again" >&2
    exit 1
fi

echo "==> ONNX Runtime (once)"
scripts/setup_onnxruntime.sh

rerun="${DEMO_RERUN:-1}"
features=()
if [ "$rerun" = 1 ]; then
    features=(--features rerun)
fi
echo "==> building (release${features:+, ${features[*]}})"
cargo build --release --quiet --bin bodyseg "${features[@]}"
bodyseg=target/release/bodyseg

mkdir -p "$out"
if [ ! -f "$out/rec/rig.toml" ] || [ "$(ls "$out/rec/cam0/depth" | wc -l)" -ne "$frames" ]; then
    echo "==> bodyseg synth: $frames frames of the handover scene"
    "$bodyseg" synth --preset handover --frames "$frames" --seed 1 --force --out "$out/rec"
fi

echo "==> bodyseg run: people from depth, BlazePose + BodyPix, DSA projection, boxes, refinement, evaluation"
rrd=()
if [ "$rerun" = 1 ]; then
    rrd=(--rerun "$out/run/run.rrd")
fi
"$bodyseg" run --recording "$out/rec" --parser model --out "$out/run" "${rrd[@]}" "${@:3}" | tee "$out/table.md"

echo
echo "The table: $out/run/report.md (also $out/run/report.json)"
echo "Refined clouds: $out/run/clouds/<frame>.ply; labels drawn back into the cameras: $out/run/labels/"
for f in "$out"/run/figures/*.png; do
    echo "Figure (input, clusters, M, N, M-N, M-R-N, truth): $f"
done
if [ "$rerun" = 1 ]; then
    echo "Rerun recording (every stage, every frame): $out/run/run.rrd"
    echo "  open it: pip install rerun-sdk==0.36.3 && rerun $out/run/run.rrd"
fi
