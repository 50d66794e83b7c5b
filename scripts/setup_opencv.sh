#!/usr/bin/env bash
# Installs what the `opencv` cargo feature (`bodyseg calibrate`) builds against: Debian's
# OpenCV development files, and clang with libclang, which the `opencv` crate's build script
# uses to generate its bindings.
#
#   scripts/setup_opencv.sh          from any folder; does nothing when already installed
#
# Needs apt-get and root (or the packages installed by hand: libopencv-dev clang
# libclang-dev). The default build (without `--features opencv`) needs none of this.
set -euo pipefail

packages=(libopencv-dev clang libclang-dev)
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
# The opencv crate finds OpenCV with pkg-config.
command -v pkg-config >/dev/null 2>&1 || missing+=(pkg-config)
if ((${#missing[@]} == 0)); then
    echo "OpenCV $(pkg-config --modversion opencv4 2>/dev/null || echo '?'), clang: installed"
    exit 0
fi
if ! command -v apt-get >/dev/null 2>&1 || [ "$(id -u)" != 0 ]; then
    echo "missing ${missing[*]}: install them (apt-get install ${missing[*]}) and rerun" >&2
    exit 1
fi
echo "==> apt-get install ${missing[*]}"
apt-get update -qq
DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
echo "OpenCV $(pkg-config --modversion opencv4), $(clang --version | head -n 1): installed"
