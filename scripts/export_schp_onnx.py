#!/usr/bin/env python3
"""Exports an SCHP checkpoint (Self-Correction-Human-Parsing, Li et al. 2020) to bodyseg's
2D parsing contract (shared/ALGORITHM.md §2) and writes its sidecar JSON.

    pip install torch onnx onnxruntime numpy
    git clone <the SCHP repository> schp      # the user's own checkout
    python3 scripts/export_schp_onnx.py --schp-repo schp \\
        --checkpoint exp-schp-201908270938-pascal-person-part.pth --out models/schp_ppp.onnx
    bodyseg parse --recording rec --frame 000000 --model models/schp_ppp.onnx --out parsed

    python3 scripts/export_schp_onnx.py --dry-run     # no SCHP needed: a tiny stand-in

What it does:
- SCHP's InPlaceABNSync (a CUDA extension) is replaced, before SCHP's code is imported, by
  a plain-PyTorch module: BatchNorm (running statistics, eval mode) with weight |w| + eps
  (eps = 1e-5, as the original kernels apply; a plain BatchNorm swap visibly degrades the
  output) followed by LeakyReLU(0.01) where the layer's activation is leaky_relu (none
  where it is "none", ELU where "elu").
- The checkpoint's `module.` prefix (DataParallel) is stripped; the state dict must then
  match the network exactly.
- Every nn.AdaptiveAvgPool2d (SCHP's PSP module pools the 32x32 map of a 512 input to 1,
  2, 3 and 6) becomes two matrix products A · X · Bᵀ with PyTorch's adaptive bins
  (start = floor(i·n/k), end = ceil((i+1)·n/k)), built for the traced input size: the
  legacy exporter has no adaptive pool whose output size does not divide the input.
- The exported graph takes one fixed-size input [N,3,512,512] float32 (BGR, normalised with
  SCHP's mean/std, N dynamic) and returns the fusion head's logits [N,7,128,128]; opset 17,
  IR version 8 (ONNX Runtime >= 1.14 reads it). The opset and IR version printed are read
  back from the written file.
- The sidecar (same path, .json): input_size, channel_order BGR, mean, std, class names,
  output_stride 4, align_corners true.
- The export is checked with onnxruntime against PyTorch on a random input, relative to the
  logits' size: max |diff| <= 1e-4 · max |logit| + 1e-3 and the same argmax on >= 99.99 %
  of the logit pixels (float32 PyTorch itself is up to ~2.3e-5 · max |logit| from float64
  on SCHP's network: docs/notes/2026-12-02-schp-export.md). On failure nothing is left at
  --out: the new files are removed, and so are older ones at that path, and the script
  exits 1.
"""

import argparse
import importlib
import json
import sys
import tempfile
import types
import warnings
from pathlib import Path

SCHP_MEAN_BGR = [0.406, 0.456, 0.485]
SCHP_STD_BGR = [0.225, 0.224, 0.229]
CLASS_NAMES = ["background", "head", "torso", "upper_arms", "lower_arms", "upper_legs", "lower_legs"]
ABN_EPS = 1e-5
# The export check (see `check_logits`): max |onnxruntime - PyTorch| <= CHECK_REL_TOL ·
# max |logit| + CHECK_ABS_TOL. float32 PyTorch is itself that far from float64: 7e-3 on
# logits of ~300 (2.3e-5 · max |logit|) with SCHP's released Pascal weights (issue 29),
# 4.5e-6 · max |logit| on the real network with smooth random weights, where onnxruntime is
# 1.8e-6 · max |logit| from PyTorch (docs/notes/2026-12-02-schp-export.md). 1e-4 leaves a
# margin of 4 over the worst of these; a wrong graph (a swapped channel, a missing layer)
# is off by the logits' own size. The absolute term covers logits near 0.
CHECK_REL_TOL = 1e-4
CHECK_ABS_TOL = 1e-3
# ... and the winning class agrees on at least this share of the logit pixels (a
# tie within the tolerance above may flip a few).
CHECK_MIN_ARGMAX_AGREEMENT = 0.9999


