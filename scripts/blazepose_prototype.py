#!/usr/bin/env python3
"""Prototype of the real-image segmenter (issue 29, parts 2-3): BlazePose landmarks + mask
in person regions -> the 7 classes with a per-pixel probability. numpy + onnxruntime only.
The rule it implements is specified in docs/notes/2026-12-02-blazepose-rule.md; the Rust
port (crates/parsing, second phase) follows that note, and this file is its reference.

    .venv/bin/python scripts/blazepose_prototype.py --variant full --out /tmp/pred/full
    .venv/bin/python scripts/score_parsing.py --pred full=/tmp/pred/full
    .venv/bin/python scripts/blazepose_prototype.py --variant full --bench   # ms per 960x540 view

Person regions: for the photographs, the person boxes of .data/real_parsing/index.json
(from the ground truth; they stand in for the boxes bodyseg finds from depth).
"""

import argparse
import json
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "scripts"))
from score_parsing import DATA, load_index, split_items  # noqa: E402

INPUT = 256  # landmark model input side, px
HEATMAP = 64  # landmark heatmap side
N_LANDMARKS = 39

# Landmark indices (MediaPipe pose topology).
NOSE = 0
FACE = list(range(0, 11))  # nose, eyes, ears, mouth
L_EAR, R_EAR = 7, 8
L_SH, R_SH, L_EL, R_EL, L_WR, R_WR = 11, 12, 13, 14, 15, 16
L_HANDS, R_HANDS = (17, 19, 21), (18, 20, 22)  # pinky, index, thumb
L_HIP, R_HIP, L_KN, R_KN, L_AN, R_AN = 23, 24, 25, 26, 27, 28
L_FEET, R_FEET = (29, 31), (30, 32)  # heel, foot index
AUX_CENTRE, AUX_SCALE = 33, 34

HEAD, TORSO, UPPER_ARMS, LOWER_ARMS, UPPER_LEGS, LOWER_LEGS = 1, 2, 3, 4, 5, 6


@dataclass
class Rule:
    """Every threshold of the rule; the defaults are the values tuned on the "tune" split."""

    roi_scales: tuple = (1.25, 2.0)  # ROI side = scale x the person box's longer side; several = hypotheses
    refine_passes: int = 2  # runs on the ROI derived from the previous run's alignment points
    select: str = "box"  # how a hypothesis is chosen: "flag" (pose flag) or "box" (mask vs box)
    aux_roi_scale: float = 1.5  # MediaPipe's scale of the alignment-point box
    use_detector: bool = False  # colour-only fallback: ROI from the detector inside the box
    det_region_scale: float = 1.5  # the detector sees a square of this x the box's longer side
    det_roi_scale: float = 1.25  # scale of the detector's alignment-point box
    min_detection: float = 0.5  # detector score needed to use its ROI
    heatmap_refine: bool = True  # MediaPipe's RefineLandmarksFromHeatmap (kernel 7)
    min_pose_flag: float = 0.1  # below: the region gives no person
    mask_threshold: float = 0.35  # a pixel is this person's when its mask value is >= this
    min_presence: float = 0.5  # a landmark counts when its presence is >= this
    min_visibility: float = 0.2  # a limb bone counts when both ends are visible >= this
    # Capsule radii, as a fraction of the body scale (shoulder-to-hip distance, or the
    # shoulder width / hip width when larger).
    r_head: float = 0.4  # x the head width
    face_to_width: float = 2.0  # head width >= this x the eyes-mouth distance
    head_down: float = 0.2  # head bone: from the face centre down (toward the chin), x head width
    head_up: float = 0.3  # and up (toward the crown), x head width
    r_torso: float = 0.25
    r_upper_arm: float = 0.15
    r_lower_arm: float = 0.14
    r_upper_leg: float = 0.2
    r_lower_leg: float = 0.22
    hand_extend: float = 0.0  # lower arm bone continues past the hand points by this fraction of wrist->hand
    distance: str = "surface"  # bone distance: "normalised" (d / r) or "surface" ((d - r) / scale + 1)
    torso_bias: float = 0.2  # added to the torso's normalised distance (limbs in front of it win)
    max_norm_dist: float = 3.0  # a mask pixel farther than this (in radii) from every bone is background
    margin_scale: float = 0.5  # bone-margin confidence: 1 - 0.5 exp(-(d2 - d1) / margin_scale)


