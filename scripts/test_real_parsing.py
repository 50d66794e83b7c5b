#!/usr/bin/env python3
"""Tests of the real-image benchmark scripts and the BlazePose prototype's pure helpers.

    python3 scripts/test_real_parsing.py          # numpy + pillow (+ scipy); others skip

Tests that need the extracted photographs (.data/real_parsing, scripts/real_parsing_data.py)
or the converted models with onnxruntime skip when those are absent.
"""

import io
import json
import sys
import unittest
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import blazepose_prototype as bp  # noqa: E402
import real_parsing_data as rpd  # noqa: E402
import score_parsing as sp  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent


def have(module):
    try:
        __import__(module)
        return True
    except ImportError:
        return False


class Scoring(unittest.TestCase):
    def test_iou_of_known_maps(self):
        # 4x4 ground truth: left half head (1), right half torso (2); prediction shifts one
        # column: head predicted on columns 0-2, torso on column 3.
        gt = np.zeros((4, 4), np.uint8)
        gt[:, :2], gt[:, 2:] = 1, 2
        pred = np.zeros((4, 4), np.uint8)
        pred[:, :3], pred[:, 3:] = 1, 2
        cm = sp.score_pair("parts7", gt, pred)
        s = sp.summarize("parts7", cm)
        self.assertAlmostEqual(s["iou"][1], 8 / 12)  # tp 8, fp 4
        self.assertAlmostEqual(s["iou"][2], 4 / 8)  # tp 4, fn 4
        self.assertAlmostEqual(s["miou_body"], (8 / 12 + 4 / 8) / 2)  # absent parts left out
        self.assertAlmostEqual(s["person_iou"], 1.0)

    def test_ignore_pixels_and_person_iou(self):
        gt = np.array([[0, 0, 3, 255]], np.uint8)
        pred = np.array([[0, 4, 4, 0]], np.uint8)
        s = sp.summarize("parts7", sp.score_pair("parts7", gt, pred))
        self.assertAlmostEqual(s["person_iou"], 1 / 2)  # the 255 pixel is not counted
        self.assertEqual(s["pixels"], 3)
        self.assertAlmostEqual(s["iou"][3], 0.0)

    def test_coarse_merges_upper_and_lower(self):
        # coarse ground truth: arms (7), legs (8); prediction upper/lower parts
        gt = np.array([[7, 7, 8, 8, 1]], np.uint8)
        pred = np.array([[3, 4, 5, 6, 2]], np.uint8)
        s = sp.summarize("super5", sp.score_pair("super5", gt, pred))
        self.assertAlmostEqual(s["iou"][3], 1.0)  # arms
        self.assertAlmostEqual(s["iou"][4], 1.0)  # legs
        self.assertAlmostEqual(s["iou"][1], 0.0)  # head predicted as torso

    def test_bad_prediction_is_an_error(self):
        with self.assertRaises(ValueError):
            sp.score_pair("parts7", np.zeros((2, 2), np.uint8), np.zeros((2, 3), np.uint8))
        with self.assertRaises(ValueError):
            sp.score_pair("parts7", np.zeros((1, 1), np.uint8), np.full((1, 1), 9, np.uint8))

    def test_split_is_disjoint_and_complete(self):
        index = [{"name": f"x{i}", "scheme": "parts7" if i % 3 else "super5"} for i in range(11)]
        tune = {r["name"] for r in sp.split_items(index, "tune")}
        test = {r["name"] for r in sp.split_items(index, "test")}
        self.assertFalse(tune & test)
        self.assertEqual(tune | test, {r["name"] for r in index})

    def test_holdout_is_apart_from_tune_and_test(self):
        index = [{"name": f"x{i}", "scheme": "parts7"} for i in range(6)]
        index += [{"name": f"h{i}", "scheme": "parts7", "split": "holdout"} for i in range(3)]
        names = {s: {r["name"] for r in sp.split_items(index, s)} for s in sp.SPLITS}
        self.assertEqual(names["holdout"], {"h0", "h1", "h2"})
        self.assertEqual(names["tune"], {"x0", "x2", "x4"})  # as before the hold-out existed
        self.assertEqual(names["dev"], names["tune"] | names["test"])
        self.assertFalse(names["dev"] & names["holdout"])
        self.assertEqual(names["all"], names["dev"] | names["holdout"])


