#!/usr/bin/env python3
"""Runs an SCHP-compatible parsing model (shared/ALGORITHM.md §2: ONNX + sidecar JSON) on the
real-image benchmark's photographs and writes one label PNG per image, as `bodyseg parse`
would (whole image as the box; pre- and post-processing of scripts/parsing_common.py, the
reference of crates/parsing/src/transform.rs).

    python3 scripts/segment_schp.py --model models/bodyseg_parser_small.onnx --out /tmp/pred/synthetic
    python3 scripts/score_parsing.py --pred synthetic=/tmp/pred/synthetic
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import parsing_common as pc  # noqa: E402
from score_parsing import DATA, load_index  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--model", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--data", default=str(DATA))
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args(argv)

    import onnxruntime as ort
    from PIL import Image

    spec = json.loads(Path(args.model).with_suffix(".json").read_text())
    s = int(spec["input_size"][0])
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = args.threads
    opts.inter_op_num_threads = 1
    sess = ort.InferenceSession(args.model, opts, providers=["CPUExecutionProvider"])
    name = sess.get_inputs()[0].name
    index = load_index(args.data)
    if index is None:
        raise SystemExit(f"{args.data}: no index.json (run scripts/real_parsing_data.py)")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_total = 0.0
    for r in index:
        rgb = np.asarray(Image.open(Path(args.data) / "images" / f"{r['name']}.jpg").convert("RGB"))
        h, w = rgb.shape[:2]
        t0 = time.perf_counter()
        x = pc.normalize_chw(pc.warp_to_input(rgb, s), spec["channel_order"], spec["mean"], spec["std"])
        logits = sess.run(None, {name: x[None]})[0][0]
        ids, _ = pc.postprocess(logits, w, h, s, spec.get("align_corners", False))
        t_total += time.perf_counter() - t0
        Image.fromarray(ids).save(out / f"{r['name']}.png")
    print(f"{len(index)} images -> {out} ({1000 * t_total / max(len(index), 1):.0f} ms/image)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
