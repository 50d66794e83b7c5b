#!/usr/bin/env python3
"""Writes the fuzz targets' seed corpus, fuzz/corpus/<target>/: small real files copied
from the repository's fixtures, and small generated ones that reach each reader's
branches (every PLY encoding and list properties, every PCD data kind, plain and
compressed MAT, 8- and 16-bit PNG). Standard library only; deterministic output.

    python3 fuzz/gen_seeds.py        (from any folder; rewrites fuzz/corpus/)
"""

import shutil
import struct
import zlib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
CORPUS = ROOT / "fuzz" / "corpus"
# Seeds stay small: libFuzzer mutates whole inputs, and a large seed slows every run.
MAX_SEED_BYTES = 16 << 10


def write(target: str, name: str, data: bytes) -> None:
    folder = CORPUS / target
    folder.mkdir(parents=True, exist_ok=True)
    assert len(data) <= MAX_SEED_BYTES, (target, name, len(data))
    (folder / name).write_bytes(data)


def copy(target: str, source: str, name: str | None = None) -> None:
    path = ROOT / source
    write(target, name or path.name, path.read_bytes())


# --- PLY ---------------------------------------------------------------------------------

VERTICES = [
    (0.1, -0.2, 1.5, 1, 200, 30, 40, 0, 7),
    (0.0, 0.0, 2.0, 0, 10, 20, 30, 1, 513),
    (-1.25, 0.5, 0.75, 255, 0, 0, 255, 2, 99),
]


def ply_header(fmt: str, props: str, extra: str = "", count: int = len(VERTICES)) -> bytes:
    return (
        f"ply\nformat {fmt} 1.0\ncomment bodyseg fuzz seed\n{extra}"
        f"element vertex {count}\n{props}end_header\n"
    ).encode()


FULL_PROPS = (
    "property float x\nproperty float y\nproperty float z\nproperty uchar label\n"
    "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    "property uchar camera\nproperty uint pixel\n"
)


def ply_seeds() -> None:
    lines = "".join(" ".join(str(v) for v in vx) + "\n" for vx in VERTICES)
    write("ply", "ascii.ply", ply_header("ascii", FULL_PROPS) + lines.encode())
    for fmt, order in [("binary_little_endian", "<"), ("binary_big_endian", ">")]:
        body = b"".join(struct.pack(order + "fffBBBBBI", *vx) for vx in VERTICES)
        write("ply", f"{fmt}.ply", ply_header(fmt, FULL_PROPS) + body)
    # Other types (double, int label, float colours), a face element with a list before
    # the vertices, and a list property inside the vertex element.
    props = (
        "property double x\nproperty double y\nproperty double z\nproperty int label\n"
        "property float red\nproperty float green\nproperty float blue\n"
        "property list uchar int extra\n"
    )
    face = "element face 1\nproperty list uchar int vertex_indices\n"
    body = struct.pack("<B3i", 3, 0, 1, 2)
    for x, y, z, label, r, g, b, _, _ in VERTICES:
        body += struct.pack("<dddifff", x, y, z, label, r / 255, g / 255, b / 255)
        body += struct.pack("<B2i", 2, 5, 6)
    write("ply", "types_lists.ply", ply_header("binary_little_endian", props, face) + body)
    minimal = "property float x\nproperty float y\nproperty float z\nproperty uchar label\n"
    write("ply", "minimal_ascii.ply", ply_header("ascii", minimal, count=1) + b"1 2 3 4\n")


# --- PCD ---------------------------------------------------------------------------------


def lzf_literals(data: bytes) -> bytes:
    """LZF 'compression' as literal runs only (valid LZF, what PCL reads)."""
    out = bytearray()
    for i in range(0, len(data), 32):
        chunk = data[i : i + 32]
        out.append(len(chunk) - 1)
        out += chunk
    return bytes(out)


def pcd_seeds() -> None:
    for name in [
        "xyzrgb_ascii.pcd",
        "xyzrgb_binary.pcd",
        "xyzrgb_binary_compressed.pcd",
        "organised_binary_compressed.pcd",
    ]:
        copy("pcd", f"crates/io/tests/data/{name}")
    header = (
        "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb label _\nSIZE 4 4 4 4 1 1\n"
        "TYPE F F F U U U\nCOUNT 1 1 1 1 1 2\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
        "POINTS 3\nDATA {}\n"
    )
    points = [(0.5, 1.0, 2.0, 0xFF0000, 1), (float("nan"), 0.0, 0.0, 0x00FF00, 255), (1.0, -1.0, 3.0, 0x0000FF, 6)]
    ascii = header.format("ascii") + "".join(
        f"{x} {y} {z} {c} {l} 0 0\n" for x, y, z, c, l in points
    )
    write("pcd", "label_ascii.pcd", ascii.encode())
    records = b"".join(struct.pack("<fffIBBB", x, y, z, c, l, 0, 0) for x, y, z, c, l in points)
    write("pcd", "label_binary.pcd", header.format("binary").encode() + records)
    columns = b"".join(
        [
            b"".join(struct.pack("<f", p[0]) for p in points),
            b"".join(struct.pack("<f", p[1]) for p in points),
            b"".join(struct.pack("<f", p[2]) for p in points),
            b"".join(struct.pack("<I", p[3]) for p in points),
            bytes(p[4] for p in points),
            bytes(6),
        ]
    )
    block = lzf_literals(columns)
    write(
        "pcd",
        "label_binary_compressed.pcd",
        header.format("binary_compressed").encode()
        + struct.pack("<II", len(block), len(columns))
        + block,
    )


