"""SCHP pre- and post-processing in numpy: the reference for bodyseg-parsing's transform.rs.

Shared by scripts/gen_parsing_golden.py (golden values the Rust tests compare against),
scripts/train_parser.py (training inputs and the held-out evaluation) and
scripts/gen_parsing_test_model.py. Formulas: shared/ALGORITHM.md §2.

  centre (cx, cy) = ((w-1)/2, (h-1)/2),  k = (S-1)/max(w-1, h-1)
  x' = (x - cx)*k + (S-1)/2,  y' = (y - cy)*k + (S-1)/2
  bilinear sampling, a neighbour outside the image counts as 0 (border 0), each sample
  rounded to a whole grey level (ties to even: SCHP's cv2.warpAffine writes a uint8 image),
  before normalisation ((v/255 - mean)/std in the sidecar's channel order).
"""

import json

import numpy as np

CLASS_NAMES = ["background", "head", "torso", "upper_arms", "lower_arms", "upper_legs", "lower_legs"]
NUM_CLASSES = 7


def write_sidecar(path, s, channel_order, mean, std, align_corners, description):
    """Writes the sidecar JSON bodyseg-parsing reads beside an ONNX parser (output stride 2,
    CLASS_NAMES), indented, with a final newline."""
    sidecar = {
        "input_size": [s, s],
        "channel_order": channel_order,
        "mean": mean,
        "std": std,
        "class_names": CLASS_NAMES,
        "output_stride": 2,
        "align_corners": align_corners,
        "description": description,
    }
    path.write_text(json.dumps(sidecar, indent=2) + "\n")


def input_transform(w, h, s):
    """(k, cx, cy) of the image -> input similarity transform."""
    k = (s - 1) / max(w - 1, h - 1, 1)
    return k, (w - 1) / 2.0, (h - 1) / 2.0


def input_from_image(w, h, s):
    """2x3 matrix M with [x', y'] = M [x, y, 1]."""
    k, cx, cy = input_transform(w, h, s)
    c = (s - 1) / 2.0
    return np.array([[k, 0.0, c - k * cx], [0.0, k, c - k * cy]])


def image_from_input(w, h, s):
    """2x3 inverse of input_from_image."""
    k, cx, cy = input_transform(w, h, s)
    c = (s - 1) / 2.0
    return np.array([[1 / k, 0.0, cx - c / k], [0.0, 1 / k, cy - c / k]])


def bilinear_border0(src, xs, ys):
    """Samples src [H, W, C] at float coordinates xs [W'], ys [H'] (separable grid):
    out [H', W', C]; neighbours outside src count as 0."""
    h, w = src.shape[:2]

    def taps(coords, n):
        i0 = np.floor(coords).astype(np.int64)
        f = coords - i0
        w0 = np.where((i0 >= 0) & (i0 < n), 1.0 - f, 0.0)
        w1 = np.where((i0 + 1 >= 0) & (i0 + 1 < n), f, 0.0)
        return np.clip(i0, 0, n - 1), w0, np.clip(i0 + 1, 0, n - 1), w1

    c0, wx0, c1, wx1 = taps(xs, w)
    r0, wy0, r1, wy1 = taps(ys, h)
    src = src.astype(np.float64)
    top = src[r0][:, c0] * wx0[None, :, None] + src[r0][:, c1] * wx1[None, :, None]
    bot = src[r1][:, c0] * wx0[None, :, None] + src[r1][:, c1] * wx1[None, :, None]
    return top * wy0[:, None, None] + bot * wy1[:, None, None]


def warp_to_input_unrounded(rgb, s):
    """rgb uint8 [h, w, 3] -> float64 [s, s, 3] in [0, 255], RGB, the bilinear samples
    before SCHP's rounding to whole grey levels."""
    h, w = rgb.shape[:2]
    k, cx, cy = input_transform(w, h, s)
    c = (s - 1) / 2.0
    grid = np.arange(s, dtype=np.float64)
    return bilinear_border0(rgb, (grid - c) / k + cx, (grid - c) / k + cy)


