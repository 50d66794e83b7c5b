#!/usr/bin/env bash
# A two-minute look at bodyseg: builds the release binary, writes a synthetic scene (two
# people, 100k points each, with the label errors of 2D parsing + projection), refines it
# and prints the paper-style table of the input vs the refined labels against the truth.
#
#   scripts/demo.sh [OUT_DIR]        (default: demo_out/ in the repository)
#
# Files in OUT_DIR: in.ply, gt.ply, boxes.json (the scene), refined.ply (+ its resolved
# configuration), report.md and report.json. Open the PLY files in any point-cloud viewer
# (MeshLab, CloudCompare): colours are the class palette.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
out="${1:-demo_out}"

echo "==> ONNX Runtime (once)"
scripts/setup_onnxruntime.sh

echo "==> building (release)"
cargo build --release --quiet --bin bodyseg
cargo build --release --quiet -p bodyseg-pipeline --example demo_scene
bodyseg=target/release/bodyseg

echo "==> writing the synthetic scene"
target/release/examples/demo_scene --out "$out" --points 100000 --people 2 --seed 1

echo "==> bodyseg refine"
"$bodyseg" refine --cloud "$out/in.ply" --boxes "$out/boxes.json" --out "$out/refined.ply"

echo "==> bodyseg eval"
"$bodyseg" eval --quiet --pred "Reference=$out/in.ply" --pred "M-R-N=$out/refined.ply" \
    --gt "$out/gt.ply" --format json --out "$out/report.json"
# The same report as markdown: --merge of a single report converts it.
"$bodyseg" eval --quiet --merge "$out/report.json" --format md --out "$out/report.md"
cat "$out/report.md"

echo
echo "==> bodyseg parse: 2D body parts of a synthetic frame with the bundled model"
"$bodyseg" synth --preset handover --frames 1 --seed 1 --no-preview --force --out "$out/rec"
"$bodyseg" parse --recording "$out/rec" --frame 000000 --out "$out/parsed"
echo "Label images and previews: $out/parsed/<camera>/parsing{,_preview}/000000.png"
echo
echo "Files are in $out/"