def abn_module():
    """A `modules` package with pure-PyTorch ABN / InPlaceABN / InPlaceABNSync."""
    import torch
    import torch.nn as nn
    import torch.nn.functional as F

    class ABN(nn.Module):
        """Activated BatchNorm as the inplace_abn kernels compute it in eval mode:
        y = act((x - mean) / sqrt(var + eps) * (|w| + eps) + b)."""

        def __init__(self, num_features, eps=ABN_EPS, momentum=0.1, affine=True,
                     activation="leaky_relu", slope=0.01, **_ignored):
            super().__init__()
            self.num_features, self.eps, self.momentum = num_features, eps, momentum
            self.affine, self.activation, self.slope = affine, activation, slope
            if affine:
                self.weight = nn.Parameter(torch.ones(num_features))
                self.bias = nn.Parameter(torch.zeros(num_features))
            else:
                self.register_parameter("weight", None)
                self.register_parameter("bias", None)
            self.register_buffer("running_mean", torch.zeros(num_features))
            self.register_buffer("running_var", torch.ones(num_features))

        folded = False

        def fold(self):
            """Stores |w| + eps as the weight, so the export is a plain BatchNormalization."""
            if self.affine and not self.folded:
                self.weight.data = self.weight.data.abs() + self.eps
            self.folded = True

        def forward(self, x):
            weight = self.weight if (self.folded or not self.affine) else self.weight.abs() + self.eps
            x = F.batch_norm(x, self.running_mean, self.running_var, weight, self.bias,
                             False, self.momentum, self.eps)
            if self.activation == "leaky_relu":
                return F.leaky_relu(x, self.slope)
            if self.activation == "elu":
                return F.elu(x)
            if self.activation in ("none", "identity", None):
                return x
            raise ValueError(f"unknown ABN activation {self.activation!r}")

    module = types.ModuleType("modules")
    module.ABN = ABN
    module.InPlaceABN = ABN
    module.InPlaceABNSync = ABN
    module.__path__ = []  # a package: `from modules.bn import ...` finds the same classes
    bn = types.ModuleType("modules.bn")
    bn.ABN, bn.InPlaceABN, bn.InPlaceABNSync = ABN, ABN, ABN
    return module, bn


def install_abn():
    module, bn = abn_module()
    sys.modules["modules"] = module
    sys.modules["modules.bn"] = bn
    return module