def warp_to_input(rgb, s):
    """rgb uint8 [h, w, 3] -> float64 [s, s, 3] of whole grey levels 0..255 (rounded, ties to
    even, as SCHP's uint8 warp), RGB, not normalised."""
    return np.rint(warp_to_input_unrounded(rgb, s))


def warp_labels_to_input(labels, s, fill=255):
    """Class ids [h, w] -> [s, s] by nearest neighbour (training targets); outside = fill."""
    h, w = labels.shape
    k, cx, cy = input_transform(w, h, s)
    c = (s - 1) / 2.0
    grid = np.arange(s, dtype=np.float64)
    xs = np.rint((grid - c) / k + cx).astype(np.int64)
    ys = np.rint((grid - c) / k + cy).astype(np.int64)
    out = np.full((s, s), fill, dtype=np.uint8)
    okx, oky = (xs >= 0) & (xs < w), (ys >= 0) & (ys < h)
    out[np.ix_(oky, okx)] = labels[np.ix_(ys[oky], xs[okx])]
    return out


def normalize_chw(samples_rgb, channel_order, mean, std):
    """[s, s, 3] RGB samples -> [3, s, s] float32 network input."""
    x = samples_rgb[..., ::-1] if channel_order == "BGR" else samples_rgb
    x = (x / 255.0 - np.asarray(mean)) / np.asarray(std)
    return np.ascontiguousarray(x.transpose(2, 0, 1)).astype(np.float32)


def resize_coords(n_in, n_out, align_corners):
    """PyTorch bilinear interpolate source coordinates of an axis."""
    i = np.arange(n_out, dtype=np.float64)
    if align_corners:
        return i * (n_in - 1) / (n_out - 1) if n_out > 1 else np.zeros(n_out)
    return np.maximum((i + 0.5) * n_in / n_out - 0.5, 0.0)


def upsample_logits(logits, s, align_corners):
    """[7, h, w] -> [s, s, 7] (bilinear, clamped at the edges as PyTorch)."""
    c, h, w = logits.shape
    src = logits.transpose(1, 2, 0).astype(np.float64)

    def taps(coords, n):
        i0 = np.minimum(np.floor(coords).astype(np.int64), n - 1)
        return i0, np.minimum(i0 + 1, n - 1), coords - i0

    r0, r1, fy = taps(resize_coords(h, s, align_corners), h)
    c0, c1, fx = taps(resize_coords(w, s, align_corners), w)
    top = src[r0][:, c0] * (1 - fx)[None, :, None] + src[r0][:, c1] * fx[None, :, None]
    bot = src[r1][:, c0] * (1 - fx)[None, :, None] + src[r1][:, c1] * fx[None, :, None]
    return top * (1 - fy)[:, None, None] + bot * fy[:, None, None]


def warp_back(logits_up, w, h):
    """[s, s, 7] upsampled logits -> [h, w, 7] at the image's size (inverse transform,
    bilinear, border 0)."""
    s = logits_up.shape[0]
    k, cx, cy = input_transform(w, h, s)
    c = (s - 1) / 2.0
    xs = (np.arange(w, dtype=np.float64) - cx) * k + c
    ys = (np.arange(h, dtype=np.float64) - cy) * k + c
    return bilinear_border0(logits_up, xs, ys)


def classify(logits_hw7):
    """Softmax + argmax: (class ids [h, w], probability of the winner [h, w])."""
    z = logits_hw7 - logits_hw7.max(axis=-1, keepdims=True)
    e = np.exp(z)
    p = e / e.sum(axis=-1, keepdims=True)
    ids = p.argmax(axis=-1)
    return ids.astype(np.uint8), np.take_along_axis(p, ids[..., None], -1)[..., 0]


def postprocess(logits, w, h, s, align_corners):
    """Network logits [7, h', w'] for input side s -> (class ids [h, w], winner
    probability [h, w]) at the image's size."""
    return classify(warp_back(upsample_logits(logits, s, align_corners), w, h))
