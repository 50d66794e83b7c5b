#!/usr/bin/env python3
"""Converts MediaPipe BlazePose (npm package @mediapipe/pose, Apache-2.0) to ONNX, once.

    python3 -m venv .venv && .venv/bin/pip install -r scripts/requirements-blazepose.txt
    python3 scripts/real_parsing_data.py            # real photographs for the check (optional)
    .venv/bin/python scripts/convert_blazepose.py   # -> models/blazepose_{lite,full,heavy}.onnx, ...

What it does, in order (issue 29, part 1):
1. `npm pack @mediapipe/pose@<pinned>` into a temporary folder (or --npm-dir: an extracted
   package), checks the SHA-256 of each file it uses against the pinned values below.
2. `pose_solution_packed_assets.data` is an Emscripten file package; its loader
   (`pose_solution_packed_assets_loader.js`) lists the files inside it. The script reads that
   list and cuts out `pose_detection.tflite` (today the package holds that file only, whole).
3. The detector's weights are sparse: 38 DENSIFY ops turn sparse fp16 constants into dense
   ones at run time. tf2onnx has no DENSIFY, so the dense values are read from the TFLite
   interpreter (reference kernels, default delegates off: with XNNPACK the DENSIFY outputs
   come back as zeros) and written into the flatbuffer as plain constant buffers; the DENSIFY
   ops are removed.
4. Each model is converted with tf2onnx (opset 17, ONNX IR version <= 10 so that ONNX
   Runtime 1.2x loads it). tf2onnx folds the fp16 DEQUANTIZE ops into fp32 constants; every
   fp32 constant whose values are exactly representable in fp16 (all of them, since they were
   fp16 in the TFLite file) is stored as fp16 again with a Cast to fp32 in front of its
   users (lossless; checked value by value).
5. Check: ONNX Runtime against the TFLite interpreter (reference kernels) on real
   photographs (crops of people from --check-images, default .data/real_parsing/images),
   plus a random input: max |difference| of the landmarks (px of the 256x256 input), of the
   segmentation mask after the sigmoid, of the pose flag; for the detector, of the box and
   keypoint regressors (px of the 224x224 input) and of the score logits. Above tolerance the
   outputs written so far are deleted and the script fails.
6. Writes models/blazepose_<variant>.onnx, models/blazepose_detector.onnx, a sidecar JSON
   next to each (input size, normalisation, outputs and their meaning), and
   models/LICENSE-APACHE-2.0 + models/NOTICE. Every file is written to a temporary and
   renamed.
"""

import argparse
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

import numpy as np

NPM_PACKAGE = "@mediapipe/pose"
NPM_VERSION = "0.5.1675469404"
SHA256 = {
    "pose_landmark_lite.tflite": "f17bfbecadb61c3be1baa8b8d851cc6619c870a87167b32848ad20db306b9d61",
    "pose_landmark_full.tflite": "e9a5c5cb17f736fafd4c2ec1da3b3d331d6edbe8a0d32395855aeb2cdfd64b9f",
    "pose_landmark_heavy.tflite": "59e42d71bcd44cbdbabc419f0ff76686595fd265419566bd4009ef703ea8e1fe",
    "pose_solution_packed_assets.data": "a63c614bef30d35947f13be361820b1e4e3bec9cfeebf4d11216a18373108e85",
}
DETECTOR_IN_PACKAGE = "pose_detection.tflite"
OPSET = 17
MAX_IR_VERSION = 10
VARIANTS = ("lite", "full", "heavy")

# Check tolerances (ONNX Runtime vs the TFLite reference kernels, fp32 both).
TOL_LANDMARK_PX = 0.05  # px of the 256x256 input; fp32 reordering noise is ~1e-3 px
TOL_MASK = 1e-2  # mask after the sigmoid, in [0, 1]: its logits reach +-700, and fp32
# summation-order noise of ~1e-4 relative moves a pixel near 0.5 by up to ~3e-3
TOL_VISIBILITY = 1e-3  # visibility / presence after the sigmoid
TOL_FLAG = 1e-3  # pose presence after the sigmoid
TOL_DETECTOR_PX = 0.05  # detector regressors, px of the 224x224 input
TOL_DETECTOR_LOGIT = 1e-2  # detector score logits

