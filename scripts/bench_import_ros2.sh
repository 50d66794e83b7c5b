#!/usr/bin/env bash
# Throughput and peak memory of `bodyseg import ros2` at two bag lengths (issue 28: a
# 3-camera qhd bag at >= 20 frames/s on 2 cores, memory flat in the bag's length).
#
#   scripts/bench_import_ros2.sh [FRAMES_SHORT] [FRAMES_LONG]     (default 100 200)
#
# A synthetic recording (3 Kinect v2 cameras: depth 512x424, colour 960x540) of 10 frames
# is written as iai_kinect2 bags (/camN/sd/image_depth 16UC1, /camN/qhd/image_color bgr8,
# CameraInfo, /tf_static; zstd chunks) by scripts/write_ros2_bag.py, its frames repeated to
# FRAMES_SHORT and FRAMES_LONG frames; each is imported once, timed by /usr/bin/time -v.
# Needs python3 with scripts/requirements-ros2.txt, and the release binary (built here, or
# BODYSEG=path/to/bodyseg). Also printed: the CPU time (user + sys), whose frames per CPU
# second times the cores is the rate on an idle machine when others share its cores.
# Scratch files go to a temporary folder, removed at the end.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

short=${1:-100}
long=${2:-200}
bin=${BODYSEG:-}
if [ -z "$bin" ]; then
    cargo build --release -q
    bin=$PWD/target/release/bodyseg
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

"$bin" -q synth --preset handover --frames 10 --seed 3 --no-preview --out "$work/src"
for n in "$short" "$long"; do
    python3 scripts/write_ros2_bag.py "$work/src" "$work/bag_$n.mcap" --repeat $((n / 10)) >/dev/null
    rm -rf "$work/rec_$n"
    /usr/bin/time -v "$bin" import ros2 "$work/bag_$n.mcap" --out "$work/rec_$n" \
        2>"$work/log_$n" >/dev/null
    secs=$(awk -F': ' '/Elapsed \(wall clock\)/ {print $2}' "$work/log_$n")
    rss=$(awk -F': ' '/Maximum resident set size/ {print $2}' "$work/log_$n")
    cpu=$(awk -F': ' '/User time|System time/ {s += $2} END {printf "%.1f", s}' "$work/log_$n")
    frames=$(grep -o '[0-9]* written ([0-9.]* frames/s)' "$work/log_$n" || true)
    bag_mb=$(( $(stat -c %s "$work/bag_$n.mcap") / 1000000 ))
    echo "$n frames (bag ${bag_mb} MB): wall ${secs}, ${frames}, CPU ${cpu} s ($(awk "BEGIN {printf \"%.1f\", $n / $cpu}") frames per CPU s), peak RSS $((rss / 1024)) MiB"
    rm -rf "$work/rec_$n" "$work/bag_$n.mcap"
done
