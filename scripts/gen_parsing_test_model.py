#!/usr/bin/env python3
"""Writes bodyseg-parsing's test data into crates/parsing/tests/data/ (committed):

- tiny.onnx + tiny.json: a tiny deterministic parsing model in bodyseg's contract
  (input [N,3,32,32] float32, logits [N,7,16,16]: Conv 3x3 stride 2 + ReLU + Conv 1x1;
  seeded weights; opset 17, IR version 8), < 10 KB.
- tiny_5ch.onnx: the same with 5 output channels (a model that breaks the contract).
- tiny_golden.json: a fixed input batch of 2 and the logits Python onnxruntime gives for it;
  and, for a fixed 40x30 RGB image, the class ids and winner probabilities of the whole
  SCHP pre-processing -> model -> post-processing chain (scripts/parsing_common.py).
- preprocess_golden.json: SCHP pre-processing (ALGORITHM.md §2) for 640x480 and 1920x1080
  images into a 512x512 input: both affine matrices and the bilinear samples at fixed input
  pixels before their rounding to whole grey levels (the Rust test rounds them, so it can
  tell a tie), of the pattern image `pattern_rgb` below (the Rust test builds the same image).

    pip install onnx onnxruntime numpy
    python3 scripts/gen_parsing_test_model.py
"""

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import parsing_common as pc  # noqa: E402

OUT = Path(__file__).resolve().parent.parent / "crates" / "parsing" / "tests" / "data"
S = 32
MEAN = [0.5, 0.4, 0.3]
STD = [0.25, 0.2, 0.3]


def pattern_rgb(w, h):
    """Deterministic test image [h, w, 3] uint8; Rust: crates/parsing/tests/golden.rs."""
    u = np.arange(w, dtype=np.int64)[None, :]
    v = np.arange(h, dtype=np.int64)[:, None]
    r = (u * 7 + v * 3) % 256
    g = (u * v) % 251
    b = (u ^ v) & 255
    return np.stack(np.broadcast_arrays(r, g, b), axis=-1).astype(np.uint8)


def tiny_model(channels):
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    rng = np.random.default_rng(5)
    w1 = rng.normal(0, 0.5, (8, 3, 3, 3)).astype(np.float32)
    b1 = rng.normal(0, 0.1, (8,)).astype(np.float32)
    w2 = rng.normal(0, 0.7, (channels, 8, 1, 1)).astype(np.float32)
    b2 = rng.normal(0, 0.1, (channels,)).astype(np.float32)
    nodes = [
        helper.make_node("Conv", ["image", "w1", "b1"], ["h1"], kernel_shape=[3, 3], strides=[2, 2], pads=[1, 1, 1, 1]),
        helper.make_node("Relu", ["h1"], ["h2"]),
        helper.make_node("Conv", ["h2", "w2", "b2"], ["logits"], kernel_shape=[1, 1]),
    ]
    graph = helper.make_graph(
        nodes, "tiny_parser",
        [helper.make_tensor_value_info("image", TensorProto.FLOAT, ["batch", 3, S, S])],
        [helper.make_tensor_value_info("logits", TensorProto.FLOAT, ["batch", channels, S // 2, S // 2])],
        [numpy_helper.from_array(a, n) for a, n in [(w1, "w1"), (b1, "b1"), (w2, "w2"), (b2, "b2")]],
    )
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)], producer_name="bodyseg")
    model.ir_version = 8
    onnx.checker.check_model(model)
    return model


def main():
    import onnx
    import onnxruntime as ort

    OUT.mkdir(parents=True, exist_ok=True)
    onnx.save(tiny_model(7), str(OUT / "tiny.onnx"))
    onnx.save(tiny_model(5), str(OUT / "tiny_5ch.onnx"))
    pc.write_sidecar(OUT / "tiny.json", S, "BGR", MEAN, STD, True,
                     "tiny random test model written by scripts/gen_parsing_test_model.py")

    sess = ort.InferenceSession(str(OUT / "tiny.onnx"), providers=["CPUExecutionProvider"])
    # Fixed input: a smooth deterministic function of (n, c, y, x), Rust recomputes it.
    n, c, y, x = np.meshgrid(np.arange(2), np.arange(3), np.arange(S), np.arange(S), indexing="ij")
    inp = np.sin(0.37 * x + 0.23 * y + 1.1 * c + 2.3 * n).astype(np.float32) * 2.0
    logits = sess.run(None, {"image": inp})[0]

    # Whole chain on a 40x30 image.
    w, h = 40, 30
    rgb = pattern_rgb(w, h)
    chw = pc.normalize_chw(pc.warp_to_input(rgb, S), "BGR", MEAN, STD)
    out = sess.run(None, {"image": chw[None]})[0][0]
    ids, probs = pc.postprocess(out, w, h, S, True)
    golden = {
        "input_formula": "sin(0.37*x + 0.23*y + 1.1*c + 2.3*n) * 2, shape [2,3,32,32], float32",
        "input_shape": list(inp.shape),
        "logits_shape": list(logits.shape),
        "logits": [float(v) for v in logits.ravel()],
        "chain_image": [w, h],
        "chain_class_ids": [int(v) for v in ids.ravel()],
        "chain_probs": [round(float(v), 7) for v in probs.ravel()],
    }
    (OUT / "tiny_golden.json").write_text(json.dumps(golden) + "\n")

    pre = {"input_size": 512, "cases": []}
    for w, h in [(640, 480), (1920, 1080)]:
        samples = pc.warp_to_input_unrounded(pattern_rgb(w, h), 512)
        coords = sorted({(x, y) for x in [0, 1, 100, 255, 256, 300, 510, 511] for y in [0, 63, 64, 65, 66, 127, 128, 255, 383, 384, 447, 448, 449, 511]}
                        | {(int(a), int(b)) for a, b in np.random.default_rng(w).integers(0, 512, (40, 2))})
        pre["cases"].append({
            "width": w, "height": h,
            "input_from_image": pc.input_from_image(w, h, 512).tolist(),
            "image_from_input": pc.image_from_input(w, h, 512).tolist(),
            "samples": [[x, y] + [float(v) for v in samples[y, x]] for x, y in coords],
        })
    (OUT / "preprocess_golden.json").write_text(json.dumps(pre) + "\n")
    for p in sorted(OUT.iterdir()):
        print(f"{p}: {p.stat().st_size} bytes")


if __name__ == "__main__":
    main()
