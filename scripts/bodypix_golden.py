#!/usr/bin/env python3
"""The Python reference of crates/parsing/tests/bodypix.rs: BodyPix's labels (person >= 0.7,
the part's class) on the synthetic two-person view, with scripts/bodypix_probe.py's crop,
sizes and sampling (margin 0.3, longer side 513 -> 512) and ONNX Runtime in Python.

    BODYSEG_BODYPIX_INPUT=/tmp/bp cargo test --release -p bodyseg-parsing --test bodypix
    .venv/bin/python scripts/bodypix_golden.py /tmp/bp   # -> crates/parsing/tests/data/bodypix_two_people_labels.png

Needs numpy, pillow, scipy, onnx and onnxruntime (scripts/requirements-blazepose.txt). The
uint8 outputs are dequantised with the scales of the model's sidecar JSON (as the probe does).
"""

import json
import sys
from pathlib import Path

import numpy as np
from PIL import Image

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bodypix_probe as probe  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
MODEL = ROOT / "models" / "bodypix_mobilenet_v1_075_quant.onnx"
OUT = ROOT / "crates" / "parsing" / "tests" / "data" / "bodypix_two_people_labels.png"


def main(argv):
    src = Path(argv[1])
    model = probe.Model(MODEL)
    img = Image.open(src / "two_people.png").convert("RGB")
    boxes = json.loads((src / "two_people.json").read_text())["person_boxes"]
    args = type("Args", (), {"mode": "crops", "margin": 0.3, "res": 513})()
    best, part, _ = probe.parse_image(model, img, boxes, args)
    labels = np.where(best >= 0.7, part, 0).astype(np.uint8)
    Image.fromarray(labels).save(OUT)
    print(f"{OUT}: {int((labels > 0).sum())} person pixels, classes {np.bincount(labels.ravel(), minlength=7).tolist()}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