# ---------------------------------------------------------------------------------------
# ROI: square, rotated; tensor pixel centre (i + 0.5) / 256 - 0.5 of the side from the centre
# ---------------------------------------------------------------------------------------

@dataclass
class Roi:
    cx: float  # centre, image px (pixel centres at integers)
    cy: float
    side: float  # px
    angle: float = 0.0  # rad; 0 = upright; the ROI's "down" axis is (-sin a, cos a)

    def axes(self):
        """(right, down) unit vectors in image px."""
        c, s = np.cos(self.angle), np.sin(self.angle)
        return np.array([c, s]), np.array([-s, c])

    def tensor_to_image(self, t):
        """Tensor coordinates [..., 2] (0..256, pixel edges) -> image px."""
        right, down = self.axes()
        off = (np.asarray(t, np.float64) / INPUT - 0.5) * self.side
        return np.array([self.cx, self.cy]) + off[..., :1] * right + off[..., 1:2] * down

    def image_to_tensor(self, p):
        right, down = self.axes()
        d = np.asarray(p, np.float64) - np.array([self.cx, self.cy])
        return np.stack([(d @ right) / self.side + 0.5, (d @ down) / self.side + 0.5], -1) * INPUT


def roi_from_box(box, scale):
    x0, y0, x1, y1 = box
    return Roi((x0 + x1) / 2.0, (y0 + y1) / 2.0, max(x1 - x0 + 1, y1 - y0 + 1) * scale, 0.0)


def roi_from_alignment(centre, scale_pt, scale):
    """MediaPipe AlignmentPointsRects + RectTransformation(square_long): side = 2 |scale -
    centre| x scale, rotated so that centre -> scale_pt points up in the ROI."""
    v = np.asarray(scale_pt) - np.asarray(centre)
    side = 2.0 * float(np.hypot(*v)) * scale
    # "up" of the ROI = v / |v|; down = -v/|v| = (-sin a, cos a)
    angle = float(np.arctan2(v[0], -v[1]))
    return Roi(float(centre[0]), float(centre[1]), side, angle)


def crop(rgb, roi, size=INPUT):
    """[size, size, 3] float32 in [0, 1]: bilinear, border replicated (BORDER_REPLICATE)."""
    h, w = rgb.shape[:2]
    g = (np.arange(size) + 0.5) * (INPUT / size)
    tx, ty = np.meshgrid(g, g)
    p = roi.tensor_to_image(np.stack([tx, ty], -1))
    x = np.clip(p[..., 0], 0, w - 1)
    y = np.clip(p[..., 1], 0, h - 1)
    x0 = np.floor(x).astype(np.int64)
    y0 = np.floor(y).astype(np.int64)
    x1 = np.minimum(x0 + 1, w - 1)
    y1 = np.minimum(y0 + 1, h - 1)
    fx = (x - x0)[..., None]
    fy = (y - y0)[..., None]
    img = rgb.astype(np.float32)
    top = img[y0, x0] * (1 - fx) + img[y0, x1] * fx
    bot = img[y1, x0] * (1 - fx) + img[y1, x1] * fx
    return ((top * (1 - fy) + bot * fy) / 255.0).astype(np.float32)


def sigmoid(x):
    return 1.0 / (1.0 + np.exp(-np.clip(x, -60, 60)))


