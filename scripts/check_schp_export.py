#!/usr/bin/env python3
"""End-to-end check of the SCHP export on the real network (issue 29, part 5): SCHP's own
pipeline against `bodyseg parse` with the exported model, label by label.

    pip install torch onnx onnxruntime opencv-python-headless numpy
    git clone <the SCHP repository> schp
    python3 scripts/check_schp_export.py --schp-repo schp --bodyseg target/release/bodyseg \\
        --images photo1.jpg photo2.jpg --work /tmp/schp_check

What it does, in --work:
1. Builds SCHP's real network, `networks.init_model('resnet101', num_classes=7,
   pretrained=None)` (ResNet-101 AugmentCE2P; InPlaceABNSync replaced by the export
   script's pure-PyTorch ABN), with seeded random weights made *smooth* (below), and saves
   them in SCHP's released checkpoint format: {'state_dict': OrderedDict('module.' + name:
   tensor)}, which SCHP's simple_extractor.py loads by stripping `module.`.
2. Exports it with scripts/export_schp_onnx.py, unchanged, as a user would.
3. For every image (the photographs given, and the 960x540 views of a `bodyseg synth`
   frame): SCHP's own pipeline — its SimpleFolderDataset pre-processing (get_affine_transform,
   cv2.warpAffine to a uint8 512x512 image, ToTensor + Normalize in BGR), the network in
   PyTorch, Upsample(align_corners=True), its transform_logits (cv2.warpAffine of each logit
   channel back to the image) and argmax — against `bodyseg parse --model <exported>.onnx`
   on a recording holding the same pixels (PNG, so both sides decode the same bytes).
4. Prints per image the share of pixels with the same label, the noise floor (SCHP's
   pipeline against itself with the warped uint8 image changed by +-1 grey level at random:
   how far float-level differences alone move the labels of this network) and the check's
   power (SCHP's logits post-processed with align_corners=False, a plausible bug, against
   SCHP's labels: this must fall below the bar).

Passes (exit 0) when every image agrees on >= 99.9 % of its pixels.

The smooth network: random logits of a deep network flip with any float difference, which
would measure float noise, not the pipelines. So (seeded) every convolution kernel is a box
filter (its k x k taps equal: a low-pass) times a He-normal channel-mixing weight scaled by
0.8 (a gain below 1: the network damps input perturbations), the ABNs keep their identity
statistics, and the fusion head is calibrated on the check images at half resolution: each
class's logits centred and scaled to the same spread, all to about +-30 (otherwise one class
wins everywhere). The logits then vary over several input pixels and their argmax has wide
margins except on thin boundaries, which the noise floor (step 4) measures. Results:
docs/notes/2026-12-02-schp-export.md.
"""

import argparse
import copy
import importlib
import json
import shutil
import subprocess
import sys
import time
from collections import OrderedDict
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import export_schp_onnx as ex  # noqa: E402
import parsing_common as pc  # noqa: E402

INPUT_SIZE = [512, 512]
MIN_AGREEMENT = 0.999
# He-normal channel mixing times this gain: below 1 the deep network damps a perturbation
# of its input instead of amplifying it (at 0.8, +-1 grey level moves 0.02 % of the argmax
# of a 256x256 input; with every layer's statistics calibrated to unit variance instead it
# moved 20-45 %: float noise, not pipelines, would be measured).
CONV_GAIN = 0.8
# Each class's logits are centred and scaled to unit spread over the calibration images,
# then all to span about +-LOGIT_SPAN: a constant offset would make one class win everywhere.
LOGIT_SPAN = 30.0


def schp_modules(schp_repo):
    """SCHP's networks, dataset and transforms, with the pure-PyTorch ABN installed."""
    ex.install_abn()
    sys.path.insert(0, str(Path(schp_repo).resolve()))
    networks = importlib.import_module("networks")
    dataset = importlib.import_module("datasets.simple_extractor_dataset")
    transforms = importlib.import_module("utils.transforms")
    return networks, dataset, transforms


