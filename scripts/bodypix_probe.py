#!/usr/bin/env python3
"""BodyPix 2.0 body parts on the real photographs (feasibility probe, 2026-12-04; results and
where the weights come from: docs/notes/2026-12-04-bodypix-probe.md).

    .venv/bin/python scripts/bodypix_probe.py OUT_DIR --model M.onnx|M.tflite [--margin 0.3]
        [--res 513] [--threshold 0.7] [--threads 1] [--mode crops|full]
        [--fuse BLAZEPOSE_DIR [--fuse-keep 5,6] [--fuse-mask other|bodypix|union]]
    .venv/bin/python scripts/score_parsing.py --pred bodypix=OUT_DIR --pred full=BLAZEPOSE_DIR

Needs numpy, pillow, scipy, onnx, onnxruntime and, for .tflite, ai-edge-litert. Writes
`<name>.png` (class ids 0-6, shared/ALGORITHM.md §0, the image's size) per image of
.data/real_parsing/ (scripts/real_parsing_data.py) for scripts/score_parsing.py, and
`timing.json` (inference milliseconds per run, wall clock).

Model: a BodyPix 2.0 graph at output stride 16 with the outputs `segments` /
`float_segments` (1 channel, logits) and `part_heatmaps` / `float_part_heatmaps` (24
channels, logits, in the body-pix JS source's PART_CHANNELS order), NHWC input of any size:
- `.onnx` with float input: a tfjs MobileNetV1 conversion, input x / 127.5 - 1 (body-pix's
  MobileNet preprocessing; `--resnet`: x + [-123.15, -115.90, -103.06], ResNet50's);
- `.onnx` with uint8 input: scripts/bodypix_onnx.py's conversions of the Coral graphs
  (outputs uint8 for the QDQ one: dequantised with the scales of the .tflite beside it);
- `.tflite` (LiteRT): the Coral uint8 graphs (input = raw 8-bit RGB; quantisation scale
  1/128, zero point 128, i.e. x / 128 - 1), outputs dequantised.
Each input side is 16 k + 1 as body-pix sizes its inputs, or 16 k for the Coral graphs (their
first op pads one pixel after), so that output cell i sits on input pixel 16 i.

Regions (--mode crops, default): for each person box of index.json, a crop of the box
widened by --margin x its size on each side (black outside the image), resized (bilinear) so
that its longer side is --res px. Outputs are sampled back bilinearly (align corners) at
every image pixel the crop covers; where crops overlap, the crop with the highest person
probability wins the pixel. --mode full: one run on the whole image (longer side --res).

Labels: person where sigmoid(segments) >= --threshold, its part = argmax of the 24 part
logits mapped to the 7 classes (faces -> head; torso front/back -> torso; upper arms; lower
arms + hands; upper legs; lower legs + feet). --fuse DIR: another segmenter's label PNGs
(BlazePose full's): the person region is theirs (--fuse-mask other), BodyPix's, or the union;
the part is BodyPix's argmax (of the crop with the highest person probability, whatever that
probability), except the classes --fuse-keep lists, kept where the other segmenter gives them.
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image
from scipy import ndimage

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / ".data" / "real_parsing"

# body-pix PART_CHANNELS (24) -> our class ids (ALGORITHM.md §0)
PART_CHANNELS = [
    "left_face", "right_face",
    "left_upper_arm_front", "left_upper_arm_back", "right_upper_arm_front", "right_upper_arm_back",
    "left_lower_arm_front", "left_lower_arm_back", "right_lower_arm_front", "right_lower_arm_back",
    "left_hand", "right_hand",
    "torso_front", "torso_back",
    "left_upper_leg_front", "left_upper_leg_back", "right_upper_leg_front", "right_upper_leg_back",
    "left_lower_leg_front", "left_lower_leg_back", "right_lower_leg_front", "right_lower_leg_back",
    "left_feet", "right_feet",
]


def part_to_class(name):
    if name.endswith("face"):
        return 1
    if name.startswith("torso"):
        return 2
    if "upper_arm" in name:
        return 3
    if "lower_arm" in name or name.endswith("hand"):
        return 4
    if "upper_leg" in name:
        return 5
    return 6  # lower legs, feet


PART_TO_CLASS = np.array([part_to_class(n) for n in PART_CHANNELS], np.uint8)
IMAGENET_MEAN_OFFSET = np.array([-123.15, -115.90, -103.06], np.float32)


class Model:
    """One BodyPix graph; run(rgb uint8 HxWx3) -> (segment logits h x w, part logits h x w x 24)."""

    def __init__(self, path, threads=1, resnet=False):
        self.path = Path(path)
        self.resnet = resnet
        if self.path.suffix == ".onnx":
            import onnxruntime as ort
            so = ort.SessionOptions()
            so.intra_op_num_threads = threads
            so.inter_op_num_threads = 1
            self.sess = ort.InferenceSession(str(self.path), so, providers=["CPUExecutionProvider"])
            self.input = self.sess.get_inputs()[0].name
            names = [o.name for o in self.sess.get_outputs()]
            self.seg = next(n for n in names if n.endswith("segments"))
            self.parts = next(n for n in names if n.endswith("part_heatmaps"))
            self.kind = "onnx"
            import onnx
            graph = onnx.load(str(self.path)).graph
            self.pads_input = any(n.name.startswith("pad_input") for n in graph.node)
            self.uint8 = graph.input[0].type.tensor_type.elem_type == onnx.TensorProto.UINT8
            self.quant = {}  # uint8 outputs of a QDQ graph: name -> (scale, zero point)
            sidecar = self.path.with_suffix(".json")  # models/bodypix_*.json: the scales
            if graph.output[0].type.tensor_type.elem_type == onnx.TensorProto.UINT8 and sidecar.exists():
                outs = json.loads(sidecar.read_text())["outputs"]
                self.quant = {n: (outs[n]["scale"], outs[n]["zero_point"]) for n in (self.seg, self.parts)}
            elif graph.output[0].type.tensor_type.elem_type == onnx.TensorProto.UINT8:
                tflite = self.path.parent / (self.path.name.split(".")[0] + ".tflite")
                from ai_edge_litert.interpreter import Interpreter
                for d in Interpreter(model_path=str(tflite)).get_output_details():
                    self.quant[d["name"]] = d["quantization"]
        else:
            from ai_edge_litert.interpreter import Interpreter
            self.it = Interpreter(model_path=str(self.path), num_threads=threads)
            self.inp = self.it.get_input_details()[0]
            self.kind = "tflite"
            self.shape = None
            self.pads_input = any(o["op_name"] == "PAD" for o in self.it._get_ops_details()[:2])

    def run(self, rgb):
        if self.kind == "onnx":
            if self.uint8:  # a conversion of the Coral graphs: raw RGB in
                x = rgb.astype(np.uint8)
            else:
                x = rgb.astype(np.float32)
                x = x + IMAGENET_MEAN_OFFSET if self.resnet else x / 127.5 - 1.0
            seg, parts = self.sess.run([self.seg, self.parts], {self.input: x[None]})
            if self.quant:
                (s1, z1), (s2, z2) = self.quant[self.seg], self.quant[self.parts]
                seg = (seg.astype(np.float32) - z1) * s1
                parts = (parts.astype(np.float32) - z2) * s2
            return seg[0, :, :, 0], parts[0]
        shape = [1, rgb.shape[0], rgb.shape[1], 3]
        if shape != self.shape:
            self.it.resize_tensor_input(self.inp["index"], shape)
            self.it.allocate_tensors()
            self.shape = shape
            outs = {d["name"]: d for d in self.it.get_output_details()}
            self.seg_d = next(d for n, d in outs.items() if n.endswith("segments"))
            self.parts_d = next(d for n, d in outs.items() if n.endswith("part_heatmaps"))
        self.it.set_tensor(self.inp["index"], rgb[None].astype(np.uint8))
        self.it.invoke()

        def deq(d):
            v = self.it.get_tensor(d["index"]).astype(np.float32)
            s, z = d["quantization"]
            return (v - z) * s if s else v

        return deq(self.seg_d)[0, :, :, 0], deq(self.parts_d)[0]


def snap(n, stride=16, pads_input=False):
    """Input side: 16 k + 1 (output cell i on input pixel 16 i, as body-pix sizes its
    inputs); 16 k for the Coral graphs, whose first op pads one pixel after (bottom, right)."""
    k = max(1, int(round((n - 1) / stride)))
    return k * stride + (0 if pads_input else 1)


def run_region(model, img, rect, res, stride=16):
    """Runs the model on `rect` (x0, y0, x1, y1: pixel edges, may leave the image) of `img`
    resized to longer side `res`; returns (ys, xs, person prob, part logits) at the image
    pixels the rect covers, and the inference time (s)."""
    x0, y0, x1, y1 = rect
    w, h = x1 - x0, y1 - y0
    k = res / max(w, h)
    win, hin = snap(w * k, stride, model.pads_input), snap(h * k, stride, model.pads_input)
    crop = img.transform((win, hin), Image.EXTENT, (x0, y0, x1, y1), Image.BILINEAR)
    t = time.perf_counter()
    seg, parts = model.run(np.asarray(crop))
    dt = time.perf_counter() - t
    s = stride  # output cell i <-> input pixel s * i (align corners)
    W, H = img.size
    ix0, iy0 = max(0, int(np.floor(x0))), max(0, int(np.floor(y0)))
    ix1, iy1 = min(W, int(np.ceil(x1))), min(H, int(np.ceil(y1)))
    ys, xs = np.mgrid[iy0:iy1, ix0:ix1]
    # image pixel centre -> crop input pixel (PIL EXTENT) -> output cell (align corners)
    cx = ((xs + 0.5 - x0) * win / w - 0.5) / s
    cy = ((ys + 0.5 - y0) * hin / h - 0.5) / s
    coords = np.stack([cy.ravel(), cx.ravel()])
    prob = 1 / (1 + np.exp(-ndimage.map_coordinates(seg, coords, order=1, mode="nearest")))
    logits = np.stack([ndimage.map_coordinates(parts[..., c], coords, order=1, mode="nearest")
                       for c in range(parts.shape[-1])], -1)
    return ys.ravel(), xs.ravel(), prob, logits, dt


def widen(box, margin):
    x0, y0, x1, y1 = box  # inclusive pixel centres
    w, h = x1 - x0 + 1, y1 - y0 + 1
    return (x0 - margin * w, y0 - margin * h, x1 + 1 + margin * w, y1 + 1 + margin * h)


def parse_image(model, img, boxes, args):
    W, H = img.size
    best = np.full((H, W), -1.0, np.float32)
    part = np.zeros((H, W), np.uint8)
    times = []
    rects = [(0, 0, W, H)] if args.mode == "full" else [widen(b, args.margin) for b in boxes]
    for rect in rects:
        ys, xs, prob, logits, dt = run_region(model, img, rect, args.res)
        times.append(dt)
        better = prob > best[ys, xs]
        ys, xs = ys[better], xs[better]
        best[ys, xs] = prob[better]
        part[ys, xs] = PART_TO_CLASS[np.argmax(logits[better], -1)]
    return best, part, times


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out")
    ap.add_argument("--model", required=True)
    ap.add_argument("--resnet", action="store_true", help="ResNet50 preprocessing (ONNX)")
    ap.add_argument("--mode", choices=("crops", "full"), default="crops")
    ap.add_argument("--res", type=int, default=513)
    ap.add_argument("--margin", type=float, default=0.15)
    ap.add_argument("--threshold", type=float, default=0.7)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--fuse", help="a folder of label PNGs whose person region is used")
    ap.add_argument("--fuse-keep", default="",
                    help="with --fuse: class ids (e.g. 5,6) kept from the --fuse labels")
    ap.add_argument("--fuse-mask", choices=("other", "bodypix", "union"), default="other",
                    help="with --fuse: the person region: the other segmenter's (default), "
                         "BodyPix's (>= --threshold), or their union")
    ap.add_argument("--data", default=str(DATA))
    ap.add_argument("--name", action="append", help="only these images")
    args = ap.parse_args(argv)

    index = json.loads((Path(args.data) / "index.json").read_text())
    model = Model(args.model, args.threads, args.resnet)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    timing = {}
    for item in index:
        if args.name and item["name"] not in args.name:
            continue
        img = Image.open(Path(args.data) / "images" / f"{item['name']}.jpg").convert("RGB")
        best, part, times = parse_image(model, img, item["person_boxes"], args)
        if args.fuse:
            other = np.asarray(Image.open(Path(args.fuse) / f"{item['name']}.png"))
            mine = best >= args.threshold
            person = {"other": other > 0, "bodypix": mine, "union": (other > 0) | mine}[args.fuse_mask]
            labels = np.where(person, part, 0).astype(np.uint8)
            keep = [int(c) for c in args.fuse_keep.split(",") if c]
            if keep:
                kept = np.isin(other, keep) & person
                labels[kept] = other[kept]
        else:
            labels = np.where(best >= args.threshold, part, 0).astype(np.uint8)
        Image.fromarray(labels).save(out / f"{item['name']}.png")
        timing[item["name"]] = [round(t * 1000, 1) for t in times]
    all_ms = [t for v in timing.values() for t in v]
    summary = {"model": str(args.model), "mode": args.mode, "res": args.res, "threads": args.threads,
               "crops": len(all_ms), "median_ms": float(np.median(all_ms)) if all_ms else None,
               "mean_ms": float(np.mean(all_ms)) if all_ms else None, "per_image_ms": timing}
    (out / "timing.json").write_text(json.dumps(summary, indent=1) + "\n")
    print(f"{len(timing)} images, {len(all_ms)} runs, median {summary['median_ms']:.0f} ms "
          f"(mean {summary['mean_ms']:.0f} ms) per run -> {out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