def refine_from_heatmap(lm, heat, kernel=7, min_conf=0.5):
    """MediaPipe RefineLandmarksFromHeatmapCalculator: x, y (tensor px) -> the sigmoid-
    weighted mean position in a kernel x kernel window of the landmark's heatmap."""
    off = kernel // 2
    out = lm.copy()
    hm = sigmoid(heat)  # [64, 64, 39]
    for i in range(N_LANDMARKS):
        col = int(lm[i, 0] / INPUT * HEATMAP)
        row = int(lm[i, 1] / INPUT * HEATMAP)
        if not (0 <= col < HEATMAP and 0 <= row < HEATMAP):
            continue
        r0, r1 = max(0, row - off), min(HEATMAP, row + off + 1)
        c0, c1 = max(0, col - off), min(HEATMAP, col + off + 1)
        win = hm[r0:r1, c0:c1, i]
        if win.max() < min_conf or win.sum() <= 0:
            continue
        rr, cc = np.mgrid[r0:r1, c0:c1]
        out[i, 0] = ((cc * win).sum() / win.sum() + 0.5) / HEATMAP * INPUT
        out[i, 1] = ((rr * win).sum() / win.sum() + 0.5) / HEATMAP * INPUT
    return out


@dataclass
class PersonPose:
    roi: Roi
    flag: float
    xy: np.ndarray  # [39, 2] image px
    visibility: np.ndarray  # [39]
    presence: np.ndarray  # [39]
    mask: np.ndarray  # [256, 256] person probability on the ROI grid


def ort_session(path, threads):
    """ONNX Runtime session: `threads` intra-op threads, one inter-op, no spin-waiting (a
    spinning pool is several times slower on a shared 2-core machine)."""
    import onnxruntime as ort

    o = ort.SessionOptions()
    o.intra_op_num_threads = threads
    o.inter_op_num_threads = 1
    o.add_session_config_entry("session.intra_op.allow_spinning", "0")
    return ort.InferenceSession(str(path), o, providers=["CPUExecutionProvider"])


class LandmarkModel:
    def __init__(self, path, threads=2):
        self.sess = ort_session(path, threads)

    calls = 0  # inference count and seconds, for the bench
    seconds = 0.0

    def run(self, rgb, roi, rule):
        x = crop(rgb, roi)[None]
        t0 = time.perf_counter()
        lm, flag, seg, heat, _ = self.sess.run(None, {"input_1": x})
        self.calls += 1
        self.seconds += time.perf_counter() - t0
        lm = lm.reshape(N_LANDMARKS, 5).astype(np.float64)
        if rule.heatmap_refine:
            lm = refine_from_heatmap(lm, heat[0])
        return PersonPose(roi, float(flag.reshape(-1)[0]), roi.tensor_to_image(lm[:, :2]),
                          sigmoid(lm[:, 3]), sigmoid(lm[:, 4]), sigmoid(seg[0, :, :, 0]))


# ---------------------------------------------------------------------------------------
# Detector (colour-only fallback): BlazePose's face-keyed detector inside the person box
# ---------------------------------------------------------------------------------------

DET_INPUT = 224


def ssd_anchors():
    """[2254, 2] anchor centres (0..1) of MediaPipe's SsdAnchorsCalculator for the pose
    detector: strides 8, 16, 32, 32, 32 (same-stride layers merged), 2 anchors per layer
    and cell, fixed size 1."""
    out = []
    strides = [8, 16, 32, 32, 32]
    i = 0
    while i < len(strides):
        j = i
        while j < len(strides) and strides[j] == strides[i]:
            j += 1
        n_per_cell = 2 * (j - i)
        fm = int(np.ceil(DET_INPUT / strides[i]))
        for y in range(fm):
            for x in range(fm):
                out += [((x + 0.5) / fm, (y + 0.5) / fm)] * n_per_cell
        i = j
    return np.array(out)


class Detector:
    def __init__(self, path, threads=2):
        self.sess = ort_session(path, threads)
        self.anchors = ssd_anchors()

    def detect(self, rgb, region):
        """Best detection in a square region (Roi, upright): (score, keypoints [4, 2] image px)."""
        x = crop(rgb, Roi(region.cx, region.cy, region.side), size=DET_INPUT) * 2.0 - 1.0
        raw, score = self.sess.run(None, {"input_1": x[None].astype(np.float32)})
        raw, score = raw[0], sigmoid(score[0, :, 0])
        k = int(score.argmax())
        kp = raw[k, 4:12].reshape(4, 2) / DET_INPUT + self.anchors[k]
        return float(score[k]), region.tensor_to_image(kp * INPUT)


