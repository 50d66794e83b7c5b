#!/usr/bin/env python3
"""Writes the tiny 3DPeople-layout fixtures used by crates/pipeline/tests/threedpeople.rs.

Usage: python3 scripts/gen_3dpeople_fixture.py [OUT_DIR]   (default: tests/fixtures)
Needs numpy, scipy, Pillow. Deterministic: running it again rewrites identical files
(JPEG encoding aside, which depends on the Pillow/libjpeg version).

The layout is that of the real dataset (Pumarola et al., ICCV 2019), as its own
visualisation notebook (github.com/albertpumarola/3DPeople-Dataset, vis_dataset.ipynb)
reads it:

    rgb/<subject>/<sequence>/cameraNN/<outfit-and-background>/<frame>.jpg
    depth_mat/<subject>/<sequence>/cameraNN/depth.mat      one per camera, one variable per frame
    segmentation_body/<subject>/<sequence>/cameraNN/<frame>.png

Images are 64x48 (the real ones are 640x480); the intrinsics are the dataset's
fx = fy = 700, cx = 320, cy = 240 scaled by 0.1: fx = fy = 70, cx = 32, cy = 24.

3dpeople/          the good data set plus one broken view
  woman01/02_04_jump/camera01  frames 0001 0002; rgb under an outfit folder (real layout);
                               depth.mat zlib-compressed float64, background 1e10 (Blender's
                               empty-pixel Z), one person pixel +inf
  woman01/02_04_jump/camera02  frames 0001 0002; rgb directly in the camera folder;
                               depth.mat uncompressed float32, background 0
  man01/01_01_walk/camera01    frame 0001: rgb and segmentation but no depth.mat (bad view)
  expected.json                per view: valid depth pixels, label counts, sample pixels
3dpeople_errors/   views that must each fail with a message naming the file
  woman02/03_01_run/camera01   0001: a NaN depth pixel; 0002: depth.mat has no variable for it
                               (it holds depth_0001, depth_0003 and a char array 'info')
  woman02/03_01_run/camera02   0001: depth is 32x24, images are 64x48
"""

import json
import os
import sys

import numpy as np
import scipy.io
from PIL import Image

W, H = 64, 48
FX = FY = 70.0
CX, CY = 32.0, 24.0

# 3DPeople segmentation_body palette (RGB) and the bodyseg class of each part
# (0 background, 1 head, 2 torso, 3 upper arms, 4 lower arms with hands,
#  5 upper legs, 6 lower legs with feet).
PALETTE = {
    "bg": ((153, 153, 153), 0),
    "Head": ((128, 64, 0), 1),
    "RUpArm": ((128, 0, 128), 3),
    "RForeArm": ((128, 128, 255), 4),
    "RHand": ((255, 128, 128), 4),
    "LUpArm": ((0, 0, 255), 3),
    "LForeArm": ((128, 128, 0), 4),
    "LHand": ((0, 128, 0), 4),
    "torso": ((128, 0, 0), 2),
    "RThigh": ((128, 255, 128), 5),
    "RLowLeg": ((255, 255, 128), 6),
    "RFoot": ((255, 0, 255), 6),
    "LThigh": ((0, 128, 128), 5),
    "LLowLeg": ((0, 0, 128), 6),
    "LFoot": ((255, 128, 0), 6),
}
TOLERANCE = 16  # the reader's default palette_tolerance
UNKNOWN = 255

# Body parts as (part, rows v0..v1, cols u0..u1), inclusive, for a person facing the camera
# (their right on the image's left).
PARTS = [
    ("Head", 2, 7, 29, 34),
    ("torso", 8, 21, 27, 36),
    ("RUpArm", 8, 13, 23, 26),
    ("RForeArm", 14, 18, 23, 26),
    ("RHand", 19, 21, 23, 26),
    ("LUpArm", 8, 13, 37, 40),
    ("LForeArm", 14, 18, 37, 40),
    ("LHand", 19, 21, 37, 40),
    ("RThigh", 22, 30, 27, 31),
    ("RLowLeg", 31, 39, 27, 31),
    ("RFoot", 40, 42, 25, 31),
    ("LThigh", 22, 30, 32, 36),
    ("LLowLeg", 31, 39, 32, 36),
    ("LFoot", 40, 42, 32, 38),
]
FLOOR_ROWS = (43, 47)  # background-labelled pixels that do have depth (a floor strip)


def label_of(rgb):
    """The expected bodyseg label of a segmentation colour (independent of the reader)."""
    for color, cls in PALETTE.values():
        if max(abs(int(a) - int(b)) for a, b in zip(rgb, color)) <= TOLERANCE:
            return cls
    return UNKNOWN