def to_tensor_normalize(img_uint8_hwc):
    """torchvision's ToTensor() then Normalize(mean, std) as simple_extractor.py composes
    them, written out (torchvision is not needed): HWC uint8 -> CHW float32 / 255, then
    (x - mean) / std per channel, the image in OpenCV's BGR order."""
    import torch

    t = torch.from_numpy(np.ascontiguousarray(img_uint8_hwc.transpose(2, 0, 1))).float().div(255)
    mean = torch.tensor(ex.SCHP_MEAN_BGR, dtype=torch.float32)[:, None, None]
    std = torch.tensor(ex.SCHP_STD_BGR, dtype=torch.float32)[:, None, None]
    return (t - mean) / std


def schp_inputs(dataset_mod, folder, perturb_seed=None):
    """SCHP's SimpleFolderDataset over `folder` (one image): (input tensor [3,512,512], meta).
    With perturb_seed, the warped uint8 image gets +-1 grey level at random first."""

    def transform(img):
        if perturb_seed is not None:
            rng = np.random.default_rng(perturb_seed)
            img = np.clip(img.astype(np.int16) + rng.integers(-1, 2, img.shape), 0, 255).astype(np.uint8)
        return to_tensor_normalize(img)

    ds = dataset_mod.SimpleFolderDataset(root=str(folder), input_size=INPUT_SIZE, transform=transform)
    assert len(ds) == 1, f"{folder}: expected one image"
    return ds[0]


def schp_labels(net, transforms_mod, image, meta):
    """simple_extractor.py's loop body for one image (on the CPU): (class ids [h, w], the
    network's logits [7, 128, 128])."""
    import torch

    with torch.no_grad():
        output = net(image[None])
        upsample = torch.nn.Upsample(size=INPUT_SIZE, mode="bilinear", align_corners=True)
        upsample_output = upsample(output[0][-1][0].unsqueeze(0)).squeeze().permute(1, 2, 0)
    logits = transforms_mod.transform_logits(upsample_output.numpy(), meta["center"], meta["scale"],
                                             meta["width"], meta["height"], input_size=INPUT_SIZE)
    return np.argmax(logits, axis=2).astype(np.uint8), output[0][-1][0].numpy()


def smooth_random_init(net, seed, calibration_batch):
    """Seeded smooth weights (see the module doc), in place."""
    import torch
    import torch.nn as nn

    g = torch.Generator().manual_seed(seed)
    for mod in net.modules():
        if isinstance(mod, nn.Conv2d):
            out_c, in_c, kh, kw = mod.weight.shape
            mix = torch.randn(out_c, in_c, 1, 1, generator=g) * CONV_GAIN * (2.0 / in_c) ** 0.5
            mod.weight.data = (mix / (kh * kw)).expand(-1, -1, kh, kw).contiguous()
            if mod.bias is not None:
                mod.bias.data.zero_()
    head = net.fushion[-1]  # SCHP's spelling: the fusion head's last 1x1 convolution
    with torch.no_grad():
        logits = net(calibration_batch)[0][-1]
        mean = logits.mean(dim=(0, 2, 3))
        std = logits.std(dim=(0, 2, 3))
        span = float(((logits - mean[:, None, None]) / std[:, None, None]).abs().max())
        k = LOGIT_SPAN / span
        head.weight.data *= (k / std)[:, None, None, None]
        head.bias.data = -mean / std * k


def write_png(path, rgb):
    import cv2

    path.parent.mkdir(parents=True, exist_ok=True)
    if not cv2.imwrite(str(path), np.ascontiguousarray(rgb[..., ::-1])):
        sys.exit(f"{path}: cannot write")


def read_labels(path):
    import cv2

    labels = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if labels is None:
        sys.exit(f"{path}: cannot read")
    return labels


def rig_toml(template_camera, names_sizes):
    """A rig.toml with one camera per (name, (w, h)): the template camera's depth sensor and
    extrinsics, a colour sensor of that size (intrinsics scaled, not used by parsing)."""
    text = []
    for name, (w, h) in names_sizes:
        cam = template_camera.replace('name = "cam0"', f'name = "{name}"')
        head, rest = cam.split("[camera.color]\n", 1)
        _, tail = rest.split("\n\n", 1)
        color = (f"[camera.color]\nwidth = {w}\nheight = {h}\nfx = {0.55 * w}\nfy = {0.55 * w}\n"
                 f"cx = {(w - 1) / 2}\ncy = {(h - 1) / 2}\ndistortion = [0.0, 0.0, 0.0, 0.0, 0.0]\n")
        text.append(head + color + "\n" + tail)
    return "".join(text)