def pose_in_box(model, rgb, box, rule, detector=None):
    """Landmark model on the box ROI of each scale (or the detector ROI), then refine_passes
    runs on the ROI of the previous run's alignment points; the best hypothesis by rule.select."""
    roi = None
    if detector is not None:
        score, kp = detector.detect(rgb, roi_from_box(box, rule.det_region_scale))
        if score >= rule.min_detection:
            roi = roi_from_alignment(kp[0], kp[1], rule.det_roi_scale)
    best = None
    for scale in rule.roi_scales:
        pose = model.run(rgb, roi if roi is not None else roi_from_box(box, scale), rule)
        for _ in range(rule.refine_passes):
            if pose.flag < 0.5:
                break
            roi2 = roi_from_alignment(pose.xy[AUX_CENTRE], pose.xy[AUX_SCALE], rule.aux_roi_scale)
            if not 0.5 * pose.roi.side <= roi2.side <= 2.0 * pose.roi.side:
                break
            pose2 = model.run(rgb, roi2, rule)
            if pose2.flag < pose.flag * 0.8:
                break
            pose = pose2
        if best is None or hypothesis_score(pose, box, rule) > hypothesis_score(best, box, rule):
            best = pose
    return best


def hypothesis_score(pose, box, rule):
    """How well a pose explains the person box (higher is better)."""
    if rule.select == "flag":
        return pose.flag
    # "box": IoU of the mask (>= threshold, on the ROI grid mapped to the image) with the box
    g = np.arange(0, INPUT, 4) + 2.0
    tx, ty = np.meshgrid(g, g)
    p = pose.roi.tensor_to_image(np.stack([tx, ty], -1))
    m = pose.mask[2::4, 2::4] >= rule.mask_threshold
    x0, y0, x1, y1 = box
    inb = (p[..., 0] >= x0) & (p[..., 0] <= x1) & (p[..., 1] >= y0) & (p[..., 1] <= y1)
    cell = (pose.roi.side / INPUT * 4) ** 2
    inter = (m & inb).sum() * cell
    union = (x1 - x0 + 1) * (y1 - y0 + 1) + (m & ~inb).sum() * cell
    return pose.flag * inter / union


# ---------------------------------------------------------------------------------------
# Landmarks + mask -> 7 classes
# ---------------------------------------------------------------------------------------

def seg_dist(px, a, b):
    """Distance of points px [..., 2] to the segment a-b."""
    ab = b - a
    L2 = float(ab @ ab)
    if L2 < 1e-9:
        return np.linalg.norm(px - a, axis=-1)
    t = np.clip(((px - a) @ ab) / L2, 0.0, 1.0)
    return np.linalg.norm(px - (a + t[..., None] * ab), axis=-1)


def polyline_dist(px, pts):
    return np.min([seg_dist(px, pts[i], pts[i + 1]) for i in range(len(pts) - 1)], axis=0)


def polygon_dist(px, poly):
    """0 inside the (convex or not) polygon, else the distance to its boundary."""
    n = len(poly)
    d = np.min([seg_dist(px, poly[i], poly[(i + 1) % n]) for i in range(n)], axis=0)
    x, y = px[..., 0], px[..., 1]
    inside = np.zeros(x.shape, bool)
    for i in range(n):
        (x0, y0), (x1, y1) = poly[i], poly[(i + 1) % n]
        cross = ((y0 > y) != (y1 > y))
        with np.errstate(divide="ignore", invalid="ignore"):
            xi = x0 + (y - y0) * (x1 - x0) / (y1 - y0)
        inside ^= cross & (x < xi)
    return np.where(inside, 0.0, d)