def adaptive_bins(n_in, n_out):
    """PyTorch's adaptive pooling bins of an axis: [(start, end)] with start = floor(i·n_in/n_out)
    and end = ceil((i+1)·n_in/n_out) (aten/src/ATen/native/AdaptiveAveragePooling.cpp)."""
    return [((i * n_in) // n_out, -(-((i + 1) * n_in) // n_out)) for i in range(n_out)]


def averaging_matrix(n_in, n_out):
    """[n_out, n_in] float64: row i averages the inputs of bin i."""
    import numpy as np

    m = np.zeros((n_out, n_in))
    for i, (start, end) in enumerate(adaptive_bins(n_in, n_out)):
        m[i, start:end] = 1.0 / (end - start)
    return m


def matrix_adaptive_avg_pool2d(output_size):
    """An nn.Module equal to nn.AdaptiveAvgPool2d(output_size) that exports to ONNX for any
    input size: y = A · x · Bᵀ over the last two axes, A and B the averaging matrices of
    the rows and columns for the size of the input it is called on (constants in a traced
    graph, so the exported model keeps the traced input size)."""
    import torch
    import torch.nn as nn

    class MatrixAdaptiveAvgPool2d(nn.Module):
        def __init__(self, output_size):
            super().__init__()
            size = (output_size, output_size) if isinstance(output_size, int) else tuple(output_size)
            self.output_size = size

        def forward(self, x):
            h, w = int(x.shape[-2]), int(x.shape[-1])
            oh = h if self.output_size[0] is None else self.output_size[0]
            ow = w if self.output_size[1] is None else self.output_size[1]
            a = torch.tensor(averaging_matrix(h, oh), dtype=x.dtype)
            b_t = torch.tensor(averaging_matrix(w, ow).T, dtype=x.dtype)
            return torch.matmul(torch.matmul(a, x), b_t)

        def extra_repr(self):
            return f"output_size={self.output_size}"

    return MatrixAdaptiveAvgPool2d(output_size)


def replace_adaptive_pools(net):
    """Replaces every nn.AdaptiveAvgPool2d inside `net` by `matrix_adaptive_avg_pool2d`;
    returns how many."""
    import torch.nn as nn

    found = [(name, mod) for name, mod in net.named_modules() if isinstance(mod, nn.AdaptiveAvgPool2d)]
    for name, mod in found:
        parent_name, _, child = name.rpartition(".")
        parent = net.get_submodule(parent_name) if parent_name else net
        setattr(parent, child, matrix_adaptive_avg_pool2d(mod.output_size))
    return len(found)


def check_logits(ref, got):
    """Compares onnxruntime's logits `got` with PyTorch's `ref` ([N,C,h,w]) relative to the
    logits' size: (ok, message)."""
    import numpy as np

    scale = float(np.abs(ref).max())
    diff = float(np.abs(ref - got).max())
    tol = CHECK_REL_TOL * scale + CHECK_ABS_TOL
    agree = float((ref.argmax(axis=1) == got.argmax(axis=1)).mean())
    ok = bool(diff <= tol and agree >= CHECK_MIN_ARGMAX_AGREEMENT)
    msg = (f"max |diff| {diff:.2e} (tolerance {tol:.2e} = {CHECK_REL_TOL:g} x max |logit| {scale:.3g} "
           f"+ {CHECK_ABS_TOL:g}), argmax agreement {100 * agree:.4f} % "
           f"(>= {100 * CHECK_MIN_ARGMAX_AGREEMENT:g} %)")
    return ok, msg


def onnx_opset(model):
    """The default-domain opset the model imports (read back from the file)."""
    return next(o.version for o in model.opset_import if o.domain in ("", "ai.onnx"))


def strip_prefix(state_dict, prefix="module."):
    return {(k[len(prefix):] if k.startswith(prefix) else k): v for k, v in state_dict.items()}


class FusionOnly:
    """Wraps SCHP's output [[parsing, fusion], [edge]] to the fusion logits."""

    @staticmethod
    def wrap(net):
        import torch.nn as nn

        class Wrapped(nn.Module):
            def __init__(self, inner):
                super().__init__()
                self.inner = inner

            def forward(self, x):
                out = self.inner(x)
                return out[0][-1] if isinstance(out, (list, tuple)) else out

        return Wrapped(net)


def stand_in_network(num_classes):
    """A tiny SCHP-shaped network for --dry-run: conv + InPlaceABNSync blocks, output at 1/4,
    a PSP-like branch (an adaptive average pool to 3x3, which does not divide the 16x16 map
    of a 64x64 input, upsampled back with align_corners), returning
    [[parsing, fusion], [edge]]."""
    import torch.nn as nn
    import torch.nn.functional as F
    from modules import InPlaceABNSync

    class StandIn(nn.Module):
        def __init__(self):
            super().__init__()
            self.conv1 = nn.Conv2d(3, 8, 3, 2, 1, bias=False)
            self.bn1 = InPlaceABNSync(8)
            self.conv2 = nn.Conv2d(8, 8, 3, 2, 1, bias=False)
            self.bn2 = InPlaceABNSync(8, activation="none")
            self.prior = nn.Sequential(nn.AdaptiveAvgPool2d(3), nn.Conv2d(8, 8, 1, bias=False))
            self.head = nn.Conv2d(8, num_classes, 1)
            self.edge = nn.Conv2d(8, 2, 1)

        def forward(self, x):
            x = self.bn2(self.conv2(self.bn1(self.conv1(x))))
            h, w = x.size(2), x.size(3)
            x = x + F.interpolate(self.prior(x), size=(h, w), mode="bilinear", align_corners=True)
            return [[self.head(x), self.head(x) * 2.0], [self.edge(x)]]

    return StandIn()


class ExportCheckFailed(Exception):
    """The exported model failed a check; its outputs are removed."""


def remove_outputs(*paths):
    for path in paths:
        Path(path).unlink(missing_ok=True)


def export(net, out, input_size, num_classes, opset, description):
    """Exports `net` (SCHP's output layout) to `out` (ONNX) and its sidecar `out`.json, checked
    against PyTorch with onnxruntime; returns the written onnx.ModelProto. Exits with an
    error, leaving nothing at `out` or its sidecar, when a check fails."""
    import onnx
    import onnxruntime as ort
    import torch

    replaced = replace_adaptive_pools(net)
    model = FusionOnly.wrap(net).eval()
    with torch.no_grad():
        x_check = torch.randn(2, 3, input_size, input_size, generator=torch.Generator().manual_seed(0))
        ref = model(x_check).numpy()
        for mod in model.modules():
            if hasattr(mod, "fold"):
                mod.fold()
        folded = model(x_check).numpy()
    ok, msg = check_logits(ref, folded)
    if not ok:
        sys.exit(f"folding |w| + eps into the BatchNorm weights changed the output: {msg}")
    sidecar_path = out.with_suffix(".json")
    tmp, tmp_sidecar = out.with_suffix(".tmp.onnx"), out.with_suffix(".tmp.json")
    out.parent.mkdir(parents=True, exist_ok=True)
    try:
        dummy = torch.zeros(1, 3, input_size, input_size)
        with torch.no_grad(), warnings.catch_warnings():
            # The pools read the traced input's size as Python ints on purpose: the exported
            # model has a fixed input size, so their matrices are constants.
            warnings.simplefilter("ignore", torch.jit.TracerWarning)
            torch.onnx.export(model, dummy, str(tmp), input_names=["image"], output_names=["logits"],
                              dynamic_axes={"image": {0: "batch"}, "logits": {0: "batch"}},
                              opset_version=opset, do_constant_folding=True, dynamo=False)
        m = onnx.load(str(tmp))
        m.ir_version = min(m.ir_version, 8)
        onnx.checker.check_model(m)
        onnx.save(m, str(tmp))

        sess = ort.InferenceSession(str(tmp), providers=["CPUExecutionProvider"])
        got = sess.run(None, {"image": x_check.numpy()})[0]
        ok, msg = check_logits(ref, got) if got.shape == ref.shape else (
            False, f"logits {list(got.shape)}, PyTorch gives {list(ref.shape)}")
        # SCHP sizes its upsampling from tensor shapes, so the exporter leaves the output's
        # spatial dims symbolic; the input size is fixed, so write the real ones.
        shape = list(got.shape)
        for dim, value in zip(list(m.graph.output[0].type.tensor_type.shape.dim)[1:], shape[1:]):
            dim.dim_value = value
        onnx.checker.check_model(m)
        onnx.save(m, str(tmp))
        if shape[1] != num_classes:
            raise ExportCheckFailed(f"output has {shape[1]} channels, expected {num_classes}")
        stride = input_size // shape[2]
        sidecar = {
            "input_size": [input_size, input_size],
            "channel_order": "BGR",
            "mean": SCHP_MEAN_BGR,
            "std": SCHP_STD_BGR,
            "class_names": CLASS_NAMES,
            "output_stride": stride,
            "align_corners": True,
            "description": description,
        }
        tmp_sidecar.write_text(json.dumps(sidecar, indent=2) + "\n")
        ops = sorted({n.op_type for n in m.graph.node})
        print(f"{out}: input [N,3,{input_size},{input_size}], logits {['N'] + shape[1:]}, "
              f"opset {onnx_opset(m)}, IR {m.ir_version}; {replaced} adaptive pools as matrix products; "
              f"onnxruntime vs torch: {msg}; ops {ops}")
        if not ok:
            raise ExportCheckFailed(f"onnxruntime and PyTorch disagree: {msg}")
    except ExportCheckFailed as e:
        remove_outputs(tmp, tmp_sidecar, out, sidecar_path)
        sys.exit(f"{out}: {e}; removed {out} and {sidecar_path}")
    except BaseException:
        remove_outputs(tmp, tmp_sidecar)
        raise
    tmp.replace(out)
    tmp_sidecar.replace(sidecar_path)
    return m


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--schp-repo", type=Path, help="checkout of the SCHP repository (holds networks/)")
    ap.add_argument("--checkpoint", type=Path, help="SCHP checkpoint (.pth), e.g. exp-schp-201908270938-pascal-person-part.pth")
    ap.add_argument("--arch", default="resnet101", help="SCHP backbone name (networks.init_model)")
    ap.add_argument("--out", type=Path, help="ONNX file to write (sidecar: same path, .json)")
    ap.add_argument("--input-size", type=int, default=512, help="fixed square input side (SCHP Pascal: 512)")
    ap.add_argument("--num-classes", type=int, default=7, help="classes of the checkpoint (Pascal-Person-Part: 7)")
    ap.add_argument("--opset", type=int, default=17, help="ONNX opset (>= 11)")
    ap.add_argument("--dry-run", action="store_true", help="export a tiny stand-in network instead (no SCHP needed)")
    args = ap.parse_args(argv)
    if args.opset < 11:
        ap.error("--opset must be >= 11")
    if args.num_classes != 7:
        ap.error("bodyseg's contract has 7 classes (Pascal-Person-Part); --num-classes must be 7")
    if not args.dry_run and (args.schp_repo is None or args.checkpoint is None or args.out is None):
        ap.error("--schp-repo, --checkpoint and --out are required (or --dry-run)")

    import torch

    install_abn()
    if args.dry_run:
        net = stand_in_network(args.num_classes)
        # Non-trivial BN statistics and negative weights, so |w| + eps matters.
        g = torch.Generator().manual_seed(0)
        for mod in net.modules():
            if hasattr(mod, "running_var"):
                mod.weight.data = torch.randn(mod.num_features, generator=g)
                mod.running_mean.data = torch.randn(mod.num_features, generator=g) * 0.1
                mod.running_var.data = torch.rand(mod.num_features, generator=g) + 0.5
        with tempfile.TemporaryDirectory() as tmp:
            ckpt = Path(tmp) / "standin.pth"
            torch.save({"state_dict": {"module." + k: v for k, v in net.state_dict().items()}}, ckpt)
            fresh = stand_in_network(args.num_classes)
            fresh.load_state_dict(strip_prefix(torch.load(ckpt, map_location="cpu")["state_dict"]), strict=True)
            out = args.out or Path(tmp) / "standin.onnx"
            m = export(fresh, out, 64 if args.input_size == 512 else args.input_size, args.num_classes,
                       args.opset, "dry run: stand-in network")
            ops = {n.op_type for n in m.graph.node}
            # BatchNorm is fused into the convolutions by the exporter; no |w| op is left.
            assert "LeakyRelu" in ops and "Abs" not in ops, ops
            print("dry run ok")
        return

    sys.path.insert(0, str(args.schp_repo.resolve()))
    networks = importlib.import_module("networks")
    net = networks.init_model(args.arch, num_classes=args.num_classes, pretrained=None)
    state = torch.load(args.checkpoint, map_location="cpu")
    state = state.get("state_dict", state)
    net.load_state_dict(strip_prefix(state), strict=True)
    export(net, args.out, args.input_size, args.num_classes, args.opset,
           f"SCHP {args.arch} from {args.checkpoint.name}, exported by scripts/export_schp_onnx.py")


if __name__ == "__main__":
    main()
