#!/usr/bin/env python3
"""Trains bodyseg's bundled 2D body-part parser on synthetic data and exports it to ONNX.

    pip install torch onnx onnxruntime numpy pillow
    cargo build --release --bin bodyseg
    python3 scripts/train_parser.py            # ~40 min on 2 CPU cores (36 min of training)

1. Renders training recordings with `bodyseg synth` (every preset, seeds 1..N, a few
   frames each at a low fps so the poses differ) and held-out recordings of other seeds
   (1000+), colour 960x540 with exact 2D truth (labels/, not the simulated predictions in
   parsing/).
2. Maps every image into the square network input with SCHP's affine pre-processing
   (scripts/parsing_common.py = crates/parsing/src/transform.rs) and trains a small
   encoder-decoder (CPU, torch.set_num_threads(2)) on random crops for a fixed time budget
   (--minutes; the step count then depends on the machine's load) or step count (--steps).
3. Exports ONNX in bodyseg's parsing contract (ALGORITHM.md §2: input [N,3,S,S] float32 RGB,
   logits [N,7,S/2,S/2], opset 17, IR version 8) with its sidecar JSON.
4. Evaluates the exported model with onnxruntime on the held-out frames at full colour
   resolution, with the same post-processing as the Rust code, and prints 2D IoU per class
   (also written to <out>.metrics.json).
"""

import argparse
import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import parsing_common as pc  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
PRESETS = ["single", "handover", "robot_cell"]
MEAN = [0.485, 0.456, 0.406]  # RGB, of pixels / 255
STD = [0.229, 0.224, 0.225]


def default_bodyseg():
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    return target / "release" / "bodyseg"


def synth(bodyseg, preset, seed, frames, fps, out):
    if out.exists():
        return
    cmd = [str(bodyseg), "--quiet", "synth", "--preset", preset, "--seed", str(seed),
           "--frames", str(frames), "--no-preview", "--set", f"fps={fps}", "--out", str(out)]
    subprocess.run(cmd, check=True)


def load_recording(rec):
    """[(rgb uint8 [h,w,3], labels uint8 [h,w])] of every camera and frame."""
    from PIL import Image

    items = []
    for cam in sorted(p for p in rec.iterdir() if (p / "color").is_dir()):
        for color in sorted((cam / "color").glob("*.png")):
            labels = cam / "labels" / color.name
            rgb = np.asarray(Image.open(color).convert("RGB"))
            lab = np.asarray(Image.open(labels))
            items.append((rgb, lab))
    return items


def make_recordings(args, seeds, frames, tag):
    recs = []
    for preset in PRESETS:
        for seed in seeds:
            out = args.work / f"{tag}_{preset}_{seed}"
            synth(args.bodyseg, preset, seed, frames, args.fps, out)
            recs.append(out)
    return recs