def run(cmd, **kw):
    print("$ " + " ".join(str(c) for c in cmd), flush=True)
    return subprocess.run([str(c) for c in cmd], check=True, **kw)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--schp-repo", type=Path, required=True, help="checkout of the SCHP repository")
    ap.add_argument("--bodyseg", type=Path, nargs="+", required=True,
                    help="bodyseg binaries to compare (each must pass); the first also renders the synth frame")
    ap.add_argument("--images", type=Path, nargs="*", default=[], help="photographs (any size, any format OpenCV reads)")
    ap.add_argument("--synth-seed", type=int, default=3, help="seed of the `bodyseg synth --preset handover` frame (3 views)")
    ap.add_argument("--seed", type=int, default=0, help="seed of the random weights")
    ap.add_argument("--work", type=Path, required=True, help="scratch folder (created; ~600 MB)")
    ap.add_argument("--skip-export", action="store_true",
                    help="reuse the checkpoint, the export and SCHP's labels in --work")
    args = ap.parse_args(argv)

    import cv2
    import torch

    networks, dataset_mod, transforms_mod = schp_modules(args.schp_repo)
    work = args.work
    work.mkdir(parents=True, exist_ok=True)

    # The views: photographs decoded once and written as PNG; synth views as they are.
    synth = work / "synth"
    if not synth.exists():
        run([args.bodyseg[0], "-q", "synth", "--preset", "handover", "--frames", "1", "--seed", args.synth_seed,
             "--no-preview", "--out", synth])
    views = {}
    for i, path in enumerate(args.images):
        bgr = cv2.imread(str(path), cv2.IMREAD_COLOR)
        if bgr is None:
            sys.exit(f"{path}: cannot read as an image")
        views[f"photo{i}"] = (bgr[..., ::-1].copy(), path.name)
    for cam in sorted(p.name for p in synth.iterdir() if (p / "color" / "000000.png").exists()):
        bgr = cv2.imread(str(synth / cam / "color" / "000000.png"), cv2.IMREAD_COLOR)
        views[f"synth_{cam}"] = (bgr[..., ::-1].copy(), f"synth seed {args.synth_seed} {cam}")
    rec = work / "rec"
    shutil.rmtree(rec, ignore_errors=True)
    for name, (rgb, _) in views.items():
        write_png(rec / name / "color" / "000000.png", rgb)
        folder = work / "schp_in" / name
        shutil.rmtree(folder, ignore_errors=True)
        write_png(folder / "000000.png", rgb)
    template = (synth / "rig.toml").read_text()
    first = template[template.index("[[camera]]"):]
    first = first[:first.index("[[camera]]", 1)] if "[[camera]]" in first[1:] else first
    (rec / "rig.toml").write_text(rig_toml(first, [(n, (v[0].shape[1], v[0].shape[0])) for n, v in views.items()]))

    # 1-2. Smooth random weights in the released format, exported by the script unchanged.
    ckpt, onnx_path = work / "schp_random_smooth.pth", work / "schp_random_smooth.onnx"
    inputs = {name: schp_inputs(dataset_mod, work / "schp_in" / name) for name in views}
    if not args.skip_export:
        net = networks.init_model("resnet101", num_classes=7, pretrained=None).eval()
        t0 = time.time()
        batch = torch.stack([inp for inp, _ in inputs.values()])
        smooth_random_init(net, args.seed, torch.nn.functional.avg_pool2d(batch, 2))
        print(f"smooth init + calibration pass: {time.time() - t0:.0f} s")
        torch.save({"state_dict": OrderedDict(("module." + k, v) for k, v in net.state_dict().items())}, ckpt)
        run([sys.executable, HERE / "export_schp_onnx.py", "--schp-repo", args.schp_repo,
             "--checkpoint", ckpt, "--out", onnx_path])

    # 3. SCHP's own pipeline with the checkpoint loaded as simple_extractor.py does; its
    # labels are kept in --work (schp_labels.npz) for reruns with --skip-export.
    cache = work / "schp_labels.npz"
    if args.skip_export and cache.exists():
        stored = np.load(cache)
        schp = {name: {k: stored[f"{name}.{k}"] for k in ("labels", "noise", "buggy")} for name in views}
        f32_vs_f64 = json.loads(str(stored["float32_vs_float64"]))
    else:
        net = networks.init_model("resnet101", num_classes=7, pretrained=None)
        state_dict = torch.load(ckpt, map_location="cpu")["state_dict"]
        net.load_state_dict(OrderedDict((k[7:], v) for k, v in state_dict.items()))
        net.eval()
        # The export check's scale: float32 PyTorch against float64 on the same input.
        first_input = next(iter(inputs.values()))[0][None]
        with torch.no_grad():
            f32 = net(first_input)[0][-1].double()
            f64 = copy.deepcopy(net).double()(first_input.double())[0][-1]
        scale = float(f64.abs().max())
        diff = float((f32 - f64).abs().max())
        f32_vs_f64 = {"view": next(iter(views)), "max_abs_diff": diff, "max_abs_logit": scale,
                      "relative": diff / scale}
        schp = {}
        for name in views:
            image, meta = inputs[name]
            labels, raw = schp_labels(net, transforms_mod, image, meta)
            noise_in, noise_meta = schp_inputs(dataset_mod, work / "schp_in" / name, perturb_seed=1)
            noise, _ = schp_labels(net, transforms_mod, noise_in, noise_meta)
            # The check's power: the same logits post-processed with align_corners=False (a
            # plausible bug) must fall below the bar.
            h, w = labels.shape
            buggy, _ = pc.postprocess(raw, w, h, INPUT_SIZE[0], align_corners=False)
            schp[name] = {"labels": labels, "noise": noise, "buggy": buggy}
            print(f"SCHP pipeline: {name} done", flush=True)
        np.savez_compressed(cache, float32_vs_float64=json.dumps(f32_vs_f64),
                            **{f"{name}.{k}": v for name, d in schp.items() for k, v in d.items()})
    print(f"float32 vs float64 PyTorch on {f32_vs_f64['view']}: max |diff| {f32_vs_f64['max_abs_diff']:.2e}, "
          f"{f32_vs_f64['relative']:.2e} x max |logit| {f32_vs_f64['max_abs_logit']:.3g}", flush=True)

    # bodyseg parse with each binary given.
    got = {}
    for i, binary in enumerate(args.bodyseg):
        parsed = work / f"parsed{i}"
        shutil.rmtree(parsed, ignore_errors=True)
        run([binary, "parse", "--recording", rec, "--frame", "000000", "--model", onnx_path,
             "--threads", "2", "--out", parsed])
        got[str(binary)] = {name: read_labels(parsed / name / "parsing" / "000000.png") for name in views}

    results = []
    for name, (rgb, what) in views.items():
        want = schp[name]["labels"]
        row = {"view": name, "source": what, "size": [int(rgb.shape[1]), int(rgb.shape[0])],
               "noise_floor_agreement": float((schp[name]["noise"] == want).mean()),
               "align_corners_false_agreement": float((schp[name]["buggy"] == want).mean()),
               "schp_class_pixels": np.bincount(want.ravel(), minlength=7).tolist(), "bodyseg": {}}
        for binary, labels in got.items():
            assert labels[name].shape == want.shape, (binary, name, labels[name].shape, want.shape)
            row["bodyseg"][binary] = {"agreement": float((labels[name] == want).mean()),
                                      "differing_pixels": int((labels[name] != want).sum())}
        results.append(row)
        agree = "; ".join(f"{b}: {100 * r['agreement']:.4f} % ({r['differing_pixels']} px differ)"
                          for b, r in row["bodyseg"].items())
        print(f"{name} ({what}, {rgb.shape[1]}x{rgb.shape[0]}): bodyseg = SCHP on {agree}; "
              f"noise floor (SCHP, +-1 grey level) {100 * row['noise_floor_agreement']:.4f} %; "
              f"align_corners=False {100 * row['align_corners_false_agreement']:.2f} %; "
              f"SCHP's class pixels {row['schp_class_pixels']}", flush=True)
    (work / "agreement.json").write_text(json.dumps({"float32_vs_float64": f32_vs_f64, "views": results},
                                                    indent=2) + "\n")
    ok = True
    for binary in got:
        worst = min(r["bodyseg"][binary]["agreement"] for r in results)
        ok &= worst >= MIN_AGREEMENT
        print(f"{binary}: worst agreement {100 * worst:.4f} % (need >= {100 * MIN_AGREEMENT:g} %)")
    print(f"details: {work / 'agreement.json'}")
    if not ok:
        sys.exit(1)


if __name__ == "__main__":
    main()
