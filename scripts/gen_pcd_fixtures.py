#!/usr/bin/env python3
"""Writes the PCD fixtures of crates/io/tests/data/ with the Python `pypcd4` package
(an implementation independent of bodyseg's reader), and a JSON sidecar with the values
the Rust tests compare against.

    pip install pypcd4==1.5.1
    python3 scripts/gen_pcd_fixtures.py

Files (all small, committed):
- xyzrgb_{ascii,binary,binary_compressed}.pcd: the same 40 unorganised points (x y z
  float32 + packed rgb: float-packed in the binary files, uint32 in the ASCII one),
  point 7 NaN (skipped by readers);
- organised_binary_compressed.pcd: an 8 x 5 organised cloud, x y z float32, rgba uint32,
  label uint32 (class ids), every third point NaN;
- pcd_fixtures.json: per file the points a reader must return (index in the file,
  x y z, r g b, label);
- scene_handover.pcd / scene_handover_boxes.json: a synthetic handover frame
  (bodyseg-synth, preset handover, seed 3, frame 6; three depth cameras back-projected
  every 4th pixel, world frame, walls cropped) as an organised binary_compressed cloud
  (the three cameras' 128 x 106 grids stacked: WIDTH 128, HEIGHT 318, invalid pixels NaN),
  and its true person boxes. Made with
  `cargo run --release -p bodyseg-lab --example pcd_scene` (run by this script).
"""

import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from pypcd4 import Encoding, MetaData, PointCloud

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "crates" / "io" / "tests" / "data"


def packed_rgb_float(rgb: np.ndarray) -> np.ndarray:
    """PCL's float-packed colour: the bits of 0x00RRGGBB read as a float32."""
    r, g, b = (rgb[:, k].astype(np.uint32) for k in range(3))
    return ((r << 16) | (g << 8) | b).astype(np.uint32).view(np.float32)


def expected(xyz, rgb, label=None):
    rows = []
    for i in range(len(xyz)):
        if not all(math.isfinite(v) for v in xyz[i]):
            continue
        row = {"index": i, "xyz": [float(v) for v in xyz[i]], "rgb": [int(v) for v in rgb[i]]}
        if label is not None:
            row["label"] = int(label[i])
        rows.append(row)
    return rows


def unorganised(sidecar):
    rng = np.random.default_rng(6)
    n = 40
    xyz = rng.uniform(-3.0, 3.0, size=(n, 3)).astype(np.float32)
    xyz[7] = np.nan
    rgb = rng.integers(0, 256, size=(n, 3)).astype(np.uint8)
    rgb[0] = [255, 0, 128]
    rgbf = packed_rgb_float(rgb)
    for name, enc in [
        ("ascii", Encoding.ASCII),
        ("binary", Encoding.BINARY),
        ("binary_compressed", Encoding.BINARY_COMPRESSED),
    ]:
        # pypcd4 prints floats with 10 decimals, which loses a float-packed colour:
        # the ASCII file stores rgb as an unsigned integer (TYPE U) instead.
        rgb_col, rgb_type = (rgbf.view(np.uint32), np.uint32) if enc == Encoding.ASCII else (rgbf, np.float32)
        pc = PointCloud.from_points(
            [xyz[:, 0], xyz[:, 1], xyz[:, 2], rgb_col],
            ("x", "y", "z", "rgb"),
            (np.float32, np.float32, np.float32, rgb_type),
        )
        file = f"xyzrgb_{name}.pcd"
        pc.save(OUT / file, encoding=enc)
        sidecar[file] = {"points": n, "organised": False, "expected": expected(xyz, rgb)}


def organised(sidecar):
    rng = np.random.default_rng(7)
    w, h = 8, 5
    n = w * h
    xyz = rng.uniform(-2.0, 2.0, size=(n, 3)).astype(np.float32)
    xyz[::3] = np.nan
    rgb = rng.integers(0, 256, size=(n, 3)).astype(np.uint8)
    rgba = (
        (np.uint32(255) << 24)
        | (rgb[:, 0].astype(np.uint32) << 16)
        | (rgb[:, 1].astype(np.uint32) << 8)
        | rgb[:, 2].astype(np.uint32)
    )
    label = (np.arange(n) % 7).astype(np.uint32)
    label[5] = 255
    data = np.rec.fromarrays(
        [xyz[:, 0], xyz[:, 1], xyz[:, 2], rgba, label],
        dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("rgba", "u4"), ("label", "u4")],
    )
    meta = MetaData.model_validate(
        {
            "fields": ("x", "y", "z", "rgba", "label"),
            "size": (4, 4, 4, 4, 4),
            "type": ("F", "F", "F", "U", "U"),
            "count": (1, 1, 1, 1, 1),
            "width": w,
            "height": h,
            "points": n,
            "version": "0.7",
            "viewpoint": (0, 0, 0, 1, 0, 0, 0),
            "data": "binary_compressed",
        }
    )
    file = "organised_binary_compressed.pcd"
    PointCloud(meta, np.asarray(data)).save(OUT / file, encoding=Encoding.BINARY_COMPRESSED)
    sidecar[file] = {
        "points": n,
        "organised": True,
        "width": w,
        "height": h,
        "expected": expected(xyz, rgb, label),
    }


def read_ascii_ply(path):
    lines = path.read_text().splitlines()
    body = lines[lines.index("end_header") + 1 :]
    rows = [l.split() for l in body if l.strip()]
    xyz = np.array([[float(v) for v in r[:3]] for r in rows], dtype=np.float32)
    camera = np.array([int(r[7]) for r in rows])
    pixel = np.array([int(r[8]) for r in rows])
    return xyz, camera, pixel


def scene():
    with tempfile.TemporaryDirectory() as tmp:
        ply = Path(tmp) / "scene.ply"
        boxes = OUT / "scene_handover_boxes.json"
        subprocess.run(
            [
                "cargo", "run", "--quiet", "--release", "-p", "bodyseg-lab",
                "--example", "pcd_scene", "--", str(ply), str(boxes),
            ],
            cwd=ROOT,
            check=True,
        )
        xyz, camera, pixel = read_ascii_ply(ply)
    depth_w, stride, cams = 512, 4, 3
    w, rows_per_cam = depth_w // stride, 424 // stride
    h = rows_per_cam * cams
    grid = np.full((h * w, 3), np.nan, dtype=np.float32)
    u = (pixel % depth_w) // stride
    v = (pixel // depth_w) // stride + camera * rows_per_cam
    grid[v * w + u] = xyz
    pc = PointCloud.from_points(
        [grid[:, 0], grid[:, 1], grid[:, 2]], ("x", "y", "z"), (np.float32,) * 3
    )
    pc.metadata.width = w
    pc.metadata.height = h
    pc.save(OUT / "scene_handover.pcd", encoding=Encoding.BINARY_COMPRESSED)


def main():
    OUT.mkdir(parents=True, exist_ok=True)
    sidecar = {}
    unorganised(sidecar)
    organised(sidecar)
    (OUT / "pcd_fixtures.json").write_text(json.dumps(sidecar, indent=1) + "\n")
    scene()
    total = sum(p.stat().st_size for p in OUT.glob("*"))
    print(f"wrote {OUT} ({total} bytes)")
    if total >= 500_000:
        sys.exit("fixtures exceed 500 KB")


if __name__ == "__main__":
    main()