LANDMARK_NAMES = [
    "nose", "left_eye_inner", "left_eye", "left_eye_outer", "right_eye_inner", "right_eye",
    "right_eye_outer", "left_ear", "right_ear", "mouth_left", "mouth_right", "left_shoulder",
    "right_shoulder", "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_pinky",
    "right_pinky", "left_index", "right_index", "left_thumb", "right_thumb", "left_hip",
    "right_hip", "left_knee", "right_knee", "left_ankle", "right_ankle", "left_heel",
    "right_heel", "left_foot_index", "right_foot_index", "aux_body_center", "aux_body_scale",
    "aux_36", "aux_37", "aux_38", "aux_39",
]


def log(msg):
    print(msg, flush=True)


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


# ---------------------------------------------------------------------------------------
# 1-2. The npm package and the packed detector
# ---------------------------------------------------------------------------------------

def npm_package(dest):
    """Runs `npm pack` into dest and extracts it; returns the package folder."""
    spec = f"{NPM_PACKAGE}@{NPM_VERSION}"
    subprocess.run(["npm", "pack", spec, "--silent"], cwd=dest, check=True,
                   stdout=subprocess.PIPE)
    tgz = next(Path(dest).glob("*.tgz"))
    with tarfile.open(tgz) as tar:
        tar.extractall(dest, filter="data")
    return Path(dest) / "package"


def unpack_detector(pkg, out_path):
    """Cuts pose_detection.tflite out of the Emscripten file package, by the loader's list."""
    loader = (pkg / "pose_solution_packed_assets_loader.js").read_text()
    m = re.search(r"loadPackage\((\{\"files\".*?\})\);", loader, re.S)
    if m is None:
        raise SystemExit("pose_solution_packed_assets_loader.js: no loadPackage({...}) metadata")
    meta = json.loads(m.group(1))
    data = (pkg / "pose_solution_packed_assets.data").read_bytes()
    if meta.get("remote_package_size") != len(data):
        raise SystemExit("pose_solution_packed_assets.data: size differs from the loader's")
    hits = [f for f in meta["files"] if f["filename"].endswith("/" + DETECTOR_IN_PACKAGE)]
    if len(hits) != 1:
        raise SystemExit(f"packed assets: expected one {DETECTOR_IN_PACKAGE}, found {hits}")
    f = hits[0]
    Path(out_path).write_bytes(data[f["start"]:f["end"]])
    log(f"detector: {f['filename']} = bytes {f['start']}..{f['end']} of the packed assets "
        f"({len(meta['files'])} file(s) inside)")


# ---------------------------------------------------------------------------------------
# 3. Densify the detector
# ---------------------------------------------------------------------------------------

def tflite_interpreter(path, preserve=False):
    """The TFLite interpreter with the reference kernels (no XNNPACK delegate)."""
    import tensorflow as tf

    return tf.lite.Interpreter(
        model_path=str(path),
        experimental_op_resolver_type=tf.lite.experimental.OpResolverType.BUILTIN_WITHOUT_DEFAULT_DELEGATES,
        experimental_preserve_all_tensors=preserve,
        num_threads=2,
    )


def densify(src, dst):
    """Replaces every DENSIFY op by a constant holding its dense output. Returns the count."""
    from tensorflow.lite.python import schema_py_generated as schema
    from tensorflow.lite.tools import flatbuffer_utils

    model = flatbuffer_utils.read_model(str(src))
    sg = model.subgraphs[0]

    def code(op):
        c = model.operatorCodes[op.opcodeIndex]
        return max(c.builtinCode, c.deprecatedBuiltinCode)

    dens = [op for op in sg.operators if code(op) == schema.BuiltinOperator.DENSIFY]
    if not dens:
        shutil.copyfile(src, dst)
        return 0
    it = tflite_interpreter(src, preserve=True)
    it.allocate_tensors()
    inp = it.get_input_details()[0]
    it.set_tensor(inp["index"], np.zeros(inp["shape"], np.float32))
    it.invoke()
    for op in dens:
        out_idx = op.outputs[0]
        dense = np.ascontiguousarray(it.get_tensor(out_idx))
        t = sg.tensors[out_idx]
        if list(dense.shape) != list(t.shape):
            raise SystemExit(f"densify: tensor {t.name}: shape {dense.shape} != {list(t.shape)}")
        if not np.any(dense):
            raise SystemExit(f"densify: tensor {t.name} came back all zeros (delegate on?)")
        buf = schema.BufferT()
        buf.data = np.frombuffer(dense.tobytes(), np.uint8)
        model.buffers.append(buf)
        t.buffer = len(model.buffers) - 1
        # The sparse input is left unused; made dense too, since tf2onnx reads every
        # constant tensor (and cannot read a sparse one).
        t_in = sg.tensors[op.inputs[0]]
        t_in.sparsity = None
        t_in.shape = t.shape
        t_in.buffer = t.buffer
    sg.operators = [op for op in sg.operators if code(op) != schema.BuiltinOperator.DENSIFY]
    flatbuffer_utils.write_model(model, str(dst))
    return len(dens)


