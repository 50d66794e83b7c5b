#!/usr/bin/env bash
# The main job on the embedded default, in a few minutes: installs what is missing (ONNX
# Runtime from PyPI), builds the release binary, renders a synthetic recording (two people
# handing over an object, three Kinect v2 cameras, exact ground truth) and runs the whole
# pipeline on it with the default 2D parser (BlazePose full, models/blazepose_full.onnx, on
# the people found from depth; --set parsing.segmenter=onnx for the synthetic-trained model):
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

echo "==> building (release)"
cargo build --release --quiet --bin bodyseg
bodyseg=target/release/bodyseg

mkdir -p "$out"
if [ ! -f "$out/rec/rig.toml" ] || [ "$(ls "$out/rec/cam0/depth" | wc -l)" -ne "$frames" ]; then
    echo "==> bodyseg synth: $frames frames of the handover scene"
    "$bodyseg" synth --preset handover --frames "$frames" --seed 1 --force --out "$out/rec"
fi

echo "==> bodyseg run: people from depth, BlazePose, DSA projection, boxes, refinement, evaluation"
"$bodyseg" run --recording "$out/rec" --parser model --out "$out/run" "${@:3}" | tee "$out/table.md"

echo
echo "The table: $out/run/report.md (also $out/run/report.json)"
echo "Refined clouds: $out/run/clouds/<frame>.ply; labels drawn back into the cameras: $out/run/labels/"
for f in "$out"/run/figures/*.png; do
    echo "Figure (input, clusters, M, N, M-N, M-R-N, truth): $f"
done