def build_model():
    import torch.nn as nn
    import torch.nn.functional as F

    def cbr(cin, cout, stride=1, dilation=1, kernel=3):
        pad = dilation * (kernel // 2)
        return nn.Sequential(
            nn.Conv2d(cin, cout, kernel, stride, padding=pad, dilation=dilation, bias=False),
            nn.BatchNorm2d(cout), nn.ReLU(inplace=True))

    class Parser(nn.Module):
        """Encoder-decoder (U-Net-like, 4 levels, 1x1 reductions before each decoder 3x3),
        logits at 1/2 of the input size."""

        def __init__(self):
            super().__init__()
            self.e1 = cbr(3, 16, 2)                                                   # /2
            self.e2 = nn.Sequential(cbr(16, 32, 2), cbr(32, 32))                      # /4
            self.e3 = nn.Sequential(cbr(32, 64, 2), cbr(64, 64))                      # /8
            self.e4 = nn.Sequential(cbr(64, 96, 2), cbr(96, 96, 1, 2), cbr(96, 96, 1, 4))  # /16
            self.d3 = nn.Sequential(cbr(96 + 64, 64, kernel=1), cbr(64, 64))
            self.d2 = nn.Sequential(cbr(64 + 32, 32, kernel=1), cbr(32, 32))
            self.d1 = nn.Sequential(cbr(32 + 16, 16, kernel=1), cbr(16, 16))
            self.head = nn.Conv2d(16, 7, 1)

        def forward(self, x):
            def up(t):
                return F.interpolate(t, scale_factor=2.0, mode="bilinear", align_corners=False)

            x1 = self.e1(x)
            x2 = self.e2(x1)
            x3 = self.e3(x2)
            x4 = self.e4(x3)
            y = self.d3(torch_cat(up(x4), x3))
            y = self.d2(torch_cat(up(y), x2))
            y = self.d1(torch_cat(up(y), x1))
            return self.head(y)

    return Parser()


def torch_cat(a, b):
    import torch

    return torch.cat([a, b], dim=1)


def iou_table(conf):
    tp = np.diag(conf).astype(np.float64)
    denom = conf.sum(0) + conf.sum(1) - tp
    return np.where(denom > 0, tp / np.maximum(denom, 1), np.nan)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--bodyseg", type=Path, default=default_bodyseg(), help="release bodyseg binary")
    ap.add_argument("--work", type=Path, default=Path("/tmp/bodyseg_parser_data"), help="synthetic recordings (cache)")
    ap.add_argument("--train-seeds", type=int, default=14, help="seeds 1..N per preset")
    ap.add_argument("--frames", type=int, default=4, help="frames per training recording")
    ap.add_argument("--val-seeds", type=int, default=2, help="held-out seeds 1001.. per preset")
    ap.add_argument("--fps", type=float, default=1.0, help="synth fps: low = more pose change between frames")
    ap.add_argument("--input-size", type=int, default=320, help="network input side S")
    ap.add_argument("--crop", type=int, default=192, help="training crop side")
    ap.add_argument("--batch", type=int, default=8)
    ap.add_argument("--minutes", type=float, default=36.0, help="training time budget")
    ap.add_argument("--steps", type=int, default=0,
                    help="train exactly this many steps instead of for --minutes (the bundled model: 750)")
    ap.add_argument("--lr", type=float, default=3e-3)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--init", type=Path, help="start from these weights (a <out>.pt of an earlier run) instead of random ones")
    ap.add_argument("--out", type=Path, default=ROOT / "models" / "bodyseg_parser_small.onnx")
    args = ap.parse_args()

    import torch
    import torch.nn.functional as F

    torch.set_num_threads(args.threads)
    torch.manual_seed(args.seed)
    rng = np.random.default_rng(args.seed)
    t_start = time.time()
    args.work.mkdir(parents=True, exist_ok=True)
    if not args.bodyseg.exists():
        sys.exit(f"{args.bodyseg}: no such binary: cargo build --release --bin bodyseg, or pass --bodyseg")

    # 1. data
    train_recs = make_recordings(args, range(1, args.train_seeds + 1), args.frames, "train")
    val_recs = make_recordings(args, range(1001, 1001 + args.val_seeds), 2, "val")
    t_data = time.time()
    print(f"synth: {len(train_recs)} training and {len(val_recs)} held-out recordings in {t_data - t_start:.0f} s", flush=True)

    s = args.input_size
    xs, ys = [], []
    counts = np.zeros(7, np.int64)
    for rec in train_recs:
        for rgb, lab in load_recording(rec):
            xs.append(np.clip(np.rint(pc.warp_to_input(rgb, s)), 0, 255).astype(np.uint8))
            y = pc.warp_labels_to_input(lab, s)
            ys.append(y)
            counts += np.bincount(y[y < 7].ravel(), minlength=7)
    x_all = np.stack(xs)
    y_all = np.stack(ys)
    # Where the image content lies in the input (rows/cols not padding), to centre crops.
    k, _, _ = pc.input_transform(960, 540, s)
    freq = counts / counts.sum()
    weights = np.sqrt(np.median(freq) / np.maximum(freq, 1e-6))
    weights = weights / weights.mean()
    print(f"train: {len(x_all)} images at {s}x{s}; class frequency {np.round(freq, 4).tolist()}; "
          f"loss weights {np.round(weights, 2).tolist()}", flush=True)

    # 2. training
    model = build_model()
    if args.init:
        model.load_state_dict(torch.load(args.init, map_location="cpu"))
        print(f"starting from {args.init}")
    n_params = sum(p.numel() for p in model.parameters())
    opt = torch.optim.AdamW(model.parameters(), lr=args.lr, weight_decay=1e-4)
    mean = torch.tensor(MEAN).view(1, 3, 1, 1)
    std = torch.tensor(STD).view(1, 3, 1, 1)
    wt = torch.tensor(weights, dtype=torch.float32)
    budget = args.minutes * 60
    t0 = time.time()
    step, losses = 0, []
    c = args.crop
    model.train()
    while (step < args.steps) if args.steps else (time.time() - t0 < budget):
        frac = step / args.steps if args.steps else (time.time() - t0) / budget
        for g in opt.param_groups:
            g["lr"] = args.lr * (0.02 + 0.98 * 0.5 * (1 + np.cos(np.pi * frac)))
        idx = rng.integers(0, len(x_all), args.batch)
        bx = np.empty((args.batch, c, c, 3), np.uint8)
        by = np.empty((args.batch, c, c), np.uint8)
        for j, i in enumerate(idx):
            # Crops mostly inside the content rows, sometimes reaching into the padding.
            oy = rng.integers(0, s - c + 1)
            ox = rng.integers(0, s - c + 1)
            bx[j] = x_all[i, oy:oy + c, ox:ox + c]
            by[j] = y_all[i, oy:oy + c, ox:ox + c]
            if rng.random() < 0.5:
                bx[j], by[j] = bx[j][:, ::-1], by[j][:, ::-1]
        x = torch.from_numpy(bx).permute(0, 3, 1, 2).float() / 255.0
        # Photometric jitter: brightness, contrast, per-channel gain.
        gain = torch.from_numpy(rng.uniform(0.7, 1.3, (args.batch, 1, 1, 1)).astype(np.float32))
        chan = torch.from_numpy(rng.uniform(0.9, 1.1, (args.batch, 3, 1, 1)).astype(np.float32))
        x = (x * gain * chan).clamp(0, 1)
        x = (x - mean) / std
        y = torch.from_numpy(by.astype(np.int64))
        logits = F.interpolate(model(x), size=(c, c), mode="bilinear", align_corners=False)
        loss = F.cross_entropy(logits, y, weight=wt, ignore_index=255)
        opt.zero_grad()
        loss.backward()
        opt.step()
        losses.append(loss.item())
        step += 1
        if step % 50 == 0:
            print(f"step {step}: loss {np.mean(losses[-50:]):.3f} ({time.time() - t0:.0f} s)", flush=True)
    t_train = time.time() - t0
    print(f"trained {step} steps of {args.batch} crops in {t_train / 60:.1f} min, {n_params} parameters", flush=True)

    # 3. export
    import onnx

    model.eval()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    # The PyTorch weights, to continue training with --init (not committed: the work folder).
    torch.save(model.state_dict(), args.work / (args.out.stem + ".pt"))
    dummy = torch.zeros(1, 3, s, s)
    tmp = args.out.with_suffix(".tmp.onnx")
    torch.onnx.export(model, dummy, str(tmp), input_names=["image"], output_names=["logits"],
                      dynamic_axes={"image": {0: "batch"}, "logits": {0: "batch"}},
                      opset_version=17, dynamo=False)
    m = onnx.load(str(tmp))
    m.ir_version = 8
    onnx.checker.check_model(m)
    onnx.save(m, str(tmp))
    os.replace(tmp, args.out)
    pc.write_sidecar(args.out.with_suffix(".json"), s, "RGB", MEAN, STD, False,
                     f"bodyseg_parser_small: trained by scripts/train_parser.py on bodyseg synth "
                     f"(presets {', '.join(PRESETS)}, seeds 1-{args.train_seeds}, {len(x_all)} images), "
                     f"{n_params} parameters, {step} steps")

    # 4. held-out evaluation through onnxruntime and the Rust-equivalent post-processing
    import onnxruntime as ort

    so = ort.SessionOptions()
    so.intra_op_num_threads = args.threads
    sess = ort.InferenceSession(str(args.out), so, providers=["CPUExecutionProvider"])
    with torch.no_grad():
        ref = model(torch.randn(1, 3, s, s, generator=torch.Generator().manual_seed(1))).numpy()
    got = sess.run(None, {"image": torch.randn(1, 3, s, s, generator=torch.Generator().manual_seed(1)).numpy()})[0]
    print(f"onnx vs torch max abs diff {np.abs(ref - got).max():.2e}")
    conf = np.zeros((7, 7), np.int64)
    n_val = 0
    for rec in val_recs:
        for rgb, lab in load_recording(rec):
            h, w = lab.shape
            x = pc.normalize_chw(pc.warp_to_input(rgb, s), "RGB", MEAN, STD)[None]
            logits = sess.run(None, {"image": x})[0][0]
            ids, _ = pc.postprocess(logits, w, h, s, False)
            valid = lab < 7
            conf += np.bincount(lab[valid].astype(np.int64) * 7 + ids[valid], minlength=49).reshape(7, 7)
            n_val += 1
    iou = iou_table(conf)
    miou = float(np.nanmean(iou))
    body = float(np.nanmean(iou[1:]))
    print(f"\nheld-out: {n_val} views (presets {', '.join(PRESETS)}, seeds 1001-{1000 + args.val_seeds}), 960x540")
    print("| class | IoU |\n|---|---|")
    for name, v in zip(pc.CLASS_NAMES, iou):
        print(f"| {name} | {v:.3f} |")
    print(f"| **mIoU (7 classes)** | **{miou:.3f}** |\n| mIoU (6 body parts) | {body:.3f} |")
    total = time.time() - t_start
    metrics = {"iou": dict(zip(pc.CLASS_NAMES, [float(v) for v in iou])), "miou": miou,
               "miou_body": body, "val_views": n_val, "train_images": int(len(x_all)),
               "steps": step, "train_minutes": t_train / 60, "total_minutes": total / 60,
               "parameters": int(n_params), "args": {k: str(v) for k, v in vars(args).items()}}
    args.out.with_suffix(".metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    print(f"\nwrote {args.out} ({args.out.stat().st_size / 1e6:.2f} MB) and its sidecar; total {total / 60:.1f} min")


if __name__ == "__main__":
    main()