# ---------------------------------------------------------------------------------------
# 4. tf2onnx and fp16 storage
# ---------------------------------------------------------------------------------------

def to_onnx(tflite_path):
    import tf2onnx

    model, _ = tf2onnx.convert.from_tflite(str(tflite_path), opset=OPSET)
    return model


def store_fp16(model):
    """Stores each fp32 initializer whose values are exact in fp16 as fp16 + Cast.
    Returns (initializers stored as fp16, initializers kept fp32)."""
    import onnx
    from onnx import helper, numpy_helper

    g = model.graph
    graph_outputs = {o.name for o in g.output}
    new_inits, casts, n16, n32 = [], [], 0, 0
    for init in g.initializer:
        if init.data_type != onnx.TensorProto.FLOAT or init.name in graph_outputs:
            new_inits.append(init)
            continue
        v = numpy_helper.to_array(init)
        h = v.astype(np.float16)
        if v.size < 16 or not np.array_equal(h.astype(np.float32), v, equal_nan=True):
            new_inits.append(init)
            n32 += 1
            continue
        name16 = init.name + "__fp16"
        new_inits.append(numpy_helper.from_array(h, name16))
        casts.append(helper.make_node("Cast", [name16], [init.name], to=onnx.TensorProto.FLOAT,
                                      name=init.name + "__cast"))
        n16 += 1
    del g.initializer[:]
    g.initializer.extend(new_inits)
    nodes = list(g.node)
    del g.node[:]
    g.node.extend(casts + nodes)
    return n16, n32


def finish_onnx(model, producer_note):
    import onnx

    # Drop opset imports no node uses (tf2onnx adds ai.onnx.ml).
    used = {n.domain for n in model.graph.node}
    keep = [o for o in model.opset_import if o.domain in ("", "ai.onnx") or o.domain in used]
    del model.opset_import[:]
    model.opset_import.extend(keep)
    if model.ir_version > MAX_IR_VERSION:
        model.ir_version = MAX_IR_VERSION
    model.producer_name = "bodyseg scripts/convert_blazepose.py"
    model.doc_string = producer_note
    onnx.checker.check_model(model)
    return model


# ---------------------------------------------------------------------------------------
# 5. Check ONNX Runtime against the TFLite interpreter
# ---------------------------------------------------------------------------------------