class GroundTruth(unittest.TestCase):
    def test_palette_png_to_classes(self):
        from PIL import Image

        colours = rpd.PPP_PALETTE.astype(np.uint8)
        # slightly off colours as in the Grapy-ML files, and one far colour -> 255
        rgb = np.array([[colours[k] for k in range(7)] + [[255, 255, 255]]], np.uint8)
        rgb[0, 6] = [126, 1, 128]  # lower legs' colour, 2-3 off
        buf = io.BytesIO()
        Image.fromarray(rgb).save(buf, format="PNG")
        ids = rpd.labels_ppp_palette(buf.getvalue())
        self.assertEqual(ids.tolist(), [[0, 1, 2, 3, 4, 5, 6, 255]])

    def test_ppp_ids_are_our_class_ids(self):
        from PIL import Image

        im = Image.new("P", (8, 1))  # palette-mode, as the released pascal_person_part_gt
        im.putdata([0, 1, 2, 3, 4, 5, 6, 9])
        im.putpalette([0, 0, 0, 128, 0, 0, 0, 128, 0] * 3)
        buf = io.BytesIO()
        im.save(buf, format="PNG")
        self.assertEqual(rpd.labels_table(buf.getvalue(), rpd.PPP_IDS).tolist(),
                         [[0, 1, 2, 3, 4, 5, 6, 255]])

    def test_cihp_and_atr_tables(self):
        from PIL import Image

        buf = io.BytesIO()
        Image.fromarray(np.array([[0, 2, 5, 6, 14, 9, 18, 13]], np.uint8)).save(buf, format="PNG")
        self.assertEqual(rpd.labels_table(buf.getvalue(), rpd.CIHP_TO_SUPER).tolist(),
                         [[0, 1, 2, 255, 7, 8, 8, 1]])
        buf = io.BytesIO()
        Image.fromarray(np.array([[4, 6, 7, 11, 15]], np.uint8)).save(buf, format="PNG")
        self.assertEqual(rpd.labels_table(buf.getvalue(), rpd.ATR_TO_SUPER).tolist(),
                         [[2, 8, 255, 1, 7]])

    @unittest.skipUnless(have("scipy"), "scipy")
    def test_component_boxes_split_touching_people_by_heads(self):
        lab = np.zeros((40, 60), np.uint8)
        lab[5:35, 10:50] = 2  # one blob of torso...
        lab[2:8, 15:22] = 1  # ...with two heads
        lab[2:8, 38:45] = 1
        boxes = rpd.component_boxes(lab)
        self.assertEqual(len(boxes), 2)
        left, right = sorted(boxes)
        self.assertLess(left[2], right[0] + 1)  # the blob is divided, not shared
        self.assertEqual(left[0], 10)
        self.assertEqual(right[2], 49)

    def test_git_blob_hash(self):
        # `git hash-object` of "hello\n"
        self.assertEqual(rpd.git_blob_sha(b"hello\n"), "ce013625030ba8dba906f756967f9e9ca394464a")


