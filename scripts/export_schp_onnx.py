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
- Adaptive average poolings (SCHP's PSP module) are rewritten as two matrix products,
  checked equal; the exporter refuses those whose output size does not divide the input.
- The exported graph takes one fixed-size input [N,3,512,512] float32 (BGR, normalised with
  SCHP's mean/std, N dynamic) and returns the fusion head's logits [N,7,128,128]; opset 17,
  IR version 8 (ONNX Runtime >= 1.14 reads it).
- The sidecar (same path, .json): input_size, channel_order BGR, mean, std, class names,
  output_stride 4, align_corners true.
- The export is checked with onnxruntime against PyTorch on a random input.
"""

import argparse
import importlib
import json
import sys
import tempfile
import types
from pathlib import Path

SCHP_MEAN_BGR = [0.406, 0.456, 0.485]
SCHP_STD_BGR = [0.225, 0.224, 0.229]
CLASS_NAMES = ["background", "head", "torso", "upper_arms", "lower_arms", "upper_legs", "lower_legs"]
ABN_EPS = 1e-5


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


def exportable_adaptive_pools(net):
    """Replaces each nn.AdaptiveAvgPool2d by the same pooling written as two matrix products
    (the row and column averaging matrices of PyTorch's adaptive windows: start floor(i n /
    out), end ceil((i + 1) n / out)). The ONNX exporter refuses an adaptive pooling whose
    output size does not divide the input size, which SCHP's PSP module has (bins 3 and 6 of
    a 64x64 map for a 512 input). Returns the number replaced."""
    import math

    import torch
    import torch.nn as nn

    class MatrixAdaptiveAvgPool2d(nn.Module):
        def __init__(self, output_size):
            super().__init__()
            o = output_size if isinstance(output_size, (tuple, list)) else (output_size, output_size)
            self.out_h, self.out_w = int(o[0]), int(o[1])

        @staticmethod
        def averaging(n_in, n_out, like):
            m = torch.zeros(n_out, n_in, dtype=like.dtype)
            for i in range(n_out):
                a, b = (i * n_in) // n_out, math.ceil((i + 1) * n_in / n_out)
                m[i, a:b] = 1.0 / (b - a)
            return m

        def forward(self, x):
            h, w = int(x.shape[-2]), int(x.shape[-1])
            ph = self.averaging(h, self.out_h, x)
            pw = self.averaging(w, self.out_w, x)
            return torch.matmul(torch.matmul(ph, x), pw.t())

    count = 0
    for name, mod in list(net.named_modules()):
        for child_name, child in list(mod.named_children()):
            if isinstance(child, nn.AdaptiveAvgPool2d):
                setattr(mod, child_name, MatrixAdaptiveAvgPool2d(child.output_size))
                count += 1
    return count


def stand_in_network(num_classes):
    """A tiny SCHP-shaped network (conv + InPlaceABNSync blocks, output at 1/4, returning
    [[parsing, fusion], [edge]]) for --dry-run."""
    import torch.nn as nn
    from modules import InPlaceABNSync

    class StandIn(nn.Module):
        def __init__(self):
            super().__init__()
            self.conv1 = nn.Conv2d(3, 8, 3, 2, 1, bias=False)
            self.bn1 = InPlaceABNSync(8)
            self.conv2 = nn.Conv2d(8, 8, 3, 2, 1, bias=False)
            self.bn2 = InPlaceABNSync(8, activation="none")
            self.head = nn.Conv2d(8, num_classes, 1)
            self.edge = nn.Conv2d(8, 2, 1)

        def forward(self, x):
            x = self.bn2(self.conv2(self.bn1(self.conv1(x))))
            return [[self.head(x), self.head(x) * 2.0], [self.edge(x)]]

    return StandIn()


def export(net, out, input_size, num_classes, opset, description):
    import numpy as np
    import onnx
    import onnxruntime as ort
    import torch

    model = FusionOnly.wrap(net).eval()
    with torch.no_grad():
        x_check = torch.randn(2, 3, input_size, input_size, generator=torch.Generator().manual_seed(0))
        ref = model(x_check).numpy()
        for mod in model.modules():
            if hasattr(mod, "fold"):
                mod.fold()
        folded = model(x_check).numpy()
    if np.abs(ref - folded).max() > 1e-4:
        sys.exit("folding |w| + eps into the BatchNorm weights changed the output")
    if exportable_adaptive_pools(model):
        with torch.no_grad():
            pooled = model(x_check).numpy()
        if np.abs(ref - pooled).max() > 1e-4:
            sys.exit("the matrix form of the adaptive poolings changed the output")
    dummy = torch.zeros(1, 3, input_size, input_size)
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_suffix(".tmp.onnx")
    with torch.no_grad():
        torch.onnx.export(model, dummy, str(tmp), input_names=["image"], output_names=["logits"],
                          dynamic_axes={"image": {0: "batch"}, "logits": {0: "batch"}},
                          opset_version=opset, do_constant_folding=True, dynamo=False)
    m = onnx.load(str(tmp))
    m.ir_version = min(m.ir_version, 8)
    onnx.checker.check_model(m)
    onnx.save(m, str(tmp))
    tmp.replace(out)

    shape = [d.dim_value for d in m.graph.output[0].type.tensor_type.shape.dim]
    if shape[1] != num_classes:
        sys.exit(f"{out}: output has {shape[1]} channels, expected {num_classes}")
    stride = input_size // shape[2] if shape[2] else 4
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
    out.with_suffix(".json").write_text(json.dumps(sidecar, indent=2) + "\n")

    sess = ort.InferenceSession(str(out), providers=["CPUExecutionProvider"])
    got = sess.run(None, {"image": x_check.numpy()})[0]
    diff = float(np.abs(ref - got).max())
    ops = sorted({n.op_type for n in m.graph.node})
    print(f"{out}: input [N,3,{input_size},{input_size}], logits {['N'] + shape[1:]}, "
          f"opset {opset}, IR {m.ir_version}; onnxruntime vs torch max abs diff {diff:.2e}; ops {ops}")
    if diff > 1e-3:
        sys.exit(f"{out}: onnxruntime and PyTorch disagree by {diff}")
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
