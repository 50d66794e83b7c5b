#!/usr/bin/env python3
"""Generate crates/eval/tests/data/sklearn_fixture.json: scikit-learn's reference metrics.

One-off generator; its output is committed and read by crates/eval/tests/sklearn.rs, which
checks bodyseg-eval's confusion matrix and per-class IoU / precision / recall / F1 against
scikit-learn (ALGORITHM.md §6). Re-run only to change the cases:

    pip install numpy scikit-learn
    python3 scripts/gen_eval_fixture.py

Labels are the 7 class ids 0..6 (0 = background). Every metric uses average=None,
labels=range(7), zero_division=0, which is the convention bodyseg-eval follows.
"""

import json
import pathlib
import warnings

import numpy as np
import sklearn
from sklearn.metrics import (
    confusion_matrix,
    f1_score,
    jaccard_score,
    precision_score,
    recall_score,
)

SEED = 20240607
LABELS = list(range(7))
OUT = pathlib.Path(__file__).resolve().parent.parent / "crates/eval/tests/data/sklearn_fixture.json"


def corrupt(rng, y_true, rate, choices):
    """y_true with a fraction `rate` of entries replaced by a random label from `choices`."""
    y_pred = y_true.copy()
    flip = rng.random(len(y_true)) < rate
    y_pred[flip] = rng.choice(choices, size=int(flip.sum()))
    return y_pred


def make_cases(rng):
    cases = []

    # All 7 classes in truth and prediction; background dominates as in a real scene.
    p = np.array([0.4, 0.1, 0.15, 0.08, 0.08, 0.1, 0.09])
    y_true = rng.choice(LABELS, size=300, p=p)
    cases.append(("all_present", y_true, corrupt(rng, y_true, 0.25, LABELS)))

    # Class 3 (upper_arms) absent from both truth and prediction: left out of the means.
    without3 = [c for c in LABELS if c != 3]
    y_true = rng.choice(without3, size=250)
    cases.append(("absent_from_both", y_true, corrupt(rng, y_true, 0.3, without3)))

    # Class 5 (upper_legs) only in the prediction: precision 0, recall 0/0 -> 0, IoU 0.
    without5 = [c for c in LABELS if c != 5]
    y_true = rng.choice(without5, size=250)
    cases.append(("only_in_prediction", y_true, corrupt(rng, y_true, 0.2, LABELS)))

    # Class 2 (torso) in the truth but never predicted: precision 0/0 -> 0, recall 0, IoU 0.
    y_true = rng.choice(LABELS, size=250)
    y_pred = corrupt(rng, y_true, 0.2, LABELS)
    without2 = [c for c in LABELS if c != 2]
    y_pred[y_pred == 2] = rng.choice(without2, size=int((y_pred == 2).sum()))
    assert (y_true == 2).any() and not (y_pred == 2).any()
    cases.append(("never_predicted", y_true, y_pred))

    # All three at once, few points, and one class (6) with a perfect score.
    y_true = rng.choice([0, 1, 4, 6], size=60)
    y_pred = y_true.copy()
    mask = y_true == 0
    y_pred[mask] = rng.choice([0, 0, 0, 1, 5], size=int(mask.sum()))
    mask = y_true == 1
    y_pred[mask] = rng.choice([1, 1, 4], size=int(mask.sum()))
    cases.append(("mixed_small", y_true, y_pred))
    return cases


def main():
    rng = np.random.default_rng(SEED)
    out_cases = []
    for name, y_true, y_pred in make_cases(rng):
        kw = dict(labels=LABELS, average=None, zero_division=0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            case = {
                "name": name,
                "y_true": [int(v) for v in y_true],
                "y_pred": [int(v) for v in y_pred],
                "confusion_matrix": confusion_matrix(y_true, y_pred, labels=LABELS).tolist(),
                "jaccard": [float(v) for v in jaccard_score(y_true, y_pred, **kw)],
                "precision": [float(v) for v in precision_score(y_true, y_pred, **kw)],
                "recall": [float(v) for v in recall_score(y_true, y_pred, **kw)],
                "f1": [float(v) for v in f1_score(y_true, y_pred, **kw)],
            }
        out_cases.append(case)
    doc = {
        "generator": "scripts/gen_eval_fixture.py",
        "seed": SEED,
        "numpy_version": np.__version__,
        "sklearn_version": sklearn.__version__,
        "labels": LABELS,
        "options": "average=None, labels=range(7), zero_division=0",
        "cases": out_cases,
    }
    OUT.parent.mkdir(parents=True, exist_ok=True)
    # One case per line keeps the file small and its diffs readable.
    lines = ["{"]
    head = {k: v for k, v in doc.items() if k != "cases"}
    for k, v in head.items():
        lines.append(f"  {json.dumps(k)}: {json.dumps(v)},")
    lines.append('  "cases": [')
    lines.append(",\n".join("    " + json.dumps(c) for c in out_cases))
    lines.append("  ]")
    lines.append("}")
    OUT.write_text("\n".join(lines) + "\n")
    json.loads(OUT.read_text())  # still valid JSON
    print(f"wrote {OUT} ({OUT.stat().st_size} bytes, {len(out_cases)} cases)")


if __name__ == "__main__":
    main()
