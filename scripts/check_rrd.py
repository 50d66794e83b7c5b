#!/usr/bin/env python3
"""Checks a bodyseg `.rrd` file with the Rerun Python SDK (a real client, not our reader).

    check_rrd.py FILE.rrd --run OUT [--cameras cam0,cam1,cam2] [--expect-scores]
                 [--clusters yes|no] [--recording REC]

Reads FILE.rrd with `rerun-sdk` (the version of the Rust SDK that wrote it, see
Cargo.toml's `re_sdk`) through its dataframe API (`rr.experimental.RrdReader(...)
.stream().collect().reader(index="frame", ...)`, a DataFusion DataFrame) and checks, against
the run's files in OUT (a run of the whole recording):

- the `frame` timeline has one row per cloud in OUT/clouds/ (indices 0..n-1, the frames in
  stem order);
- per frame and layer (refined, projected), the points of world/<layer> (as many class ids,
  none 255) + world/<layer>_unknown (class id 255) equal the vertex count of
  OUT/clouds/<stem>.ply; world/refined's class ids, counted per class, and its unknown points
  equal the PLY's `label`s (the refined labels: the points are in another order);
- per frame, the boxes of world/boxes (their count and centres) equal those of
  OUT/boxes/<stem>.json;
- every camera's colour image (an EncodedImage with its media type: the recording's file),
  depth image, 2D labels and refined labels are there for every frame (with --recording
  REC, each colour image's bytes equal to REC/<camera>/color/<stem>.png|.jpg and each depth
  image's values to REC/<camera>/depth/<stem>.png), and its Pinhole and Transform3D (static)
  at world/cameras/<name>/color and /depth;
- the AnnotationContext at world; with --expect-scores, scores/<configuration>/biou, and
  each configuration's biou and miou equal to the frame's OUT/frames/<stem>.json;
- with --clusters yes, per frame world/clusters has as many points as the PLY (`run
  --rerun-clusters`); with --clusters no, world/clusters is not in the file (the default).

Exit 0 and one summary line when all hold; exit 1 listing every failure; exit 2 when the
SDK (or its dataframe extra) is not installed: `pip install "rerun-sdk[datafusion]==0.36.3"`.
"""

import argparse
import json
import sys
from pathlib import Path

RERUN_VERSION = "0.36.3"


def ply_vertex_count(path: Path) -> int:
    with open(path, "rb") as f:
        for raw in f:
            line = raw.decode("ascii", "replace").strip()
            if line.startswith("element vertex"):
                return int(line.split()[2])
            if line == "end_header":
                break
    raise ValueError(f"{path}: no `element vertex` in the header")


def ply_labels(path: Path):
    """The `label` of every vertex of a binary little-endian PLY (numpy uint8 array)."""
    import numpy as np

    types = {"float": "<f4", "uchar": "u1", "uint": "<u4", "int": "<i4", "ushort": "<u2",
             "short": "<i2", "char": "i1", "double": "<f8"}
    fields = []
    with open(path, "rb") as f:
        while True:
            line = f.readline().decode("ascii", "replace").strip()
            if line.startswith("format") and "binary_little_endian" not in line:
                raise ValueError(f"{path}: {line}: only binary_little_endian is read")
            if line.startswith("element vertex"):
                n = int(line.split()[2])
            elif line.startswith("property"):
                _, kind, name = line.split()
                fields.append((name, types[kind]))
            elif line == "end_header" or not line:
                break
        return np.fromfile(f, dtype=np.dtype(fields), count=n)["label"]


def class_counts(values) -> dict[int, int]:
    """Class id -> count over the cells of one column (lists of class ids)."""
    import numpy as np

    cells = [np.asarray(v, dtype=np.int64) for v in values if v is not None]
    if not cells:
        return {}
    ids, counts = np.unique(np.concatenate(cells), return_counts=True)
    return {int(i): int(c) for i, c in zip(ids, counts)}


def column(df, entity: str, archetype: str, component: str) -> str | None:
    """The DataFrame column of `entity`'s `archetype:component` (names like
    `/world/refined:Points3D:positions`)."""
    want = f"/{entity}:{archetype}:{component}"
    for name in df.columns:
        if name == want or name.endswith(want):
            return name
    return None