class PrototypeGeometry(unittest.TestCase):
    def test_roi_round_trip(self):
        roi = bp.Roi(100.0, 50.0, 80.0, 0.7)
        t = np.array([[0.0, 0.0], [128.0, 128.0], [200.5, 31.25]])
        np.testing.assert_allclose(roi.image_to_tensor(roi.tensor_to_image(t)), t, atol=1e-9)
        np.testing.assert_allclose(roi.tensor_to_image(np.array([128.0, 128.0])), [100.0, 50.0])

    def test_alignment_roi_points_up(self):
        # hip centre below the scale point: upright ROI, side 2 |d| x scale
        roi = bp.roi_from_alignment(np.array([50.0, 100.0]), np.array([50.0, 60.0]), 1.5)
        self.assertAlmostEqual(roi.side, 120.0)
        self.assertAlmostEqual(roi.angle, 0.0)
        # body lying to the right (head on the right): the ROI's up is +x
        roi = bp.roi_from_alignment(np.array([50.0, 100.0]), np.array([90.0, 100.0]), 1.0)
        right, down = roi.axes()
        np.testing.assert_allclose(-down, [1.0, 0.0], atol=1e-12)

    def test_distances(self):
        px = np.array([[0.0, 0.0], [5.0, 5.0], [12.0, 0.0]])
        d = bp.seg_dist(px, np.array([0.0, 0.0]), np.array([10.0, 0.0]))
        np.testing.assert_allclose(d, [0.0, 5.0, 2.0])
        square = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
        np.testing.assert_allclose(bp.polygon_dist(px, square), [0.0, 0.0, 2.0])

    def test_anchor_count(self):
        a = bp.ssd_anchors()
        self.assertEqual(a.shape, (2254, 2))
        np.testing.assert_allclose(a[0], [0.5 / 28, 0.5 / 28])

    def test_rule_on_a_synthetic_pose(self):
        """An upright figure, mask everywhere: each bone's pixels get its class."""
        xy = np.zeros((39, 2))
        pts = {bp.L_SH: (60, 40), bp.R_SH: (40, 40), bp.L_HIP: (58, 80), bp.R_HIP: (42, 80),
               bp.L_EL: (70, 60), bp.R_EL: (30, 60), bp.L_WR: (72, 78), bp.R_WR: (28, 78),
               bp.L_KN: (58, 110), bp.R_KN: (42, 110), bp.L_AN: (58, 140), bp.R_AN: (42, 140)}
        for i in range(11):
            xy[i] = (50, 25)
        xy[2], xy[5], xy[9], xy[10] = (53, 23), (47, 23), (52, 28), (48, 28)
        xy[bp.L_EAR], xy[bp.R_EAR] = (56, 24), (44, 24)
        for i, p in pts.items():
            xy[i] = p
        for i in bp.L_HANDS:
            xy[i] = (72, 84)
        for i in bp.R_HANDS:
            xy[i] = (28, 84)
        for i in bp.L_FEET:
            xy[i] = (58, 146)
        for i in bp.R_FEET:
            xy[i] = (42, 146)
        roi = bp.Roi(50.0, 80.0, 160.0)
        pose = bp.PersonPose(roi, 1.0, xy, np.ones(39), np.ones(39), np.ones((256, 256)))
        (y0, y1, x0, x1), cls, prob, _ = bp.label_person(pose, bp.Rule(), (160, 100))
        full = np.zeros((160, 100), np.uint8)
        full[y0:y1, x0:x1] = cls
        self.assertEqual(full[25, 50], bp.HEAD)
        self.assertEqual(full[60, 50], bp.TORSO)
        self.assertEqual(full[50, 65], bp.UPPER_ARMS)
        self.assertEqual(full[70, 71], bp.LOWER_ARMS)
        self.assertEqual(full[95, 58], bp.UPPER_LEGS)
        self.assertEqual(full[125, 42], bp.LOWER_LEGS)
        self.assertTrue(np.all((prob >= 0) & (prob <= 1)))

    def test_legs_out_of_frame_are_not_invented(self):
        """A close-up: knees and ankles with low presence give no leg bones."""
        xy = np.tile([[50.0, 50.0]], (39, 1))
        xy[bp.L_SH], xy[bp.R_SH], xy[bp.L_HIP], xy[bp.R_HIP] = (60, 40), (40, 40), (58, 80), (42, 80)
        xy[[bp.L_KN, bp.R_KN, bp.L_AN, bp.R_AN]] = [(58, 95), (42, 95), (58, 99), (42, 99)]
        presence = np.ones(39)
        presence[[bp.L_KN, bp.R_KN, bp.L_AN, bp.R_AN] + list(bp.L_FEET + bp.R_FEET)] = 0.1
        pose = bp.PersonPose(bp.Roi(50.0, 60.0, 120.0), 1.0, xy, np.ones(39), presence,
                             np.ones((256, 256)))
        classes = {c for c, *_ in bp.bones(pose, bp.Rule(), (100, 100))}
        self.assertNotIn(bp.UPPER_LEGS, classes)
        self.assertNotIn(bp.LOWER_LEGS, classes)
        self.assertIn(bp.TORSO, classes)


DATA_INDEX = ROOT / ".data" / "real_parsing" / "index.json"


@unittest.skipUnless(DATA_INDEX.exists(), "no .data/real_parsing (scripts/real_parsing_data.py)")
class ExtractedData(unittest.TestCase):
    def test_every_item_has_image_labels_and_boxes(self):
        from PIL import Image

        index = json.loads(DATA_INDEX.read_text())
        manifest = json.loads((ROOT / "tests/fixtures/real_parsing/manifest.json").read_text())
        self.assertEqual(len(index), sum(len(s["items"]) for s in manifest["sources"]))
        for r in index:
            im = Image.open(DATA_INDEX.parent / "images" / f"{r['name']}.jpg")
            lab = np.asarray(Image.open(DATA_INDEX.parent / "labels" / f"{r['name']}.png"))
            self.assertEqual(lab.shape, im.size[::-1], r["name"])
            ok = {0, 1, 2, 3, 4, 5, 6, 255} if r["scheme"] == "parts7" else {0, 1, 2, 7, 8, 255}
            self.assertLessEqual(set(np.unique(lab).tolist()), ok, r["name"])
            self.assertTrue(r["person_boxes"], r["name"])


MODEL = ROOT / "models" / "blazepose_full.onnx"


@unittest.skipUnless(MODEL.exists() and have("onnxruntime"), "no models/blazepose_full.onnx or onnxruntime")
class Model(unittest.TestCase):
    def test_outputs_have_the_sidecar_shapes(self):
        spec = json.loads(MODEL.with_suffix(".json").read_text())
        model = bp.LandmarkModel(MODEL, threads=1)
        outs = model.sess.run(None, {"input_1": np.zeros((1, 256, 256, 3), np.float32)})
        for o, name in zip(outs, [o.name for o in model.sess.get_outputs()]):
            self.assertEqual(list(o.shape), spec["outputs"][name]["shape"], name)


if __name__ == "__main__":
    unittest.main(verbosity=1)