def make_view(shift_u, base_depth_m, background_depth):
    """Segmentation (H, W, 3) uint8, depth (H, W) float64, colour (H, W, 3) uint8."""
    seg = np.zeros((H, W, 3), np.uint8)
    seg[:] = PALETTE["bg"][0]
    depth = np.full((H, W), background_depth, np.float64)
    for part, v0, v1, u0, u1 in PARTS:
        seg[v0 : v1 + 1, u0 + shift_u : u1 + 1 + shift_u] = PALETTE[part][0]
    vv, uu = np.mgrid[0:H, 0:W]
    person = np.any(seg != PALETTE["bg"][0], axis=2)
    depth[person] = (base_depth_m + 0.01 * uu - 0.005 * vv)[person]
    f0, f1 = FLOOR_ROWS
    depth[f0 : f1 + 1, :] = base_depth_m + 0.5 + 0.02 * (vv[f0 : f1 + 1, :] - f0)
    # Edge pixels as the renderer's anti-aliasing leaves them: a 50/50 blend of head and
    # torso (no palette colour: unknown) and a torso pixel a few levels off (snaps to torso).
    head, torso = np.array(PALETTE["Head"][0]), np.array(PALETTE["torso"][0])
    seg[8, 31 + shift_u] = ((head + torso) // 2).astype(np.uint8)
    seg[12, 30 + shift_u] = (torso + np.array([5, 4, 3])).astype(np.uint8)
    color = np.zeros((H, W, 3), np.uint8)
    color[..., 0] = (uu * 4) % 256
    color[..., 1] = (vv * 5) % 256
    color[..., 2] = np.where(person, 200, 60)
    return seg, depth, color


def valid(d):
    return np.isfinite(d) & (d > 0) & (d < 100.0)


def expected_of(seg, depth):
    labels = np.array([[label_of(seg[v, u]) for u in range(W)] for v in range(H)])
    ok = valid(depth)
    counts = {str(k): int(np.sum((labels == k) & ok)) for k in [0, 1, 2, 3, 4, 5, 6, UNKNOWN]}
    samples = []
    # One pixel of each part, the two edge pixels, a floor pixel.
    picks = [((v0 + v1) // 2, (u0 + u1) // 2) for _, v0, v1, u0, u1 in PARTS]
    picks += [(45, 10)]
    for v, u in picks:
        if ok[v, u]:
            samples.append(
                {"u": int(u), "v": int(v), "depth_m": float(depth[v, u]), "label": int(labels[v, u])}
            )
    return {"valid_points": int(ok.sum()), "label_counts": counts, "samples": samples}


def write_images(root, subject, seq, camera, frame, seg, color, outfit):
    rgb_dir = os.path.join(root, "rgb", subject, seq, camera, *( [outfit] if outfit else []))
    seg_dir = os.path.join(root, "segmentation_body", subject, seq, camera)
    os.makedirs(rgb_dir, exist_ok=True)
    os.makedirs(seg_dir, exist_ok=True)
    Image.fromarray(color).save(os.path.join(rgb_dir, f"{frame}.jpg"), quality=90)
    Image.fromarray(seg).save(os.path.join(seg_dir, f"{frame}.png"), optimize=True)


def write_depth(root, subject, seq, camera, variables, compress):
    d = os.path.join(root, "depth_mat", subject, seq, camera)
    os.makedirs(d, exist_ok=True)
    scipy.io.savemat(os.path.join(d, "depth.mat"), variables, do_compression=compress)


def good_set(out):
    root = os.path.join(out, "3dpeople")
    expected = {}
    subject, seq = "woman01", "02_04_jump"
    cams = [
        # camera, outfit folder, base depth, background depth, compressed, dtype
        ("camera01", "wpskin01_bottom01_top01_background01", 2.5, 1e10, True, np.float64),
        ("camera02", None, 3.0, 0.0, False, np.float32),
    ]
    for ci, (camera, outfit, base, bg, compress, dtype) in enumerate(cams):
        variables = {}
        for fi, frame in enumerate(["0001", "0002"]):
            seg, depth, color = make_view(shift_u=2 * fi - 3 * ci, base_depth_m=base, background_depth=bg)
            if camera == "camera01" and frame == "0002":
                depth[4, 31] = np.inf  # a head pixel with no return: not a point
            depth = depth.astype(dtype)
            write_images(root, subject, seq, camera, frame, seg, color, outfit)
            variables[f"depth_{frame}"] = depth
            expected[f"{subject}/{seq}/{camera}/{frame}"] = expected_of(seg, depth.astype(np.float64))
        write_depth(root, subject, seq, camera, variables, compress)
    # The broken view: images but no depth_mat/ for it at all.
    seg, _, color = make_view(0, 2.0, 1e10)
    write_images(root, "man01", "01_01_walk", "camera01", "0001", seg, color, "outfit")
    with open(os.path.join(root, "expected.json"), "w") as f:
        json.dump(
            {
                "intrinsics": {"width": W, "height": H, "fx": FX, "fy": FY, "cx": CX, "cy": CY},
                "views": expected,
            },
            f,
            indent=1,
            sort_keys=True,
        )
        f.write("\n")


def error_set(out):
    root = os.path.join(out, "3dpeople_errors")
    subject, seq = "woman02", "03_01_run"
    seg, depth, color = make_view(0, 2.5, 1e10)
    for frame in ["0001", "0002"]:
        write_images(root, subject, seq, "camera01", frame, seg, color, None)
    nan_depth = depth.copy()
    nan_depth[10, 30] = np.nan
    write_depth(
        root,
        subject,
        seq,
        "camera01",
        {"depth_0001": nan_depth, "depth_0003": depth, "info": "not a matrix"},
        True,
    )
    write_images(root, subject, seq, "camera02", "0001", seg, color, None)
    write_depth(root, subject, seq, "camera02", {"depth_0001": depth[::2, ::2].copy()}, True)


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join("tests", "fixtures")
    good_set(out)
    error_set(out)


if __name__ == "__main__":
    main()