def batch_len(value) -> int:
    """Number of instances in one cell (a list of points/boxes), 0 for null."""
    if value is None:
        return 0
    try:
        return len(value)
    except TypeError:
        return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("rrd", type=Path)
    ap.add_argument("--run", type=Path, required=True, help="the run's output folder")
    ap.add_argument("--cameras", default="", help="camera names, comma-separated")
    ap.add_argument("--expect-scores", action="store_true")
    ap.add_argument("--clusters", choices=("yes", "no"), help="whether world/clusters is there")
    ap.add_argument("--recording", type=Path,
                    help="the recording: each colour image's bytes, and each depth image's "
                    "values, must equal its file's")
    args = ap.parse_args()

    try:
        import rerun as rr
        import rerun.experimental as rrx
        import datafusion  # noqa: F401  (the dataframe API's engine)
        import numpy as np
        from PIL import Image  # rerun-sdk's own dependency
    except ImportError as e:
        print(
            f"check_rrd: the Rerun SDK is not installed ({e}); "
            f'pip install "rerun-sdk[datafusion]=={RERUN_VERSION}"',
            file=sys.stderr,
        )
        return 2
    if rr.__version__ != RERUN_VERSION:
        print(
            f"check_rrd: rerun-sdk {rr.__version__} installed, the file was written by "
            f"{RERUN_VERSION}; checking anyway",
            file=sys.stderr,
        )

    failures: list[str] = []
    stems = sorted(p.stem for p in (args.run / "clouds").glob("*.ply"))
    if not stems:
        print(f"check_rrd: {args.run}/clouds: no PLY file", file=sys.stderr)
        return 1
    cameras = [c for c in args.cameras.split(",") if c]

    reader = rrx.RrdReader(args.rrd)
    recordings = reader.recordings()
    if len(recordings) != 1:
        failures.append(f"{len(recordings)} recordings in the file, want 1")
    store = reader.stream().collect()

    df = store.reader(index="frame").to_pandas()
    frames = sorted(int(v) for v in df["frame"].dropna().unique())
    if frames != list(range(len(stems))):
        failures.append(
            f"frame timeline holds {frames[:5]}... ({len(frames)}), want 0..{len(stems) - 1}"
        )

    def rows_of(frame: int):
        return df[df["frame"] == frame]

    def count(frame_rows, entity: str, archetype: str, component: str) -> int | None:
        name = column(df, entity, archetype, component)
        if name is None:
            return None
        return sum(batch_len(v) for v in frame_rows[name])

    def present(frame_rows, entity: str, archetype: str, component: str) -> bool:
        name = column(df, entity, archetype, component)
        return name is not None and frame_rows[name].notna().any()

    total_points = 0
    for index, stem in enumerate(stems):
        rows = rows_of(index)
        want = ply_vertex_count(args.run / "clouds" / f"{stem}.ply")
        total_points += want
        labels = ply_labels(args.run / "clouds" / f"{stem}.ply")
        for layer in ("refined", "projected"):
            known = count(rows, f"world/{layer}", "Points3D", "positions")
            ids = count(rows, f"world/{layer}", "Points3D", "class_ids")
            # An entity whose positions are always empty has no positions column.
            unknown = count(rows, f"world/{layer}_unknown", "Points3D", "positions") or 0
            if known is None or not present(rows, f"world/{layer}_unknown", "Points3D",
                                            "class_ids"):
                failures.append(f"frame {stem}: no world/{layer} or world/{layer}_unknown")
                continue
            if known + unknown != want or ids != known:
                failures.append(
                    f"frame {stem}: world/{layer} has {known} points ({ids} class ids) + "
                    f"{unknown} unknown points, the PLY {want}"
                )
            name = column(df, f"world/{layer}", "Points3D", "class_ids")
            got = class_counts(rows[name]) if name else {}
            if 255 in got:
                failures.append(f"frame {stem}: world/{layer} has {got[255]} unknown points")
            name = column(df, f"world/{layer}_unknown", "Points3D", "class_ids")
            if unknown and (name is None or set(class_counts(rows[name])) != {255}):
                failures.append(f"frame {stem}: world/{layer}_unknown: class ids not 255")
            if layer == "refined":
                ply = {int(k): int(v) for k, v in zip(*np.unique(labels, return_counts=True))}
                if {**got, **({255: unknown} if unknown else {})} != ply:
                    failures.append(
                        f"frame {stem}: world/refined's class ids {sorted(got.items())} + "
                        f"{unknown} unknown, the PLY's labels {sorted(ply.items())}"
                    )
        clusters = count(rows, "world/clusters", "Points3D", "positions")
        if args.clusters == "yes" and clusters != want:
            failures.append(f"frame {stem}: world/clusters has {clusters} points, the PLY {want}")
        if args.clusters == "no" and clusters is not None:
            failures.append(f"frame {stem}: world/clusters is there ({clusters} points)")
        boxes_file = args.run / "boxes" / f"{stem}.json"
        if boxes_file.is_file():
            boxes = json.loads(boxes_file.read_text())["boxes"]
            got_boxes = count(rows, "world/boxes", "Boxes3D", "half_sizes") or 0
            if got_boxes != len(boxes):
                failures.append(f"frame {stem}: {got_boxes} boxes, the JSON {len(boxes)}")
            name = column(df, "world/boxes", "Boxes3D", "centers")
            cells = [v for v in rows[name] if v is not None and len(v)] if name else []
            got = np.array([list(c) for c in cells[0]], dtype=np.float64) if cells else None
            want = np.array([b["center_m"] for b in boxes], dtype=np.float64).reshape(-1, 3)
            if boxes and (got is None or got.shape != want.shape
                          or not np.allclose(got, want, atol=1e-5)):
                failures.append(f"frame {stem}: world/boxes' centres are not the JSON's")
        for c in cameras:
            base = f"world/cameras/{c}"
            for entity, archetype, component in (
                (f"{base}/color/image", "EncodedImage", "blob"),
                (f"{base}/color/image", "EncodedImage", "media_type"),
                (f"{base}/depth/image", "DepthImage", "buffer"),
                (f"{base}/color/labels", "SegmentationImage", "buffer"),
                (f"{base}/color/refined_labels", "SegmentationImage", "buffer"),
            ):
                if not present(rows, entity, archetype, component):
                    failures.append(f"frame {stem}: no {entity} ({archetype})")
            if args.recording is not None:
                files = [f for f in (args.recording / c / "color").glob(f"{stem}.*")
                         if f.suffix.lower() in (".png", ".jpg", ".jpeg")]
                name = column(df, f"{base}/color/image", "EncodedImage", "blob")
                blobs = [v for v in rows[name] if v is not None] if name else []
                got = bytes(blobs[0][0].tobytes()) if blobs and len(blobs[0]) else None
                if len(files) != 1 or got != files[0].read_bytes():
                    failures.append(
                        f"frame {stem}: {base}/color/image is not the bytes of "
                        f"{args.recording / c / 'color'}/{stem}.png|.jpg"
                    )
                depth_png = args.recording / c / "depth" / f"{stem}.png"
                if not depth_png.is_file():
                    failures.append(f"frame {stem}: no {depth_png} to compare the depth with")
                else:
                    name = column(df, f"{base}/depth/image", "DepthImage", "buffer")
                    buffers = [v for v in rows[name] if v is not None] if name else []
                    got = (np.frombuffer(buffers[0][0].tobytes(), dtype="<u2")
                           if buffers and len(buffers[0]) else None)
                    with Image.open(depth_png) as png:
                        want = np.asarray(png, dtype=np.uint16).ravel()
                    if got is None or not np.array_equal(got, want):
                        failures.append(
                            f"frame {stem}: {base}/depth/image's values are not those of "
                            f"{depth_png}"
                        )
        if args.expect_scores:
            if not any(":Scalars:scalars" in n and "/scores/" in n and "biou" in n
                       for n in df.columns if rows[n].notna().any()):
                failures.append(f"frame {stem}: no scores/<configuration>/biou")
            # Each configuration's BIoU and mIoU equal the frame's record, where it has one.
            record = args.run / "frames" / f"{stem}.json"
            scores = json.loads(record.read_text()).get("scores") if record.is_file() else None
            for config in (scores or {}).get("configurations", []):
                for metric in ("biou", "miou"):
                    entity = f"scores/{config['name']}/{metric}"
                    name = column(df, entity, "Scalars", "scalars")
                    values = [float(v[0]) for v in rows[name] if v is not None and len(v)] \
                        if name else []
                    want = config["metrics"][metric]
                    if len(values) != 1 or abs(values[0] - want) > 1e-9:
                        failures.append(f"frame {stem}: {entity} is {values}, {record} {want}")

    static = store.reader(index=None).to_pandas()
    for c in cameras:
        for sensor in ("color", "depth"):
            entity = f"world/cameras/{c}/{sensor}"
            for archetype, component in (("Pinhole", "image_from_camera"),
                                         ("Transform3D", "translation")):
                if column(static, entity, archetype, component) is None:
                    failures.append(f"no static {archetype} at {entity}")
    if column(static, "world", "AnnotationContext", "context") is None:
        failures.append("no AnnotationContext at world")

    if failures:
        for f in failures:
            print(f"check_rrd: {f}", file=sys.stderr)
        return 1
    print(
        f"check_rrd: {args.rrd}: {len(stems)} frames, {total_points} points, "
        f"{len(cameras)} cameras: all entities present, counts equal the run's files"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
