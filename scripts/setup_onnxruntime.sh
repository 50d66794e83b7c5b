#!/usr/bin/env bash
# Puts the ONNX Runtime shared library that `bodyseg parse` (bodyseg-parsing) loads at run
# time into .deps/onnxruntime/ (git-ignored), once: the library shipped inside PyPI's
# `onnxruntime` wheel (onnxruntime/capi/libonnxruntime.so.*), fetched with pip.
#
#   scripts/setup_onnxruntime.sh          from any folder; does nothing when already done
#
# Result: .deps/onnxruntime/libonnxruntime.so (a link to the versioned file). bodyseg finds
# it there by itself; elsewhere, point ORT_DYLIB_PATH or parsing.runtime_library at it.
# Needs python3 with pip (installed with apt-get when missing and run as root).
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."

ORT_VERSION=1.24.4
dest=.deps/onnxruntime
lib="$dest/libonnxruntime.so"

if [ -e "$lib" ] && [ "$(cat "$dest/VERSION" 2>/dev/null)" = "$ORT_VERSION" ]; then
    echo "ONNX Runtime $ORT_VERSION: $lib (already set up)"
    exit 0
fi

if ! python3 -m pip --version >/dev/null 2>&1; then
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        apt-get update -qq && apt-get install -y -qq python3 python3-pip
    else
        echo "python3 with pip is needed to fetch ONNX Runtime (apt-get install python3-pip)" >&2
        exit 1
    fi
fi

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
arch=$(uname -m)
echo "==> fetching onnxruntime $ORT_VERSION ($arch) from PyPI"
# The wheel's library does not depend on the Python version: ask for one fixed tag so the
# same file comes down whatever python3 this machine has.
python3 -m pip download --quiet "onnxruntime==$ORT_VERSION" --no-deps --only-binary=:all: \
    --python-version 3.11 --implementation cp --abi cp311 \
    --platform "manylinux_2_28_$arch" --platform "manylinux_2_27_$arch" \
    --platform "manylinux_2_17_$arch" --platform "manylinux2014_$arch" \
    --dest "$tmp"

mkdir -p "$dest"
python3 - "$tmp" "$dest" "$ORT_VERSION" <<'PY'
import pathlib, re, sys, zipfile
tmp, dest, version = pathlib.Path(sys.argv[1]), pathlib.Path(sys.argv[2]), sys.argv[3]
wheels = sorted(tmp.glob("onnxruntime-*.whl"))
if not wheels:
    sys.exit(f"no onnxruntime wheel was downloaded into {tmp}")
with zipfile.ZipFile(wheels[0]) as z:
    names = [n for n in z.namelist() if re.fullmatch(r"onnxruntime/capi/libonnxruntime\.so(\.[0-9.]+)?", n)]
    if not names:
        sys.exit(f"{wheels[0].name} holds no onnxruntime/capi/libonnxruntime.so*")
    name = max(names, key=len)
    out = dest / f"libonnxruntime.so.{version}"
    part = out.with_suffix(out.suffix + ".partial")
    part.write_bytes(z.read(name))
    part.replace(out)
    print(f"{wheels[0].name}: {name} -> {out}")
PY
ln -sfn "libonnxruntime.so.$ORT_VERSION" "$lib"
echo "$ORT_VERSION" > "$dest/VERSION"
echo "ONNX Runtime $ORT_VERSION: $lib"