def bones(pose, rule, image_wh):
    """[(class, kind, points, radius px)] of the bones this pose supports.

    kind "poly" = capsule around a polyline, "area" = polygon (torso)."""
    P, vis, pres = pose.xy, pose.visibility, pose.presence
    ok = pres >= rule.min_presence

    def seen(*idx):
        return all(ok[i] and vis[i] >= rule.min_visibility for i in idx)

    sh_mid = (P[L_SH] + P[R_SH]) / 2
    hip_mid = (P[L_HIP] + P[R_HIP]) / 2
    sw = np.linalg.norm(P[L_SH] - P[R_SH])
    hw = np.linalg.norm(P[L_HIP] - P[R_HIP])
    tl = np.linalg.norm(sh_mid - hip_mid)
    scale = max(tl, sw, hw, 1.0)
    out = []
    if ok[L_SH] and ok[R_SH]:
        if ok[L_HIP] and ok[R_HIP]:
            out.append((TORSO, "area", np.array([P[L_SH], P[R_SH], P[R_HIP], P[L_HIP]]),
                        rule.r_torso * scale, scale))
        else:
            # hips out of frame: the torso runs from the shoulders down the body axis
            down = pose.roi.axes()[1]
            out.append((TORSO, "area", np.array([P[L_SH], P[R_SH], P[R_SH] + down * scale,
                                                 P[L_SH] + down * scale]), rule.r_torso * scale, scale))
    face = [i for i in FACE if ok[i]]
    if face:
        # head: a capsule along the body's up axis through the face points' mean, sized by
        # the face (ear to ear, or eyes to mouth x face_to_width), not by the torso
        hc = P[face].mean(0)
        if ok[L_SH] and ok[R_SH] and np.linalg.norm(hc - sh_mid) > 1e-6:
            up = (hc - sh_mid) / np.linalg.norm(hc - sh_mid)
        else:
            up = -pose.roi.axes()[1]
        eyes = (P[2] + P[5]) / 2
        mouth = (P[9] + P[10]) / 2
        width = max(np.linalg.norm(P[L_EAR] - P[R_EAR]),
                    rule.face_to_width * np.linalg.norm(eyes - mouth), 1.0)
        out.append((HEAD, "poly", np.array([hc - rule.head_down * width * up,
                                            hc + rule.head_up * width * up]), rule.r_head * width, scale))
    # A limb: its upper part from root to middle joint, its lower part on to the end joint and
    # past it to the mean of the hand (feet) landmarks seen, for hands extended by hand_extend.
    limbs = [(root, mid, end, tips, UPPER_ARMS, LOWER_ARMS, rule.r_upper_arm, rule.r_lower_arm, rule.hand_extend)
             for root, mid, end, tips in ((L_SH, L_EL, L_WR, L_HANDS), (R_SH, R_EL, R_WR, R_HANDS))]
    limbs += [(root, mid, end, tips, UPPER_LEGS, LOWER_LEGS, rule.r_upper_leg, rule.r_lower_leg, 0.0)
              for root, mid, end, tips in ((L_HIP, L_KN, L_AN, L_FEET), (R_HIP, R_KN, R_AN, R_FEET))]
    for root, mid, end, tips, upper, lower, r_upper, r_lower, extend in limbs:
        if seen(root, mid):
            out.append((upper, "poly", np.array([P[root], P[mid]]), r_upper * scale, scale))
            if seen(end):
                pts = [P[mid], P[end]]
                tp = [i for i in tips if ok[i]]
                if tp:
                    tip = P[tp].mean(0)
                    pts.append(tip + extend * (tip - P[end]) if extend else tip)
                out.append((lower, "poly", np.array(pts), r_lower * scale, scale))
    return out


