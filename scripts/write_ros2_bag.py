#!/usr/bin/env python3
"""Writes a ROS 2 bag (MCAP, rosbag2's layout) from a bodyseg recording, in iai_kinect2's
topic layout, with the ROS 2 Python tooling (mcap-ros2-support's writer and the real
message definitions, concatenated as rosbag2 stores them).

    python3 -m pip install -r scripts/requirements-ros2.txt
    python3 scripts/write_ros2_bag.py REC OUT.mcap [options]

Per camera NAME of REC/rig.toml (kinect2_bridge's names):
  /NAME/sd/image_depth (or image_depth_rect with --rect)    sensor_msgs/Image, the depth
  /NAME/sd/camera_info                                       the depth (IR) sensor
  /NAME/RES/image_color (or image_color_rect)                sensor_msgs/Image, the colour
  /NAME/RES/camera_info                                      the colour sensor
  with --compressed: .../image_color/compressed (JPEG or PNG) and
  .../image_depth/compressedDepth (image_transport_plugins' format) instead.
RES is --resolution (default from the colour width: 1920 hd, 960 qhd). With
--resolution sd the colour goes on /NAME/sd/image_color_rect, registered to the depth:
only for a recording whose colour sensor is its depth sensor.

/tf_static (one TFMessage, kinect2_bridge's tree under --world-frame):
  WORLD -> NAME_link                      world_from_colour (z-up world of the recording)
  NAME_link -> NAME_rgb_optical_frame     identity (as kinect2_bridge)
  NAME_rgb_optical_frame -> NAME_ir_optical_frame   color_from_depth

Frame i of the recording is stamped --start-sec + i / --fps (depth); colour
--colour-offset-ms later. --rect undistorts the images (nearest neighbour) and writes
CameraInfo with p = the raw k (ROS: a rectified image is described by p, without
distortion). --scale K keeps every K-th pixel (intrinsics / K), for small test fixtures;
--scaled-recording DIR writes the recording the bag then holds (rig.toml, images).
"""

import argparse
import io
import math
import os
import sys
import tomllib
from pathlib import Path

import numpy as np
from PIL import Image

try:
    from mcap.writer import CompressionType
    from mcap_ros2.writer import Writer
except ImportError:  # pragma: no cover - said to the user
    sys.exit("write_ros2_bag.py needs mcap-ros2-support: "
             "python3 -m pip install -r scripts/requirements-ros2.txt")

SEP = "=" * 80 + "\n"

# The .msg definitions of ROS 2 (common_interfaces, rcl_interfaces, geometry2), Humble on.
MSG = {
    "builtin_interfaces/Time": "int32 sec\nuint32 nanosec\n",
    "std_msgs/Header": "builtin_interfaces/Time stamp\nstring frame_id\n",
    "sensor_msgs/Image": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n"
        "uint8 is_bigendian\nuint32 step\nuint8[] data\n"),
    "sensor_msgs/CompressedImage": "std_msgs/Header header\nstring format\nuint8[] data\n",
    "sensor_msgs/RegionOfInterest": (
        "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n"),
    "sensor_msgs/CameraInfo": (
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n"
        "float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n"
        "uint32 binning_y\nRegionOfInterest roi\n"),
    "geometry_msgs/Vector3": "float64 x\nfloat64 y\nfloat64 z\n",
    "geometry_msgs/Quaternion": "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    "geometry_msgs/Transform": "Vector3 translation\nQuaternion rotation\n",
    "geometry_msgs/TransformStamped": (
        "std_msgs/Header header\nstring child_frame_id\nTransform transform\n"),
    "tf2_msgs/TFMessage": "geometry_msgs/TransformStamped[] transforms\n",
}

# Each type's dependencies, in the order rosbag2 appends them.
DEPS = {
    "sensor_msgs/Image": ["std_msgs/Header", "builtin_interfaces/Time"],
    "sensor_msgs/CompressedImage": ["std_msgs/Header", "builtin_interfaces/Time"],
    "sensor_msgs/CameraInfo": ["std_msgs/Header", "builtin_interfaces/Time",
                               "sensor_msgs/RegionOfInterest"],
    "tf2_msgs/TFMessage": ["geometry_msgs/TransformStamped", "std_msgs/Header",
                           "builtin_interfaces/Time", "geometry_msgs/Transform",
                           "geometry_msgs/Vector3", "geometry_msgs/Quaternion"],
}


