#!/usr/bin/env python3
"""Unit tests of scripts/export_schp_onnx.py (fast, no SCHP checkout needed):

    pip install torch onnx onnxruntime numpy
    python3 scripts/test_export_schp.py          # or: pytest scripts/test_export_schp.py

- the adaptive average pools written as matrix products equal PyTorch's
  F.adaptive_avg_pool2d (SCHP's PSP sizes 1, 2, 3, 6 on a 32x32 map, and odd cases);
- they replace nested nn.AdaptiveAvgPool2d modules and export to ONNX, where onnxruntime
  gives the same values;
- the export check is relative to the logits' size: float32-level differences on logits
  of ~300 pass, a wrong graph fails;
- a failed check leaves nothing at --out (nor its sidecar, nor temporaries) and exits
  non-zero; a dry run writes both, with the opset and IR version read back.

The end-to-end check on SCHP's real network is scripts/check_schp_export.py (slow).
"""

import contextlib
import io
import json
import sys
import tempfile
import traceback
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import export_schp_onnx as ex  # noqa: E402

# (input h, input w, output size): SCHP's PSP module on the 32x32 map of a 512 input, then
# non-square maps, sizes that do not divide, an output larger than the input, and None
# (keep that axis).
POOL_CASES = [(32, 32, 1), (32, 32, 2), (32, 32, 3), (32, 32, 6), (32, 24, (3, 6)), (17, 23, 5),
              (33, 32, 6), (5, 5, 8), (12, 20, (None, 7))]


def rel_err(got, want):
    return float((got - want).abs().max() / want.abs().max())


def test_bins_are_pytorchs():
    # floor(i·n/k) .. ceil((i+1)·n/k): 32 -> 3 overlaps at the seams, as PyTorch does.
    assert ex.adaptive_bins(32, 3) == [(0, 11), (10, 22), (21, 32)]
    assert ex.adaptive_bins(32, 6) == [(0, 6), (5, 11), (10, 16), (16, 22), (21, 27), (26, 32)]
    assert ex.adaptive_bins(5, 8) == [(0, 1), (0, 2), (1, 2), (1, 3), (2, 4), (3, 4), (3, 5), (4, 5)]
    m = ex.averaging_matrix(32, 3)
    assert np.allclose(m.sum(axis=1), 1.0) and m.shape == (3, 32)


def test_matrix_pool_equals_adaptive_avg_pool2d():
    import torch
    import torch.nn.functional as F

    g = torch.Generator().manual_seed(1)
    for h, w, k in POOL_CASES:
        x64 = torch.randn(2, 16, h, w, generator=g, dtype=torch.float64) + 2.0
        pool = ex.matrix_adaptive_avg_pool2d(k)
        # float64: the same bins give the same numbers to rounding (~1e-16); one wrong
        # bin is off by ~1e-2.
        e64 = rel_err(pool(x64), F.adaptive_avg_pool2d(x64, k))
        assert e64 < 1e-12, (h, w, k, e64)
        # float32: against the exact (float64) pool of the same float32 input. Measured
        # <= 1.7e-7 relative for the PSP sizes; PyTorch's own float32 pool is up to 7.6e-7
        # off (another summation order), so the bound is 1e-6.
        x32 = x64.float()
        exact = F.adaptive_avg_pool2d(x32.double(), k)
        e32 = rel_err(pool(x32).double(), exact)
        assert e32 < 1e-6, (h, w, k, e32)


def test_replace_adaptive_pools_in_nested_modules():
    import torch
    import torch.nn as nn

    class Psp(nn.Module):
        def __init__(self):
            super().__init__()
            self.stages = nn.ModuleList([nn.Sequential(nn.AdaptiveAvgPool2d((s, s)), nn.Conv2d(4, 4, 1))
                                         for s in (1, 2, 3, 6)])
            self.top = nn.AdaptiveAvgPool2d(3)

        def forward(self, x):
            return [stage(x).sum() for stage in self.stages] + [self.top(x)]

    torch.manual_seed(0)
    net = Psp().eval()
    x = torch.randn(1, 4, 32, 32)
    with torch.no_grad():
        before = net(x)
        assert ex.replace_adaptive_pools(net) == 5
        after = net(x)
    assert not any(isinstance(m, nn.AdaptiveAvgPool2d) for m in net.modules())
    for b, a in zip(before, after):
        assert torch.allclose(b, a, rtol=1e-5, atol=1e-5), (b, a)