def label_person(pose, rule, shape):
    """For the pixels of the ROI's bounding box: (window, class [h, w], probability [h, w],
    normalised bone distance [h, w]) of one person; class 0 where not this person's."""
    h, w = shape
    corners = pose.roi.tensor_to_image(np.array([[0, 0], [INPUT, 0], [0, INPUT], [INPUT, INPUT]], float))
    x0 = int(max(0, np.floor(corners[:, 0].min())))
    x1 = int(min(w, np.ceil(corners[:, 0].max()) + 1))
    y0 = int(max(0, np.floor(corners[:, 1].min())))
    y1 = int(min(h, np.ceil(corners[:, 1].max()) + 1))
    if x1 <= x0 or y1 <= y0:
        return None
    yy, xx = np.mgrid[y0:y1, x0:x1]
    px = np.stack([xx, yy], -1).astype(np.float64)
    # mask back to the image: bilinear on the ROI grid (pixel centres at i + 0.5), 0 outside
    t = pose.roi.image_to_tensor(px) - 0.5
    tx, ty = t[..., 0], t[..., 1]
    inside = (tx >= -0.5) & (tx <= INPUT - 0.5) & (ty >= -0.5) & (ty <= INPUT - 0.5)
    tx = np.clip(tx, 0, INPUT - 1)
    ty = np.clip(ty, 0, INPUT - 1)
    ix, iy = np.minimum(np.floor(tx).astype(int), INPUT - 2), np.minimum(np.floor(ty).astype(int), INPUT - 2)
    fx, fy = tx - ix, ty - iy
    m = pose.mask
    mv = ((m[iy, ix] * (1 - fx) + m[iy, ix + 1] * fx) * (1 - fy)
          + (m[iy + 1, ix] * (1 - fx) + m[iy + 1, ix + 1] * fx) * fy)
    mv = np.where(inside, mv, 0.0)

    bl = bones(pose, rule, (w, h))
    if not bl:
        return None
    # normalised distance to each bone; the torso's is raised by torso_bias, so that a limb
    # lying in front of the torso (inside its own capsule, distance < 1) wins over it
    if rule.distance == "normalised":
        nd = np.stack([(polygon_dist(px, pts) / r + rule.torso_bias) if kind == "area"
                       else polyline_dist(px, pts) / r
                           for _, kind, pts, r, _ in bl])  # [bones, h, w]
    else:  # "surface": distance to the capsule's surface, in units of the body scale
        sc = bl[0][4]
        nd = np.stack([((polygon_dist(px, pts) - r) / sc + rule.torso_bias) if kind == "area"
                       else (polyline_dist(px, pts) - r) / sc
                       for _, kind, pts, r, _ in bl]) + 1.0
    cls_of = np.array([b[0] for b in bl])
    # per class: the nearest of its bones
    best_per_class = np.full((7,) + nd.shape[1:], np.inf)
    for k, c in enumerate(cls_of):
        best_per_class[c] = np.minimum(best_per_class[c], nd[k])
    order = np.argsort(best_per_class, axis=0)
    cls = order[0]
    d1 = np.take_along_axis(best_per_class, order[:1], 0)[0]
    d2 = np.take_along_axis(best_per_class, order[1:2], 0)[0]
    d2 = np.where(np.isfinite(d2), d2, d1 + 10.0)
    conf = 1.0 - 0.5 * np.exp(-(d2 - d1) / rule.margin_scale)
    person = (mv >= rule.mask_threshold) & (d1 <= rule.max_norm_dist)
    cls = np.where(person, cls, 0).astype(np.uint8)
    prob = np.where(person, mv * conf, 0.0)
    return (y0, y1, x0, x1), cls, prob, np.where(person, d1, np.inf)


def segment(model, rgb, boxes, rule, detector=None):
    """Class ids [h, w] and winner probability [h, w] of an image with person boxes.
    Where people overlap, a pixel goes to the person whose bone is nearer (normalised);
    with depth (bodyseg's boxes) it would go to the person in front."""
    h, w = rgb.shape[:2]
    labels = np.zeros((h, w), np.uint8)
    prob = np.zeros((h, w), np.float64)
    best = np.full((h, w), np.inf)
    for box in boxes:
        pose = pose_in_box(model, rgb, box, rule, detector if rule.use_detector else None)
        if pose.flag < rule.min_pose_flag:
            continue
        res = label_person(pose, rule, (h, w))
        if res is None:
            continue
        (y0, y1, x0, x1), c, p, d = res
        win = best[y0:y1, x0:x1]
        take = d < win
        labels[y0:y1, x0:x1][take] = c[take]
        prob[y0:y1, x0:x1][take] = p[take]
        win[take] = d[take]
    return labels, prob