def msgdef(name):
    """The schema text of `name` as rosbag2 stores it: the type, then each dependency
    after a separator line and `MSG: pkg/Type`."""
    text = MSG[name]
    for dep in DEPS.get(name, []):
        text += SEP + f"MSG: {dep}\n" + MSG[dep]
    return text


def schema_name(name):
    pkg, typ = name.split("/")
    return f"{pkg}/msg/{typ}"


def stamp_of(ns):
    return {"sec": ns // 1_000_000_000, "nanosec": ns % 1_000_000_000}


def quaternion_xyzw(r):
    """Unit quaternion [x, y, z, w] of a rotation matrix (Shepperd's method, w >= 0)."""
    t = r[0][0] + r[1][1] + r[2][2]
    if t > 0:
        s = 2.0 * math.sqrt(t + 1.0)
        w, x, y, z = 0.25 * s, (r[2][1] - r[1][2]) / s, (r[0][2] - r[2][0]) / s, (r[1][0] - r[0][1]) / s
    elif r[0][0] > r[1][1] and r[0][0] > r[2][2]:
        s = 2.0 * math.sqrt(1.0 + r[0][0] - r[1][1] - r[2][2])
        w, x, y, z = (r[2][1] - r[1][2]) / s, 0.25 * s, (r[0][1] + r[1][0]) / s, (r[0][2] + r[2][0]) / s
    elif r[1][1] > r[2][2]:
        s = 2.0 * math.sqrt(1.0 + r[1][1] - r[0][0] - r[2][2])
        w, x, y, z = (r[0][2] - r[2][0]) / s, (r[0][1] + r[1][0]) / s, 0.25 * s, (r[1][2] + r[2][1]) / s
    else:
        s = 2.0 * math.sqrt(1.0 + r[2][2] - r[0][0] - r[1][1])
        w, x, y, z = (r[1][0] - r[0][1]) / s, (r[0][2] + r[2][0]) / s, (r[1][2] + r[2][1]) / s, 0.25 * s
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    return [x, y, z, w]


def pose_matrix(table):
    """4x4 matrix of a rig.toml pose table (rotation or quaternion_wxyz, translation_m)."""
    m = np.eye(4)
    if "rotation" in table:
        m[:3, :3] = np.array(table["rotation"], dtype=float)
    else:
        w, x, y, z = table["quaternion_wxyz"]
        n = math.sqrt(w * w + x * x + y * y + z * z)
        w, x, y, z = w / n, x / n, y / n, z / n
        m[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    m[:3, 3] = table.get("translation_m", [0.0, 0.0, 0.0])
    return m


def transform(parent, child, m, ns):
    return {
        "header": {"stamp": stamp_of(ns), "frame_id": parent},
        "child_frame_id": child,
        "transform": {
            "translation": dict(zip("xyz", (float(v) for v in m[:3, 3]))),
            "rotation": dict(zip("xyzw", quaternion_xyzw(m[:3, :3].tolist()))),
        },
    }


def scaled_sensor(sensor, k):
    """A sensor table with every k-th pixel: size // k, focal lengths and centre / k."""
    if k == 1:
        return dict(sensor)
    out = dict(sensor)
    out["width"], out["height"] = sensor["width"] // k, sensor["height"] // k
    for key in ("fx", "fy", "cx", "cy"):
        out[key] = sensor[key] / k
    return out


def distort(d, x, y):
    """OpenCV's distortion of normalised coordinates (5 or 8 coefficients)."""
    d = list(d) + [0.0] * (8 - len(d))
    k1, k2, p1, p2, k3, k4, k5, k6 = d[:8]
    r2 = x * x + y * y
    radial = (1 + r2 * (k1 + r2 * (k2 + r2 * k3))) / (1 + r2 * (k4 + r2 * (k5 + r2 * k6)))
    xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x)
    yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y
    return xd, yd


def undistort_map(sensor):
    """For each pixel of the rectified image (same fx fy cx cy), the raw pixel it shows
    (nearest), or -1 outside."""
    w, h = sensor["width"], sensor["height"]
    u, v = np.meshgrid(np.arange(w, dtype=float), np.arange(h, dtype=float))
    x, y = (u - sensor["cx"]) / sensor["fx"], (v - sensor["cy"]) / sensor["fy"]
    xd, yd = distort(sensor.get("distortion", []), x, y)
    us = np.rint(xd * sensor["fx"] + sensor["cx"]).astype(int)
    vs = np.rint(yd * sensor["fy"] + sensor["cy"]).astype(int)
    inside = (us >= 0) & (us < w) & (vs >= 0) & (vs < h)
    return np.where(inside, vs * w + us, -1)


def remap(img, index):
    flat = img.reshape(-1, *img.shape[2:])
    out = flat[np.clip(index, 0, None)].reshape(*index.shape, *img.shape[2:])
    out[index < 0] = 0
    return out


def camera_info(sensor, frame_id, ns, rect):
    d = [float(v) for v in sensor.get("distortion", [0.0] * 5)]
    fx, fy, cx, cy = sensor["fx"], sensor["fy"], sensor["cx"], sensor["cy"]
    return {
        "header": {"stamp": stamp_of(ns), "frame_id": frame_id},
        "height": sensor["height"], "width": sensor["width"],
        "distortion_model": "rational_polynomial" if len(d) == 8 else "plumb_bob",
        "d": d,
        "k": [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
        "r": [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        # Monocular: p = [k | 0]; with --rect the rectified images are described by it.
        "p": [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
        "binning_x": 0, "binning_y": 0,
        "roi": {"x_offset": 0, "y_offset": 0, "height": 0, "width": 0, "do_rectify": False},
    }


def png_bytes(array, mode=None):
    buf = io.BytesIO()
    Image.fromarray(array, mode).save(buf, format="PNG")
    return buf.getvalue()


def read_depth(path):
    return np.array(Image.open(path), dtype=np.uint16)


def read_colour(path):
    return np.array(Image.open(path).convert("RGB"), dtype=np.uint8)


def colour_image(rgb, encoding):
    if encoding == "rgb8":
        data, step = rgb, 3
    elif encoding == "bgr8":
        data, step = rgb[..., ::-1], 3
    elif encoding in ("rgba8", "bgra8"):
        c = rgb if encoding == "rgba8" else rgb[..., ::-1]
        data, step = np.concatenate([c, np.full(rgb.shape[:2] + (1,), 255, np.uint8)], axis=2), 4
    elif encoding == "mono8":
        data, step = rgb.mean(axis=2).round().astype(np.uint8), 1
    else:
        raise SystemExit(f"--colour-encoding {encoding}: rgb8, bgr8, rgba8, bgra8 or mono8")
    return np.ascontiguousarray(data).tobytes(), rgb.shape[1] * step


def depth_image(depth_mm, encoding):
    if encoding in ("16UC1", "mono16"):
        return depth_mm.astype("<u2").tobytes(), depth_mm.shape[1] * 2
    if encoding == "32FC1":
        m = depth_mm.astype("<f4") / 1000.0
        m[depth_mm == 0] = np.nan
        return m.tobytes(), depth_mm.shape[1] * 4
    # Any other name is written as it is (for tests of unknown encodings).
    return depth_mm.astype("<u2").tobytes(), depth_mm.shape[1] * 2


def compressed_depth(depth_mm, encoding):
    """image_transport_plugins' compressedDepth: 12-byte ConfigHeader, then a PNG."""
    if encoding == "32FC1":
        # compressed_depth_image_transport's defaults: depth_max 10 m, quantisation 100.
        a = np.float32(100.0 * 101.0)
        b = np.float32(1.0 - a / np.float32(10.0))
        z = depth_mm.astype(np.float32) / np.float32(1000.0)
        q = np.where((z > 0) & (z < 10.0), a / np.where(z > 0, z, 1) + b, 0).astype(np.uint16)
        header = np.array([0], "<i4").tobytes() + np.array([a, b], "<f4").tobytes()
        return header + png_bytes(q), "32FC1; compressedDepth png"
    header = np.array([0], "<i4").tobytes() + np.array([0.0, 0.0], "<f4").tobytes()
    return header + png_bytes(depth_mm.astype(np.uint16)), f"{encoding}; compressedDepth png"


def write_toml_rig(rig, path):
    def floats(v):
        return "[" + ", ".join(repr(float(x)) for x in v) + "]"
    lines = []
    for cam in rig["camera"]:
        lines += ["[[camera]]", f'name = "{cam["name"]}"',
                  f"depth_scale = {float(cam.get('depth_scale', 1000.0))!r}",
                  f"depth_shift_mm = {float(cam.get('depth_shift_mm', 0.0))!r}", ""]
        for sensor in ("depth", "color"):
            s = cam[sensor]
            lines += [f"[camera.{sensor}]", f"width = {s['width']}", f"height = {s['height']}"]
            lines += [f"{k} = {float(s[k])!r}" for k in ("fx", "fy", "cx", "cy")]
            lines += [f"distortion = {floats(s.get('distortion', [0.0] * 5))}", ""]
        for pose in ("color_from_depth", "world_from_depth"):
            m = pose_matrix(cam.get(pose, {}))
            lines += [f"[camera.{pose}]",
                      "rotation = [" + ", ".join(floats(r) for r in m[:3, :3]) + "]",
                      f"translation_m = {floats(m[:3, 3])}", ""]
    path.write_text("\n".join(lines))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("recording", type=Path)
    ap.add_argument("out", type=Path, help="the .mcap file to write")
    ap.add_argument("--resolution", choices=["auto", "sd", "qhd", "hd"], default="auto")
    ap.add_argument("--rect", action="store_true", help="rectified topics (*_rect), undistorted")
    ap.add_argument("--compressed", action="store_true",
                    help="CompressedImage: colour JPEG (or --colour-format png), depth compressedDepth")
    ap.add_argument("--colour-format", choices=["jpeg", "png"], default="jpeg")
    ap.add_argument("--depth-encoding", default="16UC1", help="16UC1, mono16 or 32FC1")
    ap.add_argument("--colour-encoding", default="bgr8", help="rgb8, bgr8, rgba8, bgra8, mono8")
    ap.add_argument("--fps", type=float, default=30.0)
    ap.add_argument("--start-sec", type=int, default=1_700_000_000)
    ap.add_argument("--colour-offset-ms", type=float, default=3.0)
    ap.add_argument("--world-frame", default="world")
    ap.add_argument("--frames", type=int, help="only the first N frames")
    ap.add_argument("--repeat", type=int, default=1, help="write the frames N times over (long bags)")
    ap.add_argument("--scale", type=int, default=1, help="keep every K-th pixel")
    ap.add_argument("--scaled-recording", type=Path, help="write the recording the bag holds")
    ap.add_argument("--compression", choices=["zstd", "lz4", "none"], default="zstd")
    ap.add_argument("--skip-topic", action="append", default=[], help="leave out a topic (tests)")
    args = ap.parse_args()

    rig = tomllib.loads((args.recording / "rig.toml").read_text())
    cams = rig["camera"]
    k = args.scale
    for cam in cams:
        cam["depth"], cam["color"] = scaled_sensor(cam["depth"], k), scaled_sensor(cam["color"], k)
    stems = sorted(p.stem for p in (args.recording / cams[0]["name"] / "depth").glob("*.png"))
    if args.frames:
        stems = stems[: args.frames]
    res = args.resolution
    if res == "auto":
        res = "hd" if cams[0]["color"]["width"] * k >= 1920 else "qhd"
    if res == "sd":
        for cam in cams:
            same = cam["color"] == cam["depth"] and np.allclose(pose_matrix(cam.get("color_from_depth", {})), np.eye(4))
            if not same:
                sys.exit(f"--resolution sd: camera {cam['name']}'s colour is not registered to its depth")

    compression = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4,
                   "none": CompressionType.NONE}[args.compression]
    tmp = args.out.with_name(args.out.name + ".tmp")
    with open(tmp, "wb") as f:
        writer = Writer(f, compression=compression)
        schemas = {n: writer.register_msgdef(schema_name(n), msgdef(n)) for n in DEPS}
        t0 = args.start_sec * 1_000_000_000
        transforms = []
        for cam in cams:
            n = cam["name"]
            color_from_depth = pose_matrix(cam.get("color_from_depth", {}))
            world_from_depth = pose_matrix(cam.get("world_from_depth", {}))
            world_from_colour = world_from_depth @ np.linalg.inv(color_from_depth)
            transforms += [transform(args.world_frame, f"{n}_link", world_from_colour, t0),
                           transform(f"{n}_link", f"{n}_rgb_optical_frame", np.eye(4), t0),
                           transform(f"{n}_rgb_optical_frame", f"{n}_ir_optical_frame",
                                     color_from_depth, t0)]

        def write(topic, schema, msg, ns):
            if topic not in args.skip_topic:
                writer.write_message(topic, schemas[schema], msg, log_time=ns, publish_time=ns)

        write("/tf_static", "tf2_msgs/TFMessage", {"transforms": transforms}, t0)
        maps = {}
        frame = 0
        for _ in range(args.repeat):
            for stem in stems:
                depth_ns = t0 + round(frame * 1e9 / args.fps)
                colour_ns = depth_ns + round(args.colour_offset_ms * 1e6)
                frame += 1
                for cam in cams:
                    n = cam["name"]
                    ir, rgb = f"{n}_ir_optical_frame", f"{n}_rgb_optical_frame"
                    colour_frame = ir if res == "sd" else rgb
                    depth = read_depth(args.recording / n / "depth" / f"{stem}.png")[::k, ::k]
                    cpath = next((args.recording / n / "color").glob(f"{stem}.*"))
                    colour = read_colour(cpath)[::k, ::k]
                    depth = depth[: cam["depth"]["height"], : cam["depth"]["width"]]
                    colour = colour[: cam["color"]["height"], : cam["color"]["width"]]
                    if args.rect:
                        for key, sensor in (("d", cam["depth"]), ("c", cam["color"])):
                            if (n, key) not in maps:
                                maps[(n, key)] = undistort_map(sensor)
                        depth = remap(depth, maps[(n, "d")])
                        colour = remap(colour, maps[(n, "c")])
                    if args.scaled_recording and frame <= len(stems):
                        for layer, img in (("depth", depth), ("color", colour)):
                            folder = args.scaled_recording / n / layer
                            folder.mkdir(parents=True, exist_ok=True)
                            Image.fromarray(img).save(folder / f"{stem}.png")
                    suffix = "_rect" if args.rect else ""
                    depth_topic = f"/{n}/sd/image_depth{suffix}"
                    colour_topic = f"/{n}/{res}/image_color{'_rect' if res == 'sd' else suffix}"
                    write(f"/{n}/sd/camera_info", "sensor_msgs/CameraInfo",
                          camera_info(cam["depth"], ir, depth_ns, args.rect), depth_ns)
                    if res != "sd":
                        write(f"/{n}/{res}/camera_info", "sensor_msgs/CameraInfo",
                              camera_info(cam["color"], colour_frame, colour_ns, args.rect), colour_ns)
                    dh = {"stamp": stamp_of(depth_ns), "frame_id": ir}
                    ch = {"stamp": stamp_of(colour_ns), "frame_id": colour_frame}
                    if args.compressed:
                        data, fmt = compressed_depth(depth, args.depth_encoding)
                        write(depth_topic + "/compressedDepth", "sensor_msgs/CompressedImage",
                              {"header": dh, "format": fmt, "data": data}, depth_ns)
                        buf = io.BytesIO()
                        if args.colour_format == "jpeg":
                            Image.fromarray(colour).save(buf, format="JPEG", quality=95)
                            fmt = "bgr8; jpeg compressed bgr8"
                        else:
                            Image.fromarray(colour).save(buf, format="PNG")
                            fmt = "bgr8; png compressed bgr8"
                        write(colour_topic + "/compressed", "sensor_msgs/CompressedImage",
                              {"header": ch, "format": fmt, "data": buf.getvalue()}, colour_ns)
                    else:
                        data, step = depth_image(depth, args.depth_encoding)
                        write(depth_topic, "sensor_msgs/Image",
                              {"header": dh, "height": depth.shape[0], "width": depth.shape[1],
                               "encoding": args.depth_encoding, "is_bigendian": 0, "step": step,
                               "data": data}, depth_ns)
                        data, step = colour_image(colour, args.colour_encoding)
                        write(colour_topic, "sensor_msgs/Image",
                              {"header": ch, "height": colour.shape[0], "width": colour.shape[1],
                               "encoding": args.colour_encoding, "is_bigendian": 0, "step": step,
                               "data": data}, colour_ns)
        writer.finish()
    os.replace(tmp, args.out)
    if args.scaled_recording:
        rect_cams = cams
        if args.rect:
            rect_cams = [dict(c, depth=dict(c["depth"], distortion=[0.0] * 5),
                              color=dict(c["color"], distortion=[0.0] * 5)) for c in cams]
        write_toml_rig({"camera": rect_cams}, args.scaled_recording / "rig.toml")
    print(f"{args.out}: {frame} frames x {len(cams)} cameras, colour on /NAME/{res}/, "
          f"{args.out.stat().st_size} bytes")


if __name__ == "__main__":
    main()