def test_pools_export_and_run_in_onnxruntime():
    import onnxruntime as ort
    import torch
    import torch.nn as nn
    import torch.nn.functional as F

    class Pools(nn.Module):
        def __init__(self):
            super().__init__()
            self.p3, self.p6 = nn.AdaptiveAvgPool2d(3), nn.AdaptiveAvgPool2d(6)

        def forward(self, x):
            return torch.cat([self.p3(x).flatten(1), self.p6(x).flatten(1)], dim=1)

    net = Pools().eval()
    assert ex.replace_adaptive_pools(net) == 2
    x = torch.randn(2, 8, 32, 32, generator=torch.Generator().manual_seed(2)) + 1.0
    want = torch.cat([F.adaptive_avg_pool2d(x, 3).flatten(1), F.adaptive_avg_pool2d(x, 6).flatten(1)], 1)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "pools.onnx"
        with torch.no_grad(), contextlib.redirect_stderr(io.StringIO()):
            torch.onnx.export(net, x, str(path), input_names=["x"], output_names=["y"],
                              dynamic_axes={"x": {0: "n"}, "y": {0: "n"}}, opset_version=17, dynamo=False)
        sess = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
        got = torch.from_numpy(sess.run(None, {"x": x.numpy()})[0])
    # float32 in both, other summation orders: see test_matrix_pool_equals_adaptive_avg_pool2d.
    assert rel_err(got, want) < 1e-6, rel_err(got, want)


def test_check_is_relative_to_the_logits_size():
    rng = np.random.default_rng(3)
    ref = (rng.normal(0, 100, (2, 7, 32, 32))).astype(np.float32)
    ref[:, 2] += 300.0  # logits of ~300, one class ahead by a wide margin
    # The float32-vs-float64 difference, 7e-3 on logits of ~300, passes...
    ok, msg = ex.check_logits(ref, ref + rng.uniform(-7e-3, 7e-3, ref.shape).astype(np.float32))
    assert ok, msg
    # ... while the same absolute difference on logits of ~1 does not (it would be 1 %).
    small = ref / 300.0
    ok, msg = ex.check_logits(small, small + 7e-3)
    assert not ok, msg
    # A wrong graph (two channels swapped) fails.
    ok, msg = ex.check_logits(ref, ref[:, [0, 1, 3, 2, 4, 5, 6]])
    assert not ok, msg
    # Within the tolerance but another winner on 1 % of the pixels fails too.
    tie = np.zeros((1, 7, 10, 10), np.float32)
    tie[0, 0] = 1e-4
    flipped = tie.copy()
    flipped[0, 1, 0, 0] = 2e-4
    ok, msg = ex.check_logits(tie, flipped)
    assert not ok and "argmax agreement 99.0000 %" in msg, msg


def dry_run_net():
    import torch

    ex.install_abn()
    net = ex.stand_in_network(7)
    g = torch.Generator().manual_seed(0)
    for mod in net.modules():
        if hasattr(mod, "running_var"):
            mod.weight.data = torch.randn(mod.num_features, generator=g)
    return net


def test_failed_check_removes_the_outputs():
    import onnxruntime as ort

    class OffByOne:
        """An InferenceSession whose logits are 1 off (a broken export)."""

        def __init__(self, *args, **kwargs):
            self.inner = real(*args, **kwargs)

        def run(self, *args, **kwargs):
            return [y + 1.0 for y in self.inner.run(*args, **kwargs)]

    real = ort.InferenceSession
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "models" / "schp.onnx"
        out.parent.mkdir()
        out.write_bytes(b"an older export")
        out.with_suffix(".json").write_text("{}")
        ort.InferenceSession = OffByOne
        try:
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
                ex.export(dry_run_net(), out, 64, 7, 17, "test")
            raise AssertionError("export passed its check on logits 1 off")
        except SystemExit as e:
            assert "disagree" in str(e.code), e.code
        finally:
            ort.InferenceSession = real
        left = sorted(p.name for p in out.parent.iterdir())
        assert left == [], left


def test_dry_run_writes_model_and_sidecar():
    import onnx

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "standin.onnx"
        stdout = io.StringIO()
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(io.StringIO()):
            ex.main(["--dry-run", "--out", str(out)])
        m = onnx.load(str(out))
        sidecar = json.loads(out.with_suffix(".json").read_text())
        assert sorted(p.name for p in out.parent.iterdir()) == ["standin.json", "standin.onnx"]
    # The exported file's own opset and IR version are what is printed.
    assert ex.onnx_opset(m) == 17 and m.ir_version == 8
    assert "opset 17, IR 8" in stdout.getvalue() and "1 adaptive pools" in stdout.getvalue(), stdout.getvalue()
    # The output's spatial dims are fixed in the graph (SCHP leaves them symbolic).
    dims = [d.dim_value or d.dim_param for d in m.graph.output[0].type.tensor_type.shape.dim]
    assert dims == ["batch", 7, 16, 16], dims
    assert sidecar["output_stride"] == 4 and sidecar["input_size"] == [64, 64], sidecar
    assert "MatMul" in {n.op_type for n in m.graph.node}


def main():
    tests = [(name, fn) for name, fn in globals().items() if name.startswith("test_") and callable(fn)]
    failed = 0
    for name, fn in tests:
        try:
            fn()
            print(f"ok   {name}")
        except Exception:  # noqa: BLE001 - report every failure, then exit non-zero
            failed += 1
            print(f"FAIL {name}\n{traceback.format_exc()}")
    print(f"{len(tests) - failed} passed, {failed} failed")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
