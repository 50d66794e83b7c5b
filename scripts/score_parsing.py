#!/usr/bin/env python3
"""Scores 2D body-part label maps against the real-image ground truth (issue 29, part 4).

    python3 scripts/score_parsing.py --pred synthetic=out/synth --pred full=out/full
    python3 scripts/score_parsing.py --pred full=out/full --split test

Predictions: one folder per segmenter, `<name>.png` per image (8-bit class ids, the 7 classes
of shared/ALGORITHM.md §0, at the image's size), as written by scripts/segment_schp.py and
scripts/blazepose_prototype.py. Ground truth: .data/real_parsing/ (scripts/real_parsing_data.py).

Metrics (pixels pooled over the images of a set into one confusion matrix, as ALGORITHM.md
§6 pools points; ground-truth pixels 255 are left out):
- exact set (ground truth "parts7", Pascal-Person-Part classes): IoU per class, body-part
  mIoU = mean IoU of the 6 body parts, person-vs-background IoU (any part vs background).
- coarse set ("super5", LIP/CIHP/ATR): predictions are merged to super-classes (upper +
  lower arms -> arms, upper + lower legs -> legs): IoU of head, torso, arms, legs, their
  mean, and person-vs-background IoU.
A class absent from both prediction and ground truth of a set is left out of the mean.

--split: "tune" = the even-indexed images of each set (sorted by name) among those without a
split in the index, "test" = the odd ones, "dev" = tune + test, "holdout" = the images the
index marks "holdout" (added after the rule was tuned; never looked at while tuning),
"all" (default) = every image. The rule is tuned on "tune" only.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT / ".data" / "real_parsing"
IGNORE = 255
PARTS7 = ["background", "head", "torso", "upper_arms", "lower_arms", "upper_legs", "lower_legs"]
SUPER = ["background", "head", "torso", "arms", "legs"]
# parts7 id -> super id; the coarse ground truth's ids 0 1 2 7 8 -> super id
PRED_TO_SUPER = np.array([0, 1, 2, 3, 3, 4, 4], np.int64)
GT_SUPER_LUT = np.full(256, -1, np.int64)
GT_SUPER_LUT[[0, 1, 2, 7, 8]] = [0, 1, 2, 3, 4]


def load_index(data):
    path = Path(data) / "index.json"
    if not path.exists():
        return None
    return json.loads(path.read_text())


SPLITS = ("all", "dev", "tune", "test", "holdout")


def split_items(index, split):
    out = []
    for scheme in ("parts7", "super5"):
        items = sorted((r for r in index if r["scheme"] == scheme), key=lambda r: r["name"])
        if split == "holdout":
            out += [r for r in items if r.get("split") == "holdout"]
            continue
        if split != "all":
            items = [r for r in items if r.get("split") != "holdout"]
        if split == "tune":
            items = items[0::2]
        elif split == "test":
            items = items[1::2]
        out += items
    return out


def confusion(gt, pred, n):
    """n x n confusion (rows ground truth, columns prediction) of two id maps; gt < 0 skipped."""
    keep = gt >= 0
    return np.bincount(gt[keep] * n + pred[keep], minlength=n * n).reshape(n, n)


def iou_per_class(cm):
    tp = np.diag(cm).astype(np.float64)
    denom = cm.sum(0) + cm.sum(1) - tp
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(denom > 0, tp / denom, np.nan)


def person_iou(cm):
    """IoU of 'any body class' against background, from a confusion matrix (class 0 = bg)."""
    tp = cm[1:, 1:].sum()
    fp = cm[0, 1:].sum()
    fn = cm[1:, 0].sum()
    return tp / (tp + fp + fn) if tp + fp + fn > 0 else np.nan


def score_pair(scheme, gt, pred):
    """Confusion matrix of one image: 7x7 for parts7, 5x5 (super) for super5."""
    if gt.shape != pred.shape:
        raise ValueError(f"prediction {pred.shape[::-1]} vs ground truth {gt.shape[::-1]}")
    if pred.max(initial=0) > 6:
        raise ValueError(f"prediction has class id {pred.max()} > 6")
    pred = pred.astype(np.int64)
    if scheme == "parts7":
        g = gt.astype(np.int64)
        g[gt == IGNORE] = -1
        if g.max(initial=0) > 6:
            raise ValueError(f"ground truth has class id {g.max()}")
        return confusion(g, pred, 7)
    g = GT_SUPER_LUT[gt]
    return confusion(g, PRED_TO_SUPER[pred], 5)


def summarize(scheme, cm):
    iou = iou_per_class(cm)
    body = iou[1:]
    return {"iou": iou, "miou_body": float(np.nanmean(body)) if np.any(~np.isnan(body)) else np.nan,
            "person_iou": float(person_iou(cm)), "pixels": int(cm.sum())}


def score_folder(pred_dir, items, data):
    from PIL import Image

    cms = {"parts7": np.zeros((7, 7), np.int64), "super5": np.zeros((5, 5), np.int64)}
    counts = {"parts7": 0, "super5": 0}
    missing = []
    for r in items:
        p = Path(pred_dir) / f"{r['name']}.png"
        if not p.exists():
            missing.append(r["name"])
            continue
        gt = np.asarray(Image.open(Path(data) / "labels" / f"{r['name']}.png"))
        pred = np.asarray(Image.open(p))
        try:
            cms[r["scheme"]] += score_pair(r["scheme"], gt, pred)
        except ValueError as e:
            raise SystemExit(f"{p}: {e}")
        counts[r["scheme"]] += 1
    return cms, counts, missing


def fmt(x):
    return "–" if x is None or np.isnan(x) else f"{x:.3f}"


def table(results, scheme, title, classes, mean_name, bold):
    """Markdown lines of one set's table (none when no image of the set was scored)."""
    rows = [(n, r) for n, r in results if r["counts"][scheme]]
    if not rows:
        return []
    star = "**" if bold else ""
    lines = [f"{title}, {rows[0][1]['counts'][scheme]} images)", "",
             "| segmenter | " + " | ".join(classes[1:]) + f" | {mean_name} | person vs bg |",
             "|---|" + "---:|" * (len(classes) + 1)]
    for name, r in rows:
        s = summarize(scheme, r["cms"][scheme])
        lines.append(f"| {name} | " + " | ".join(fmt(v) for v in s["iou"][1:])
                     + f" | {star}{fmt(s['miou_body'])}{star} | {star}{fmt(s['person_iou'])}{star} |")
    return lines + [""]