def bench(model, rule, repeats, detector=None):
    """ms per 960x540 view with 2 people (a photograph resized, two boxes), min and median."""
    from PIL import Image

    img = None
    idx = load_index(DATA)
    if idx:
        r = next(r for r in idx if r["name"] == "ppp_2008_000034")
        im = Image.open(DATA / "images" / f"{r['name']}.jpg").convert("RGB")
        sx, sy = 960 / im.size[0], 540 / im.size[1]
        img = np.asarray(im.resize((960, 540), Image.BILINEAR))
        boxes = [[b[0] * sx, b[1] * sy, b[2] * sx, b[3] * sy] for b in r["person_boxes"]][:2]
    if img is None or len(boxes) < 2:
        rng = np.random.default_rng(0)
        img = rng.integers(0, 255, (540, 960, 3), dtype=np.uint8)
        boxes = [[200, 40, 420, 530], [560, 40, 780, 530]]
    segment(model, img, boxes, rule, detector)
    times, infer = [], []
    for _ in range(repeats):
        model.calls, model.seconds = 0, 0.0
        t0 = time.perf_counter()
        segment(model, img, boxes, rule, detector)
        times.append(1000 * (time.perf_counter() - t0))
        infer.append((model.calls, 1000 * model.seconds))
    k = int(np.argmin(times))
    return min(times), float(np.median(times)), infer[k]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--variant", default="full", choices=("lite", "full", "heavy"))
    ap.add_argument("--models", default=str(ROOT / "models"))
    ap.add_argument("--out", help="folder for <name>.png label maps (and <name>.prob.png)")
    ap.add_argument("--split", choices=("all", "tune", "test"), default="all")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--set", action="append", default=[], metavar="FIELD=VALUE",
                    help="override a Rule field")
    ap.add_argument("--bench", type=int, nargs="?", const=20, help="time N views of 960x540 with 2 people")
    args = ap.parse_args(argv)

    rule = Rule()
    for kv in args.set:
        k, v = kv.split("=", 1)
        cur = getattr(rule, k)
        if isinstance(cur, bool):
            val = v.lower() in ("1", "true", "yes")
        elif isinstance(cur, tuple):
            val = tuple(float(x) for x in v.split(","))
        else:
            val = type(cur)(v)
        setattr(rule, k, val)
    model = LandmarkModel(Path(args.models) / f"blazepose_{args.variant}.onnx", args.threads)
    detector = Detector(Path(args.models) / "blazepose_detector.onnx", args.threads) if rule.use_detector else None
    if args.bench:
        lo, med, (calls, ms) = bench(model, rule, args.bench, detector)
        print(f"{args.variant}: 960x540 view, 2 people, {args.threads} threads: "
              f"min {lo:.1f} ms, median {med:.1f} ms ({args.bench} runs); in the fastest run "
              f"{calls} landmark inferences took {ms:.1f} ms, the rest (crop, labels) {lo - ms:.1f} ms")
        return 0
    from PIL import Image

    index = load_index(DATA)
    if index is None:
        raise SystemExit(f"{DATA}: no index.json (run scripts/real_parsing_data.py)")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t = 0.0
    items = split_items(index, args.split)
    for r in items:
        rgb = np.asarray(Image.open(DATA / "images" / f"{r['name']}.jpg").convert("RGB"))
        t0 = time.perf_counter()
        labels, prob = segment(model, rgb, r["person_boxes"], rule, detector)
        t += time.perf_counter() - t0
        Image.fromarray(labels).save(out / f"{r['name']}.png")
        Image.fromarray((prob * 255).round().astype(np.uint8)).save(out / f"{r['name']}.prob.png")
    print(f"{args.variant}: {len(items)} images -> {out} ({1000 * t / max(len(items), 1):.0f} ms/image)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
