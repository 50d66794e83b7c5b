#!/usr/bin/env bash
# The whole check, as CI runs it (.ci/run): formatting, lints, crate boundaries, tests.
#
#   scripts/test.sh            from any folder
#
# Installs what a fresh Debian 12 machine with the Rust toolchain lacks (the rustfmt and
# clippy components; OpenCV and clang for the `opencv` feature, which clippy and the tests
# build: --all-features). Tests run in release: the DBSCAN property tests compare against an
# O(n^2) brute force on hundreds of clouds. Slow tests marked #[ignore] run last.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."

step() { printf '\n==> %s\n' "$*"; }

step "toolchain"
if ! command -v cargo >/dev/null 2>&1; then
    echo "cargo not found: install the Rust toolchain with rustup, then rerun" >&2
    exit 1
fi
# rust-toolchain.toml pins the version; rustup installs it on first use.
missing=()
cargo fmt --version >/dev/null 2>&1 || missing+=(rustfmt)
cargo clippy --version >/dev/null 2>&1 || missing+=(clippy)
if ((${#missing[@]})); then
    if ! command -v rustup >/dev/null 2>&1; then
        echo "cargo ${missing[*]} missing and no rustup to install them" >&2
        exit 1
    fi
    rustup component add "${missing[@]}"
fi
if ! command -v python3 >/dev/null 2>&1; then
    if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        apt-get update -qq && apt-get install -y -qq python3
    else
        echo "python3 not found (needed by scripts/check_boundaries.py)" >&2
        exit 1
    fi
fi
cargo --version
rustc --version

step "ONNX Runtime (scripts/setup_onnxruntime.sh; once, into .deps/onnxruntime/)"
scripts/setup_onnxruntime.sh

step "OpenCV for the opencv feature (scripts/setup_opencv.sh; apt-get once)"
scripts/setup_opencv.sh

step "cargo fmt --all --check"
cargo fmt --all --check

# --release: the opencv crate's build script (binding generation and its C++ wrapper, several
# minutes) then runs once for clippy and the release tests below, instead of once per profile.
step "cargo clippy --release --workspace --all-targets --all-features -- -D warnings"
cargo clippy --release --workspace --all-targets --all-features -- -D warnings

step "python3 scripts/check_boundaries.py"
python3 scripts/check_boundaries.py

step "python3 scripts/export_schp_onnx.py --dry-run and scripts/test_export_schp.py (when torch, onnx and onnxruntime are installed)"
if python3 -c "import torch, onnx, onnxruntime" >/dev/null 2>&1; then
    python3 scripts/export_schp_onnx.py --dry-run 2>&1 | grep -v -i warning
    python3 scripts/test_export_schp.py
else
    echo "skipped: pip install torch onnx onnxruntime to check the SCHP export script"
fi

step "python3 scripts/test_real_parsing.py (real-image benchmark scripts; when numpy and pillow are installed)"
if python3 -c "import numpy, PIL" >/dev/null 2>&1; then
    python3 scripts/test_real_parsing.py
else
    echo "skipped: pip install numpy pillow scipy to test the benchmark scripts"
fi

step "python3 scripts/test_results_doc.py (docs/results.md's generator on a made-up work folder)"
python3 scripts/test_results_doc.py

step "Rerun Python SDK for tests/cli_rerun.rs (rerun-sdk[datafusion]==0.36.3 in .venv-rerun; ~4 min once)"
# The e2e test of `--rerun` reads the .rrd back with the SDK of the Rust crate's version
# (Cargo.toml's re_sdk); it skips, saying so, when this Python has no SDK.
if [ ! -x .venv-rerun/bin/python ] || ! .venv-rerun/bin/python -c "import rerun, datafusion" >/dev/null 2>&1; then
    python3 -m venv .venv-rerun && .venv-rerun/bin/pip install -q "rerun-sdk[datafusion]==0.36.3" \
        || echo "warning: rerun-sdk not installed: the .rrd check of tests/cli_rerun.rs is skipped"
fi
export BODYSEG_RERUN_PYTHON="$PWD/.venv-rerun/bin/python"

step "cargo test --workspace --all-features --release"
log=$(mktemp)
trap 'rm -f "$log"' EXIT
cargo test --workspace --all-features --release 2>&1 | tee "$log"

# Slow cases are #[ignore]d and run here, in release; skipped when there are none (a run
# of zero tests would read as "no test ran").
if grep -rqs '#\[ignore' crates tests; then
    step "cargo test --workspace --all-features --release -- --ignored (slow tests)"
    cargo test --workspace --all-features --release -- --ignored 2>&1 | tee -a "$log"
fi

# Every fuzz target (fuzz/README.md) for a few seconds: libFuzzer on stable Rust, from the
# committed seeds and crash regressions; a crash, hang or memory failure fails the check.
# Its own instrumented build in fuzz/target/ (the workspace again, a few minutes on a
# fresh machine), then 12 targets x 5 s.
step "scripts/fuzz.sh 5 (each fuzz target for 5 s)"
scripts/fuzz.sh 5

step "all checks passed"
# One closing line with the totals of every test binary above.
awk '/^test result:/ { for (i = 1; i <= NF; i++) { if ($(i+1) ~ /^passed/) p += $i; if ($(i+1) ~ /^failed/) f += $i } }
     END { printf "tests: %d passed, %d failed\n", p, f }' "$log"