def tables(results):
    """Markdown: one table for the exact set, one for the coarse set; a row per segmenter."""
    return "\n".join(
        table(results, "parts7", "Exact 7-class ground truth (Pascal-Person-Part classes",
              PARTS7, "mIoU (6 parts)", True)
        + table(results, "super5", "Coarse ground truth (LIP/CIHP/ATR super-classes",
                SUPER, "mIoU (4)", False))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--pred", action="append", required=True, metavar="NAME=DIR",
                    help="a segmenter's label PNGs (repeatable)")
    ap.add_argument("--data", default=str(DATA))
    ap.add_argument("--split", choices=SPLITS, default="all")
    ap.add_argument("--json", help="also write the confusion matrices and metrics here")
    args = ap.parse_args(argv)

    index = load_index(args.data)
    if index is None:
        print(f"{args.data}: no index.json (run scripts/real_parsing_data.py)", file=sys.stderr)
        return 2
    items = split_items(index, args.split)
    results = []
    for spec in args.pred:
        if "=" not in spec:
            ap.error(f"--pred {spec}: expected NAME=DIR")
        name, folder = spec.split("=", 1)
        cms, counts, missing = score_folder(folder, items, args.data)
        if missing:
            print(f"{name}: {len(missing)} predictions missing in {folder} "
                  f"(first: {missing[0]}.png); scored without them", file=sys.stderr)
        results.append((name, {"cms": cms, "counts": counts}))
    print(f"split: {args.split}\n")
    print(tables(results))
    if args.json:
        out = {name: {k: {"confusion": r["cms"][k].tolist(), "images": r["counts"][k],
                          **{m: (v.tolist() if isinstance(v, np.ndarray) else v)
                             for m, v in summarize(k, r["cms"][k]).items()}}
                      for k in ("parts7", "super5")} for name, r in results}
        Path(args.json).write_text(json.dumps(out, indent=1, default=float) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
