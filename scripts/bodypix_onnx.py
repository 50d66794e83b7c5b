#!/usr/bin/env python3
"""Makes tf2onnx's conversion of a Coral BodyPix TFLite graph take any input size, and checks
it against the TFLite interpreter (feasibility probe, docs/notes/2026-12-04-bodypix-probe.md).

    # tf2onnx needs tensorflow (scripts/requirements-blazepose.txt); M = the .tflite, no suffix
    python -m tf2onnx.convert --tflite M.tflite --output M.qdq.raw.onnx --opset 17
    python -m tf2onnx.convert --tflite M.tflite --output M.dequant.raw.onnx --opset 17 --dequantize
    .venv/bin/python scripts/bodypix_onnx.py M.tflite M.qdq.raw.onnx M.qdq.onnx
    .venv/bin/python scripts/bodypix_onnx.py M.tflite M.dequant.raw.onnx M.dequant.onnx

tf2onnx keeps the TFLite file's fixed input (1 x 1280 x 720 x 3) and writes the segment
output through a Reshape to that size. This script renames the input's height and width to
symbolic dims, turns that Reshape into the NCHW -> NHWC Transpose it stands for, and, for a
`--dequantize` conversion (float weights and activations, uint8 RGB in), drops the final
QuantizeLinear ops so that the outputs are float logits. The convolutions' explicit pads
(1 each side) are TF's SAME padding for the odd sizes the graph sees after its first op pads
the input by one pixel (bottom, right), so inputs of 16 k x 16 k' keep TF's semantics.

Check: on crops of the real photographs (person boxes of .data/real_parsing/, longer side
513 -> 512 x 16 k) and one random image, ONNX Runtime vs the TFLite interpreter (XNNPACK off):
max |difference| of the segment and part logits (dequantised), the share of pixels whose
part argmax and person mask (sigmoid >= 0.7) agree.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np
import onnx
from onnx import TensorProto, helper

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / ".data" / "real_parsing"


def make_dynamic(model):
    g = model.graph
    dims = g.input[0].type.tensor_type.shape.dim
    dims[1].dim_param, dims[2].dim_param = "height", "width"
    for o in g.output:
        d = o.type.tensor_type.shape.dim
        d[1].dim_param, d[2].dim_param = "out_height", "out_width"
    dequantized = g.input[0].type.tensor_type.elem_type == TensorProto.UINT8 and not any(
        n.op_type == "DequantizeLinear" for n in g.node)
    outputs = {o.name for o in g.output}
    consumers = {}
    for n in g.node:
        for i in n.input:
            consumers.setdefault(i, []).append(n)
    new_nodes = []
    for n in g.node:
        if n.op_type == "Reshape" and n.output[0] in outputs:
            new_nodes.append(helper.make_node("Transpose", [n.input[0]], list(n.output),
                                              name=n.name, perm=[0, 2, 3, 1]))
            continue
        if dequantized and n.op_type == "QuantizeLinear":
            # feeds an output through Transpose / Reshape / Concat only
            new_nodes.append(helper.make_node("Identity", [n.input[0]], list(n.output), name=n.name))
            continue
        new_nodes.append(n)
    del g.node[:]
    g.node.extend(new_nodes)
    if dequantized:
        for o in g.output:
            o.type.tensor_type.elem_type = TensorProto.FLOAT
    del g.value_info[:]
    used = {i for n in g.node for i in n.input}
    keep = [t for t in g.initializer if t.name in used]
    del g.initializer[:]
    g.initializer.extend(keep)
    onnx.checker.check_model(model)
    return model


def tflite_run(path, x):
    from ai_edge_litert.interpreter import Interpreter, OpResolverType
    it = Interpreter(model_path=str(path),
                     experimental_op_resolver_type=OpResolverType.BUILTIN_WITHOUT_DEFAULT_DELEGATES)
    inp = it.get_input_details()[0]
    it.resize_tensor_input(inp["index"], list(x.shape))
    it.allocate_tensors()
    it.set_tensor(inp["index"], x)
    it.invoke()
    out = {}
    for d in it.get_output_details():
        v = it.get_tensor(d["index"]).astype(np.float32)
        s, z = d["quantization"]
        out[d["name"]] = (v - z) * s if s else v
    quant = {d["name"]: d["quantization"] for d in it.get_output_details()}
    return out, quant


def onnx_run(sess, x, quant):
    names = [o.name for o in sess.get_outputs()]
    vals = sess.run(names, {sess.get_inputs()[0].name: x})
    out = {}
    for n, v in zip(names, vals):
        v = v.astype(np.float32)
        if vals[0].dtype == np.uint8:
            s, z = quant[n]
            v = (v - z) * s
        out[n] = v
    return out


def inputs(n_crops):
    from PIL import Image
    xs = []
    index = json.loads((DATA / "index.json").read_text()) if (DATA / "index.json").exists() else []
    for item in index:
        img = Image.open(DATA / "images" / f"{item['name']}.jpg").convert("RGB")
        for x0, y0, x1, y1 in item["person_boxes"]:
            w, h = x1 - x0 + 1, y1 - y0 + 1
            rect = (x0 - 0.15 * w, y0 - 0.15 * h, x1 + 1 + 0.15 * w, y1 + 1 + 0.15 * h)
            k = 513 / max(rect[2] - rect[0], rect[3] - rect[1])
            size = (max(16, round((rect[2] - rect[0]) * k / 16) * 16),
                    max(16, round((rect[3] - rect[1]) * k / 16) * 16))
            xs.append(np.asarray(img.transform(size, Image.EXTENT, rect, Image.BILINEAR))[None])
            if len(xs) >= n_crops:
                break
        if len(xs) >= n_crops:
            break
    rng = np.random.default_rng(0)
    xs.append(rng.integers(0, 256, (1, 320, 256, 3), dtype=np.uint8))
    return xs


def check(tflite, onnx_path, n_crops):
    import onnxruntime as ort
    so = ort.SessionOptions()
    so.intra_op_num_threads = 1
    sess = ort.InferenceSession(str(onnx_path), so, providers=["CPUExecutionProvider"])
    worst = {"segments": 0.0, "part_heatmaps": 0.0}
    agree_part, agree_mask, steps = [], [], {}
    for x in inputs(n_crops):
        ref, quant = tflite_run(tflite, x)
        got = onnx_run(sess, x, quant)
        for key in worst:
            name = f"float_{key}"
            d = float(np.abs(ref[name] - got[name]).max())
            worst[key] = max(worst[key], d)
            steps[key] = quant[name][0]
        mask_r = 1 / (1 + np.exp(-ref["float_segments"])) >= 0.7
        mask_g = 1 / (1 + np.exp(-got["float_segments"])) >= 0.7
        agree_mask.append(float((mask_r == mask_g).mean()))
        agree_part.append(float((ref["float_part_heatmaps"].argmax(-1)
                                 == got["float_part_heatmaps"].argmax(-1)).mean()))
    report = {"inputs": len(agree_part),
              "max_abs_diff": worst,
              "max_abs_diff_in_output_steps": {k: worst[k] / steps[k] for k in worst},
              "part_argmax_agreement_min": min(agree_part),
              "mask_agreement_min": min(agree_mask)}
    print(json.dumps(report, indent=1))
    return report


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("tflite")
    ap.add_argument("raw_onnx", help="tf2onnx's output")
    ap.add_argument("out_onnx")
    ap.add_argument("--crops", type=int, default=20)
    args = ap.parse_args(argv)
    model = make_dynamic(onnx.load(args.raw_onnx))
    onnx.save(model, args.out_onnx)
    check(args.tflite, args.out_onnx, args.crops)
    return 0


if __name__ == "__main__":
    sys.exit(main())
