#!/usr/bin/env bash
# A screenshot of the Rerun viewer showing a .rrd file, on a machine without a display:
# the viewer of the Python package (`pip install rerun-sdk==0.36.3`) under Xvfb, rendering
# in software (Mesa's lavapipe Vulkan; the GL backend lacks R32Float render targets), with
# the viewer's own `--screenshot-to`. Needs: apt-get install xvfb mesa-vulkan-drivers.
#
#   scripts/rerun_screenshot.sh FILE.rrd OUT.png [WxH]     (default 1600x900 logical px)
set -euo pipefail
rrd="$1"
png="$2"
size="${3:-1600x900}"
rerun="${RERUN:-rerun}"
display=":$((90 + RANDOM % 9))"
Xvfb "$display" -screen 0 3200x1800x24 >/dev/null 2>&1 &
xvfb=$!
trap 'kill "$xvfb" 2>/dev/null || true' EXIT
sleep 2
# The viewer exits after the screenshot (with a non-zero status on some versions).
DISPLAY="$display" WGPU_BACKEND=vulkan XDG_RUNTIME_DIR="${XDG_RUNTIME_DIR:-/tmp}" \
    timeout 300 "$rerun" --port $((9900 + RANDOM % 90)) --window-size "$size" \
    --screenshot-to "$png" "$rrd" >/dev/null 2>&1 || true
test -s "$png" || { echo "no screenshot written: $png" >&2; exit 1; }
echo "$png"