# --- MAT ---------------------------------------------------------------------------------


def mat_header() -> bytes:
    text = b"MATLAB 5.0 MAT-file, bodyseg fuzz seed".ljust(116, b" ")
    return text + bytes(8) + struct.pack("<H", 0x0100) + b"IM"


def padded(data: bytes) -> bytes:
    return data + bytes(-len(data) % 8)


def sub(ty: int, data: bytes) -> bytes:
    return struct.pack("<II", ty, len(data)) + padded(data)


def mat_array(name: bytes, rows: int, cols: int, cls: int, data_ty: int, data: bytes) -> bytes:
    body = sub(6, struct.pack("<II", cls, 0))
    body += sub(5, struct.pack("<ii", rows, cols))
    if len(name) <= 4:  # the small element form
        body += struct.pack("<HH", 1, len(name)) + name.ljust(4, b"\0")
    else:
        body += sub(1, name)
    body += sub(data_ty, data)
    return struct.pack("<II", 14, len(body)) + body


def mat_seeds() -> None:
    copy("mat", "tests/fixtures/3dpeople/depth_mat/woman01/02_04_jump/camera01/depth.mat", "3dpeople_depth.mat")
    doubles = struct.pack("<6d", 1.0, 4.0, 2.0, 5.0, 3.0, 6.0)
    plain = mat_array(b"a", 2, 3, 6, 9, doubles)
    uint16 = mat_array(b"depth_map", 2, 2, 11, 4, struct.pack("<4H", 0, 1000, 65535, 7))
    write("mat", "two_variables.mat", mat_header() + plain + uint16)
    inner = mat_array(b"depth", 3, 2, 7, 7, struct.pack("<6f", 0.5, 1.5, 2.5, 0, -1, 1e3))
    compressed = zlib.compress(inner, 9)
    write("mat", "compressed.mat", mat_header() + struct.pack("<II", 15, len(compressed)) + compressed)


# --- PNG ---------------------------------------------------------------------------------


def png(width: int, height: int, bit_depth: int, color_type: int, rows: list[bytes]) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    ihdr = struct.pack(">IIBBBBB", width, height, bit_depth, color_type, 0, 0, 0)
    raw = b"".join(b"\0" + row for row in rows)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b"")


def png_seeds() -> None:
    depth = [struct.pack(">4H", 0, 1000 + v, 2500, 65535) for v in range(3)]
    write("png", "depth16.png", png(4, 3, 16, 0, depth))
    labels = [bytes([0, 1, 2, 255]), bytes([3, 4, 5, 6]), bytes([255, 0, 0, 1])]
    write("png", "labels8.png", png(4, 3, 8, 0, labels))
    copy("png", "tests/fixtures/3dpeople/segmentation_body/man01/01_01_walk/camera01/0001.png", "3dpeople_segmentation.png")
    rgb = [bytes([255, 0, 0, 0, 255, 0]), bytes([0, 0, 255, 10, 20, 30])]
    write("color_image", "rgb8.png", png(2, 2, 8, 2, rgb))
    rgba16 = [struct.pack(">8H", 65535, 0, 0, 65535, 0, 65535, 0, 32768)]
    write("color_image", "rgba16.png", png(2, 1, 16, 6, rgba16))
    copy("color_image", "tests/fixtures/3dpeople/rgb/man01/01_01_walk/camera01/outfit/0001.jpg", "3dpeople.jpg")


# --- text formats ------------------------------------------------------------------------

IDENTITY = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]


def sensor(
    width: int, height: int, fx: float, fy: float, cx: float, cy: float, distortion: list[float]
) -> str:
    """One sensor's keys, as under `[camera.depth]`, `[camera.color]` or in an intrinsics file."""
    return (
        f"width = {width}\nheight = {height}\n"
        f"fx = {fx}\nfy = {fy}\ncx = {cx}\ncy = {cy}\ndistortion = {distortion}\n"
    )


