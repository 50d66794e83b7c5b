#!/usr/bin/env python3
"""Overlays of 2D body-part predictions on the real photographs (issue 29, study tool).

    target/release/examples/real_parsing /tmp/pred/full blazepose:full poses=1
    .venv/bin/python scripts/real_parsing_overlay.py /tmp/pred/full --out /tmp/overlay [--name pp_2008_000652]

One PNG per image: photograph | ground truth / prediction | errors (2 x 2), each panel
with the person boxes; the prediction panel also with the pose's landmarks and bones when
`<name>.poses.json` is there (the example's `poses=1`): a landmark drawn filled when its
presence is >= 0.5, hollow otherwise; its colour goes from red (visibility 0) to green (1).
The errors panel: grey = right, red = a wrong part, blue = person missed, yellow = background
labelled as a person; white = not labelled in the ground truth. The per-image mIoU (parts
present in prediction or ground truth) and person IoU are printed and written in the title
strip.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / ".data" / "real_parsing"
# ALGORITHM.md §0 order: background, head, torso, upper arms, lower arms, upper legs, lower legs
COLOURS = np.array([[0, 0, 0], [230, 60, 60], [60, 160, 60], [60, 90, 230], [240, 200, 40],
                    [40, 200, 200], [200, 60, 200], [0, 0, 0]], np.uint8)
SUPER_GT = {0: 0, 1: 1, 2: 2, 7: 3, 8: 5}  # coarse ground truth -> a colour index
BONES = [(11, 12), (11, 23), (12, 24), (23, 24), (11, 13), (13, 15), (12, 14), (14, 16),
         (23, 25), (25, 27), (24, 26), (26, 28), (27, 29), (27, 31), (28, 30), (28, 32)]


def colourise(lab, coarse):
    out = np.zeros(lab.shape + (3,), np.uint8)
    if coarse:
        for k, c in SUPER_GT.items():
            out[lab == k] = COLOURS[c]
    else:
        for k in range(7):
            out[lab == k] = COLOURS[k]
    out[lab == 255] = 255
    return out


def blend(img, col, alpha=0.55):
    return (img.astype(np.float32) * (1 - alpha) + col.astype(np.float32) * alpha).astype(np.uint8)


def errors(gt, pred, coarse):
    out = np.full(gt.shape + (3,), 128, np.uint8)
    p = pred.copy()
    if coarse:
        p = np.array([0, 1, 2, 7, 7, 8, 8], np.int64)[np.clip(p, 0, 6)]
    wrong = (gt != 255) & (gt != 0) & (p != 0) & (gt != p)
    missed = (gt != 255) & (gt != 0) & (p == 0)
    extra = (gt == 0) & (p != 0)
    out[(gt == 0) & (p == 0)] = 30
    out[wrong] = [230, 40, 40]
    out[missed] = [40, 80, 255]
    out[extra] = [250, 230, 40]
    out[gt == 255] = 255
    return out


def scores(gt, pred, coarse):
    ok = gt != 255
    if coarse:
        pred = np.array([0, 1, 2, 7, 7, 8, 8], np.int64)[np.clip(pred, 0, 6)]
        parts = [1, 2, 7, 8]
    else:
        parts = [1, 2, 3, 4, 5, 6]
    ious = []
    for c in parts:
        a, b = (gt == c) & ok, (pred == c) & ok
        u = (a | b).sum()
        if u:
            ious.append((a & b).sum() / u)
    a, b = (gt != 0) & ok, (pred != 0) & ok
    person = (a & b).sum() / max((a | b).sum(), 1)
    return (float(np.mean(ious)) if ious else float("nan")), float(person)


def draw_pose(d, pose, k):
    xy = np.array(pose["xy"])
    pres, vis = np.array(pose["presence"]), np.array(pose["visibility"])
    for a, b in BONES:
        if pres[a] >= 0.5 and pres[b] >= 0.5:
            d.line([tuple(xy[a]), tuple(xy[b])], fill=(255, 255, 255), width=1)
    for i in range(33):
        x, y = xy[i]
        c = (int(255 * (1 - vis[i])), int(255 * vis[i]), 0)
        r = 3
        if pres[i] >= 0.5:
            d.ellipse([x - r, y - r, x + r, y + r], fill=c)
        else:
            d.ellipse([x - r, y - r, x + r, y + r], outline=c)
    cx, cy = xy[33]
    d.text((cx + 4, cy), f"#{k} f{pose['flag']:.2f}", fill=(255, 255, 255))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("pred")
    ap.add_argument("--out", required=True)
    ap.add_argument("--name", action="append")
    ap.add_argument("--data", default=str(DATA))
    args = ap.parse_args()
    data, pred_dir, out = Path(args.data), Path(args.pred), Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    index = json.loads((data / "index.json").read_text())
    for item in index:
        name = item["name"]
        if args.name and name not in args.name:
            continue
        coarse = item["scheme"] != "parts7"
        img = np.asarray(Image.open(data / "images" / f"{name}.jpg").convert("RGB"))
        gt = np.asarray(Image.open(data / "labels" / f"{name}.png")).astype(np.int64)
        pp = pred_dir / f"{name}.png"
        if not pp.exists():
            print(f"{name}: no prediction", file=sys.stderr)
            continue
        pred = np.asarray(Image.open(pp)).astype(np.int64)
        panels = [img, blend(img, colourise(gt, coarse)), blend(img, colourise(pred, False)),
                  errors(gt, pred, coarse)]
        h, w = img.shape[:2]
        poses_path = pred_dir / f"{name}.poses.json"
        if poses_path.exists():
            sub = Image.fromarray(panels[2])
            sd = ImageDraw.Draw(sub)
            for k, pose in enumerate(json.loads(poses_path.read_text())):
                if pose is not None:
                    draw_pose(sd, pose, k)
            panels[2] = np.asarray(sub)
        # 2 x 2 panels, small photographs enlarged to ~700 px wide panels
        zoom = max(1, int(700 // max(w, 1)))
        canvas = Image.new("RGB", (2 * w * zoom + 4, 2 * h * zoom + 18), (255, 255, 255))
        d = ImageDraw.Draw(canvas)
        for k, p in enumerate(panels):
            ox, oy = (k % 2) * (w * zoom + 4), 14 + (k // 2) * (h * zoom + 4)
            canvas.paste(Image.fromarray(p).resize((w * zoom, h * zoom), Image.NEAREST), (ox, oy))
            for b in item["person_boxes"]:
                x0, y0, x1, y1 = (v * zoom for v in b)
                d.rectangle([x0 + ox, y0 + oy, x1 + ox, y1 + oy], outline=(255, 255, 255))
        miou, person = scores(gt, pred, coarse)
        title = f"{name}  mIoU {miou:.3f}  person {person:.3f}"
        d.text((2, 1), title, fill=(0, 0, 0))
        print(title)
        canvas.save(out / f"{name}.png")


if __name__ == "__main__":
    main()
