#!/usr/bin/env bash
# Makes models/bodypix_mobilenet_v1_075_quant.onnx from Google Coral's BodyPix TFLite graph
# (google-coral/project-bodypix, Apache-2.0), pinned by commit and SHA-256 (NOTICE, sidecar
# models/bodypix_mobilenet_v1_075_quant.json; probe: docs/notes/2026-12-04-bodypix-probe.md).
#
#   python3 -m venv .venv && .venv/bin/pip install -r scripts/requirements-blazepose.txt \
#       ai-edge-litert          # tf2onnx + onnx; LiteRT for the check
#   git clone https://github.com/google-coral/project-bodypix /tmp/project-bodypix
#   scripts/convert_bodypix.sh /tmp/project-bodypix     # a clone or bare git dir of it
#
# Steps: the TFLite file at the pinned commit (checked by SHA-256) -> tf2onnx (opset 17, the
# uint8 QDQ graph) -> scripts/bodypix_onnx.py (symbolic height/width, the segment output's
# fixed Reshape -> the NCHW->NHWC Transpose it stands for, check against LiteRT) -> models/.
set -euo pipefail
REPO=${1:?usage: scripts/convert_bodypix.sh PROJECT_BODYPIX_GIT_DIR}
COMMIT=a46c428d729741c82f64550d742b2c65fe92999b
FILE=models/bodypix_mobilenet_v1_075_720_1280_16_quant.tflite
SHA256=6abaed4ad9080cafd327d0f03fd23f0c46d4409b75b6e23abde9a35582067696
PY=${PYTHON:-.venv/bin/python}
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
git --git-dir="$(git -C "$REPO" rev-parse --absolute-git-dir)" show "$COMMIT:$FILE" >"$tmp/m.tflite"
echo "$SHA256  $tmp/m.tflite" | sha256sum -c --quiet
"$PY" -m tf2onnx.convert --tflite "$tmp/m.tflite" --output "$tmp/m.raw.onnx" --opset 17
"$PY" scripts/bodypix_onnx.py "$tmp/m.tflite" "$tmp/m.raw.onnx" "$tmp/m.onnx"
mv "$tmp/m.onnx" models/bodypix_mobilenet_v1_075_quant.onnx
sha256sum models/bodypix_mobilenet_v1_075_quant.onnx