def camera(name: str, header: str, depth: str, color: str, world_from_depth: str) -> str:
    """One `[[camera]]` of a rig.toml: the keys after its name (`header`), its two sensors,
    the identity rotation and 52 mm baseline from depth to colour, and `world_from_depth`'s keys."""
    return (
        f'[[camera]]\nname = "{name}"\n{header}\n'
        f"[camera.depth]\n{depth}\n"
        f"[camera.color]\n{color}\n"
        f"[camera.color_from_depth]\nrotation = {IDENTITY}\ntranslation_m = [-0.052, 0.0, 0.0]\n\n"
        f"[camera.world_from_depth]\n{world_from_depth}"
    )


# Two cameras: Brown-Conrady depth, rational (8-coefficient) colour and a quaternion pose,
# then undistorted sensors, default depth scale and shift, and a rotation-matrix pose.
RIG = camera(
    "cam0",
    "depth_scale = 1000.0\ndepth_shift_mm = 0.0\n",
    sensor(512, 424, 366.9, 364.8, 243.0, 207.7, [0.0966, -0.283, 0.000159, -0.000508, 0.105]),
    sensor(
        1920, 1080, 1059.9, 1053.9, 954.9, 523.7, [0.0563, -0.0742, 0.00143, -0.0017, 0.0241, 0.1, 0.2, 0.3]
    ),
    "quaternion_wxyz = [0.7071067811865476, 0.7071067811865476, 0.0, 0.0]\ntranslation_m = [0.0, -3.0, 2.2]\n",
) + "\n" + camera(
    "cam1",
    "",
    sensor(512, 424, 365.0, 365.0, 256.0, 212.0, [0.0] * 5),
    sensor(1920, 1080, 1050.0, 1050.0, 960.0, 540.0, [0.0] * 5),
    "rotation = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]\ntranslation_m = [2.0, 0.0, 2.2]\n",
)

INTRINSICS = sensor(640, 576, 504.2, 504.3, 321.5, 330.1, [0.5, -0.1, 0.0001, -0.0002, 0.01])

BOXES = """{
  "frame": "000042",
  "boxes": [
    {"id": 0, "center_m": [0.5, 1.0, 0.9], "half_extents_m": [0.3, 0.25, 0.9], "yaw_rad": 0.3},
    {"id": 1, "center_m": [-1.0, 0.0, 0.85], "half_extents_m": [0.25, 0.2, 0.85]}
  ]
}
"""


def text_seeds() -> None:
    copy("boxes", "crates/io/tests/data/scene_handover_boxes.json")
    write("boxes", "two_boxes.json", BOXES.encode())
    write("rig_toml", "rig.toml", RIG.encode())
    write("rig_toml", "intrinsics.toml", INTRINSICS.encode())
    for serial in ["299150235147", "019469645147"]:
        for name in ["calib_color.yaml", "calib_ir.yaml", "calib_pose.yaml", "calib_depth.yaml"]:
            source = ROOT / "tests/fixtures/calib/iai_kinect2" / serial / name
            if source.exists():
                copy("opencv_yaml", str(source.relative_to(ROOT)), f"{serial}_{name}")
    for source in sorted((ROOT / "tests/fixtures/calib/ros").glob("*.yaml")):
        copy("ros_camera_info", str(source.relative_to(ROOT)))
    copy("ros_camera_info", "crates/calib/tests/data/ros_camera_info.yaml")
    for source in sorted((ROOT / "tests/fixtures/calib/openptrack").glob("*/camera_poses.yaml")):
        copy("openptrack", str(source.relative_to(ROOT)), f"{source.parent.name}.yaml")
    copy("openptrack", "crates/calib/tests/data/openptrack_camera_poses.yaml")
    for source in sorted((ROOT / "tests/fixtures/calib/azure_kinect").glob("*.json")):
        if source.stat().st_size <= MAX_SEED_BYTES:
            copy("azure_kinect", str(source.relative_to(ROOT)))
    copy("azure_kinect", "crates/calib/tests/data/azure_kinect_calibration.json")
    # The default file is mostly comments (past 16 KiB): its seed keeps the TOML alone, which
    # is all the config reader parses; comments are covered by the benchmark files.
    text = (ROOT / "configs/default.toml").read_text()
    keys = [line for line in text.splitlines() if line.strip() and not line.lstrip().startswith("#")]
    write("config", "default.toml", ("\n".join(keys) + "\n").encode())
    for source in sorted((ROOT / "configs/benchmarks").glob("*.toml")):
        copy("config", str(source.relative_to(ROOT)), f"benchmark_{source.name}")
    write("config", "settings.txt", b"refine.eps_m=0.05\nproject.mode=naive\nboxes.mode=\"labels\"\n")


def main() -> None:
    if CORPUS.exists():
        shutil.rmtree(CORPUS)
    ply_seeds()
    pcd_seeds()
    mat_seeds()
    png_seeds()
    text_seeds()
    for folder in sorted(CORPUS.iterdir()):
        files = list(folder.iterdir())
        print(f"{folder.name}: {len(files)} seeds, {sum(f.stat().st_size for f in files)} bytes")


if __name__ == "__main__":
    main()