def check_inputs(size, images, lo, hi, max_images):
    """Real-image inputs [1, size, size, 3] in [lo, hi]: the central square crop of each
    image and its top-left quarter, resized; plus one uniform random input."""
    from PIL import Image

    out = []
    for p in images[:max_images]:
        im = Image.open(p).convert("RGB")
        w, h = im.size
        s = min(w, h)
        for box in ((w // 2 - s // 2, h // 2 - s // 2, w // 2 + s - s // 2, h // 2 + s - s // 2),
                    (0, 0, max(w // 2, 8), max(h // 2, 8))):
            crop = np.asarray(im.crop(box).resize((size, size), Image.BILINEAR), np.float32)
            out.append((Path(p).name, (crop / 255.0 * (hi - lo) + lo)[None]))
    rng = np.random.default_rng(0)
    out.append(("random", rng.uniform(lo, hi, (1, size, size, 3)).astype(np.float32)))
    return out


def run_tflite(path, x):
    it = tflite_interpreter(path)
    it.allocate_tensors()
    it.set_tensor(it.get_input_details()[0]["index"], x)
    it.invoke()
    return {d["name"]: it.get_tensor(d["index"]).copy() for d in it.get_output_details()}


def sigmoid(x):
    return 1.0 / (1.0 + np.exp(-np.clip(np.asarray(x, np.float64), -100.0, 100.0)))


def check_landmark(tflite_path, onnx_path, inputs):
    import onnxruntime as ort

    sess = ort.InferenceSession(str(onnx_path), providers=["CPUExecutionProvider"])
    name = sess.get_inputs()[0].name
    worst = {"landmarks_px": 0.0, "mask": 0.0, "pose_flag": 0.0, "visibility": 0.0}
    for _, x in inputs:
        ref = run_tflite(tflite_path, x)
        got = dict(zip([o.name for o in sess.get_outputs()], sess.run(None, {name: x})))
        lm_r, lm_o = ref["Identity"].reshape(39, 5), got["Identity"].reshape(39, 5)
        worst["landmarks_px"] = max(worst["landmarks_px"], float(np.abs(lm_r[:, :2] - lm_o[:, :2]).max()))
        worst["visibility"] = max(worst["visibility"],
                                  float(np.abs(sigmoid(lm_r[:, 3:5]) - sigmoid(lm_o[:, 3:5])).max()))
        worst["mask"] = max(worst["mask"], float(np.abs(sigmoid(ref["Identity_2"]) - sigmoid(got["Identity_2"])).max()))
        worst["pose_flag"] = max(worst["pose_flag"], float(np.abs(ref["Identity_1"] - got["Identity_1"]).max()))
    ok = (worst["landmarks_px"] <= TOL_LANDMARK_PX and worst["mask"] <= TOL_MASK
          and worst["pose_flag"] <= TOL_FLAG and worst["visibility"] <= TOL_VISIBILITY)
    return ok, worst


def max_output_diff(model_a_bytes, onnx_path_b, inputs):
    """Max |difference| over all outputs of two ONNX models on the inputs."""
    import onnxruntime as ort

    sa = ort.InferenceSession(model_a_bytes, providers=["CPUExecutionProvider"])
    sb = ort.InferenceSession(str(onnx_path_b), providers=["CPUExecutionProvider"])
    name = sa.get_inputs()[0].name
    worst = 0.0
    for _, x in inputs:
        for a, b in zip(sa.run(None, {name: x}), sb.run(None, {name: x})):
            worst = max(worst, float(np.abs(a - b).max()))
    return worst


def check_detector(tflite_path, onnx_path, inputs):
    import onnxruntime as ort

    sess = ort.InferenceSession(str(onnx_path), providers=["CPUExecutionProvider"])
    name = sess.get_inputs()[0].name
    worst = {"regressors_px": 0.0, "score_logits": 0.0}
    best_score = 0.0
    for _, x in inputs:
        ref = run_tflite(tflite_path, x)
        got = dict(zip([o.name for o in sess.get_outputs()], sess.run(None, {name: x})))
        worst["regressors_px"] = max(worst["regressors_px"], float(np.abs(ref["Identity"] - got["Identity"]).max()))
        logits_r = np.clip(ref["Identity_1"], -100, 100)
        logits_o = np.clip(got["Identity_1"], -100, 100)
        worst["score_logits"] = max(worst["score_logits"], float(np.abs(logits_r - logits_o).max()))
        best_score = max(best_score, float(sigmoid(logits_r).max()))
    ok = worst["regressors_px"] <= TOL_DETECTOR_PX and worst["score_logits"] <= TOL_DETECTOR_LOGIT
    return ok, worst, best_score


# ---------------------------------------------------------------------------------------
# 6. Sidecars, licence, notice
# ---------------------------------------------------------------------------------------

def landmark_sidecar(variant, onnx_path, check):
    return {
        "model": "blazepose_landmark",
        "variant": variant,
        "source": f"npm {NPM_PACKAGE}@{NPM_VERSION} pose_landmark_{variant}.tflite (MediaPipe, Apache-2.0)",
        "source_sha256": SHA256[f"pose_landmark_{variant}.tflite"],
        "input": {"name": "input_1", "shape": [1, 256, 256, 3], "layout": "NHWC",
                  "channel_order": "RGB", "range": [0.0, 1.0],
                  "normalisation": "pixel / 255, no mean or std"},
        "input_size": [256, 256],
        "roi": ("the tensor is the crop of a square region of interest of the image: centre, side "
                "and rotation (MediaPipe NormalizedRect), tensor pixel centre (i + 0.5) / 256 - 0.5 "
                "of the side from the centre, rotated; bilinear; outside the image the border "
                "pixel is replicated (ImageToTensorCalculator, BORDER_REPLICATE). From a "
                "detection or from the previous landmarks: box around the alignment points "
                "(centre = aux_body_center, side = 2 |aux_body_scale - aux_body_center|, "
                "rotation so that the centre->scale vector points up), scaled by 1.5, square_long"),
        "outputs": {
            "Identity": {"shape": [1, 195], "meaning": "39 landmarks x (x, y, z, visibility, presence): "
                         "x, y in px of the 256x256 input; z in the same scale, relative to the hips; "
                         "visibility and presence are logits (sigmoid -> probability). 0-32 the body "
                         "landmarks (names below), 33-34 the alignment points of the next ROI"},
            "Identity_1": {"shape": [1, 1], "meaning": "pose presence, already a probability "
                           "(MediaPipe thresholds it at 0.5)"},
            "Identity_2": {"shape": [1, 256, 256, 1], "meaning": "segmentation logits on the 256x256 "
                           "input grid (sigmoid -> person probability)"},
            "Identity_3": {"shape": [1, 64, 64, 39], "meaning": "landmark heatmaps (logits), used by "
                           "MediaPipe to refine x, y (RefineLandmarksFromHeatmap, kernel 7)"},
            "Identity_4": {"shape": [1, 117], "meaning": "39 world landmarks x (x, y, z), metres, "
                           "origin between the hips"},
        },
        "landmark_names": LANDMARK_NAMES[:35],
        "weights": "fp16 storage (exact: the TFLite weights are fp16), cast to fp32 in the graph",
        "opset": OPSET,
        "check": check,
        "file_bytes": os.path.getsize(onnx_path),
    }


def detector_sidecar(onnx_path, check):
    return {
        "model": "blazepose_detector",
        "source": f"npm {NPM_PACKAGE}@{NPM_VERSION} pose_solution_packed_assets.data -> "
                  f"{DETECTOR_IN_PACKAGE} (MediaPipe, Apache-2.0), densified",
        "source_sha256": SHA256["pose_solution_packed_assets.data"],
        "input": {"name": "input_1", "shape": [1, 224, 224, 3], "layout": "NHWC",
                  "channel_order": "RGB", "range": [-1.0, 1.0],
                  "normalisation": "pixel / 127.5 - 1; the whole image letterboxed into 224x224 "
                                   "(keep aspect ratio, border zero)"},
        "input_size": [224, 224],
        "outputs": {
            "Identity": {"shape": [1, 2254, 12], "meaning": "per anchor: box dx, dy, w, h then 4 "
                         "keypoints (x, y), offsets in px of the 224 input from the anchor centre; "
                         "keypoint 0 mid-hip, 1 full-body size/rotation point, 2 mid-shoulder, 3 "
                         "upper-body size/rotation point. The box is the face's"},
            "Identity_1": {"shape": [1, 2254, 1], "meaning": "score logits (clip to +-100, sigmoid; "
                           "MediaPipe keeps > 0.5 and weighted NMS at IoU 0.3)"},
        },
        "anchors": {"num_layers": 5, "strides": [8, 16, 32, 32, 32], "min_scale": 0.1484375,
                    "max_scale": 0.75, "offset": [0.5, 0.5], "aspect_ratios": [1.0],
                    "fixed_anchor_size": True,
                    "count": "28x28x2 + 14x14x2 + 7x7x6 = 2254"},
        "roi_from_detection": "MediaPipe pose_detection_to_roi: centre = the start keypoint, side = "
                              "2 |end - start|, rotation so that start->end points up (target 90 deg), "
                              "then scaled 1.5, square_long. Full body: keypoints 0->1",
        "weights": "fp16 storage (exact: the TFLite weights are fp16, sparse), cast to fp32",
        "opset": OPSET,
        "check": check,
        "file_bytes": os.path.getsize(onnx_path),
    }


NOTICE = """\
BlazePose models in this folder (blazepose_lite.onnx, blazepose_full.onnx,
blazepose_heavy.onnx, blazepose_detector.onnx)

Derived from MediaPipe Pose by Google LLC, as published in the npm package
{pkg}@{ver} (files pose_landmark_lite.tflite, pose_landmark_full.tflite,
pose_landmark_heavy.tflite, and pose_detection.tflite inside
pose_solution_packed_assets.data), licensed under the Apache License, Version 2.0
(LICENSE-APACHE-2.0 in this folder). "package.json": "license": "Apache-2.0".

Changes made by bodyseg's scripts/convert_blazepose.py:
- Format conversion: TensorFlow Lite flatbuffer -> ONNX (tf2onnx, opset {opset}). The
  graph computes the same function: ONNX Runtime was checked against the TensorFlow Lite
  interpreter on real photographs (numbers in each model's .json sidecar).
- Densification (pose_detection.tflite only): its sparse fp16 weights (38 DENSIFY ops)
  were expanded to dense constants before the conversion; the DENSIFY ops were removed.
- Weight storage: the fp16 weights are stored as fp16 initializers with a Cast to fp32
  (no value changed).
No weights were retrained or otherwise modified.
"""


def find_apache_text(pkg):
    """The Apache-2.0 text: from the npm package if it ships one, else the system's copy
    (the @mediapipe/pose package declares Apache-2.0 in package.json but ships no text)."""
    for name in ("LICENSE", "LICENSE.txt", "LICENSE.md"):
        if (pkg / name).exists():
            return (pkg / name).read_text(), f"npm package {name}"
    for cand in (Path("/usr/share/common-licenses/Apache-2.0"),):
        if cand.exists():
            return cand.read_text(), str(cand)
    raise SystemExit("no Apache-2.0 licence text found (npm package ships none; "
                     "/usr/share/common-licenses/Apache-2.0 missing)")


def write_atomic(path, data):
    path = Path(path)
    tmp = path.with_name(path.name + ".tmp")
    tmp.write_bytes(data if isinstance(data, bytes) else data.encode())
    os.replace(tmp, path)


# ---------------------------------------------------------------------------------------

def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default="models", help="output folder (default models/)")
    ap.add_argument("--npm-dir", help="an extracted @mediapipe/pose package (default: npm pack)")
    ap.add_argument("--variants", nargs="+", default=list(VARIANTS), choices=VARIANTS)
    ap.add_argument("--no-detector", action="store_true")
    ap.add_argument("--check-images", default=".data/real_parsing/images",
                    help="folder of real photographs for the check (jpg/png)")
    ap.add_argument("--check-count", type=int, default=8, help="photographs used by the check")
    args = ap.parse_args()

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    images = sorted(p for p in Path(args.check_images).glob("*") if p.suffix.lower() in (".jpg", ".jpeg", ".png"))
    if not images:
        raise SystemExit(f"{args.check_images}: no photographs for the check "
                         "(run scripts/real_parsing_data.py, or give --check-images)")

    written = []
    try:
        with tempfile.TemporaryDirectory(prefix="blazepose_") as tmp:
            tmp = Path(tmp)
            pkg = Path(args.npm_dir) if args.npm_dir else npm_package(tmp)
            for name, want in SHA256.items():
                got = sha256(pkg / name)
                if got != want:
                    raise SystemExit(f"{pkg / name}: sha256 {got}, pinned {want}")
            log(f"{NPM_PACKAGE}@{NPM_VERSION}: files match the pinned SHA-256")

            lm_inputs = check_inputs(256, images, 0.0, 1.0, args.check_count)
            summary = {}
            for variant in args.variants:
                src = pkg / f"pose_landmark_{variant}.tflite"
                model = to_onnx(src)
                model32 = model.SerializeToString()
                n16, n32 = store_fp16(model)
                finish_onnx(model, f"MediaPipe BlazePose landmark ({variant}), converted from "
                                   f"{NPM_PACKAGE}@{NPM_VERSION}; Apache-2.0, see NOTICE")
                dst = out / f"blazepose_{variant}.onnx"
                write_atomic(dst, model.SerializeToString())
                written.append(dst)
                ok, worst = check_landmark(src, dst, lm_inputs)
                lossless = max_output_diff(model32, dst, lm_inputs)
                log(f"{variant}: fp16 storage vs fp32 (ONNX Runtime, all outputs): max |diff| {lossless:.3g}")
                if lossless != 0.0:
                    raise SystemExit(f"{variant}: fp16 weight storage changed the outputs")
                log(f"{variant}: fp16 initializers {n16}, fp32 kept {n32}; check on "
                    f"{len(lm_inputs)} inputs: " + ", ".join(f"{k} {v:.2e}" for k, v in worst.items()))
                if not ok:
                    raise SystemExit(f"{variant}: ONNX Runtime differs from TFLite beyond tolerance")
                check = {"inputs": len(lm_inputs), "max_abs_diff": worst,
                         "tolerance": {"landmarks_px": TOL_LANDMARK_PX, "mask": TOL_MASK,
                                       "pose_flag": TOL_FLAG, "visibility": TOL_VISIBILITY},
                         "fp16_storage_vs_fp32_max_abs_diff": lossless}
                sidecar = landmark_sidecar(variant, dst, check)
                write_atomic(dst.with_suffix(".json"), json.dumps(sidecar, indent=2) + "\n")
                written.append(dst.with_suffix(".json"))
                summary[variant] = (os.path.getsize(dst), worst)

            if not args.no_detector:
                packed = tmp / DETECTOR_IN_PACKAGE
                unpack_detector(pkg, packed)
                dense = tmp / "pose_detection_dense.tflite"
                n = densify(packed, dense)
                log(f"detector: {n} DENSIFY ops replaced by constants")
                model = to_onnx(dense)
                model32 = model.SerializeToString()
                n16, n32 = store_fp16(model)
                finish_onnx(model, f"MediaPipe BlazePose detector, converted from {NPM_PACKAGE}@"
                                   f"{NPM_VERSION} (densified); Apache-2.0, see NOTICE")
                dst = out / "blazepose_detector.onnx"
                write_atomic(dst, model.SerializeToString())
                written.append(dst)
                det_inputs = check_inputs(224, images, -1.0, 1.0, args.check_count)
                ok, worst, best_score = check_detector(packed, dst, det_inputs)
                lossless = max_output_diff(model32, dst, det_inputs)
                log(f"detector: fp16 storage vs fp32 (ONNX Runtime, all outputs): max |diff| {lossless:.3g}")
                if lossless != 0.0:
                    raise SystemExit("detector: fp16 weight storage changed the outputs")
                log(f"detector: fp16 initializers {n16}, fp32 kept {n32}; check on "
                    f"{len(det_inputs)} inputs (reference: the sparse original): "
                    + ", ".join(f"{k} {v:.2e}" for k, v in worst.items())
                    + f"; best detection score {best_score:.2f}")
                if not ok:
                    raise SystemExit("detector: ONNX Runtime differs from TFLite beyond tolerance")
                check = {"inputs": len(det_inputs), "max_abs_diff": worst,
                         "best_detection_score": best_score,
                         "tolerance": {"regressors_px": TOL_DETECTOR_PX, "score_logits": TOL_DETECTOR_LOGIT},
                         "fp16_storage_vs_fp32_max_abs_diff": lossless}
                write_atomic(dst.with_suffix(".json"), json.dumps(detector_sidecar(dst, check), indent=2) + "\n")
                written.append(dst.with_suffix(".json"))
                summary["detector"] = (os.path.getsize(dst), worst)

            text, origin = find_apache_text(pkg)
            write_atomic(out / "LICENSE-APACHE-2.0", text)
            write_atomic(out / "NOTICE", NOTICE.format(pkg=NPM_PACKAGE, ver=NPM_VERSION, opset=OPSET))
            log(f"licence text from {origin}")
    except BaseException:
        for p in written:
            p.unlink(missing_ok=True)
        log("check or conversion failed: outputs deleted")
        raise

    log("\nfile | bytes")
    for k, (size, _) in summary.items():
        name = "blazepose_detector.onnx" if k == "detector" else f"blazepose_{k}.onnx"
        log(f"{name} | {size}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
