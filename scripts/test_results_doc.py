#!/usr/bin/env python3
"""Tests of scripts/results_doc.py (docs/results.md's generator) on a made-up work folder.

    python3 scripts/test_results_doc.py          # standard library only
"""

import contextlib
import io
import json
import sys
import tempfile
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import results_doc as rd  # noqa: E402

# bodyseg-eval's class order (report["classes"]).
CLASSES = ["background", "head", "torso", "upper_arms", "lower_arms", "upper_legs", "lower_legs"]


def matrix(right, wrong):
    """[truth][prediction] counts: `right` on the diagonal, `wrong` of each class predicted as
    the next one."""
    n = len(CLASSES)
    m = [[0] * n for _ in range(n)]
    for i in range(n):
        m[i][i] = right
        m[i][(i + 1) % n] += wrong
    return m


def iou(m, k):
    tp = m[k][k]
    return tp / (sum(m[k]) + sum(r[k] for r in m) - tp)


def report(configurations):
    """A bodyseg-eval report.json of {name: confusion matrix}; fractions, as the binary writes."""
    out = []
    for name, m in configurations.items():
        ious = [iou(m, k) for k in range(len(CLASSES))]
        out.append({
            "name": name,
            "confusion": {"counts": m},
            "metrics": {
                "per_class": [{"class": c, "iou": v} for c, v in zip(CLASSES, ious)],
                "miou": sum(ious) / len(ious),
                "biou": sum(ious[1:]) / len(ious[1:]),
                "ap": 0.9,
                "f1": 0.9,
            },
        })
    return {"version": 1, "classes": CLASSES, "configurations": out}


def write(path: Path, value):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(value))


def refinement(wrong_reference):
    """The paper's five rows, each configuration after Reference with fewer wrong points."""
    return {name: matrix(100, wrong_reference - 3 * i) for i, name in enumerate(rd.PAPER)}


# Wrong points added per class in each refinement setting's runs, so that no two runs are equal.
SETTING_OFFSET = {"": 0, "_improved": 2, "_vote": 4, "_weighted": 1}


def work_folder(root: Path):
    """Every file results_doc.py reads, as scripts/reproduce.sh leaves them."""
    for source in ["recorded", "model", "blazepose"]:
        for mode in ["naive", "dsa"]:
            for setting in ["", "_improved", "_vote"] + (["_weighted"] if source == "model" else []):
                run = root / "runs" / f"{source}_{mode}{setting}"
                wrong = {"recorded": 20, "model": 40, "blazepose": 60}[source] + SETTING_OFFSET[setting]
                write(run / "report.json", report(refinement(wrong)))
                for recording, extra in [("single_2001", 0), ("handover_2005", 10)]:
                    write(run / recording / "report.json", report(refinement(wrong + extra)))
    (root / "projection.md").write_text("| preset | x |\n|---|---|\n| single | 1 |\n")
    write(root / "subset" / "report.json", report(refinement(20)))


class BodyIouByPreset(unittest.TestCase):
    def test_sums_the_matrices_of_a_presets_recordings(self):
        with tempfile.TemporaryDirectory() as tmp:
            run = Path(tmp)
            a, b = matrix(100, 10), matrix(50, 40)
            write(run / "single_2001" / "report.json", report({"M-R-N": a}))
            write(run / "single_2002" / "report.json", report({"M-R-N": b}))
            write(run / "robot_cell_2009" / "report.json", report({"M-R-N": b}))
            got = rd.body_iou_by_preset(run)
        # Summed counts: 150 right, 50 wrong each way per class -> 150 / 250 for every body
        # class; the mean of the two recordings' BIoU (100/120 and 50/130) would be 0.609.
        self.assertEqual(sorted(got), ["robot_cell", "single"])
        self.assertAlmostEqual(got["single"], 100.0 * 150 / 250, places=9)
        self.assertAlmostEqual(got["robot_cell"], 100.0 * 50 / 130, places=9)


class Document(unittest.TestCase):
    def setUp(self):
        tmp = tempfile.TemporaryDirectory()
        self.addCleanup(tmp.cleanup)
        work_folder(Path(tmp.name))
        text = io.StringIO()
        argv = sys.argv
        sys.argv = ["results_doc.py", tmp.name, "125"]
        try:
            with contextlib.redirect_stdout(text):
                rd.main()
        finally:
            sys.argv = argv
        self.doc = text.getvalue()

    def test_blazepose_has_its_section_tables_and_figure(self):
        self.assertIn("## BlazePose + BodyPix, the default parser, on the synthetic benchmark", self.doc)
        self.assertIn("### BlazePose + BodyPix (default parser), DSA projection, improved refinement\n", self.doc)
        self.assertIn("![BlazePose, paper mode](images/results_blazepose.png)", self.doc)
        self.assertNotIn("not generated yet", self.doc)

    def test_blazepose_row_holds_its_runs_numbers(self):
        # blazepose_dsa: Reference 60 wrong points per class, M-R-N (fifth row) 60 - 12.
        ref, mrn = 100.0 * 100 / 220, 100.0 * 100 / 196
        self.assertIn(f"| BlazePose + BodyPix | dsa | {ref:.2f} | {mrn:.2f} | {ref:.2f} | {mrn:.2f} |", self.doc)
        # Per preset: single_2001 as the run, handover_2005 with 10 more wrong points.
        self.assertIn(f"`single` BlazePose {mrn:.2f}", self.doc)
        self.assertIn(f"`handover` BlazePose {100.0 * 100 / 216:.2f}", self.doc)

    def test_error_shares_count_the_true_body_points(self):
        # blazepose_naive, handover_2005, Reference: 70 wrong points per class, each to the
        # next class; of the 6 x 170 true body points 5 x 70 go to another part, and the lower
        # legs' 70 to background.
        self.assertIn(f"BlazePose gives another body part to `handover` {100 * 350 / 1020:.1f}%", self.doc)
        self.assertIn(f"and background to `handover` {100 * 70 / 1020:.1f}%", self.doc)

    def test_elapsed_time_is_written(self):
        self.assertIn("in 2 min 5 s.", self.doc)


if __name__ == "__main__":
    unittest.main()
