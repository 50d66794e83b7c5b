#!/usr/bin/env bash
# What `--rerun` (issue 31) costs `bodyseg run`: per-frame time with and without writing
# the .rrd on the same synthetic recording in the same session (ratio; issue 31 wants
# <= 1.15), and the peak memory (max RSS, /usr/bin/time -v) of `run --rerun` at two
# recording lengths (flat memory: the file streams frame by frame).
#
#   scripts/bench_rerun.sh [FRAMES] [LONG_FRAMES] [SHORT_FRAMES]   (default 24, 500, 100)
#
# Needs a release binary built with the feature: cargo build --release --features rerun.
# Time: the ratio of `run`'s wall-clock times and of its CPU times (user + sys, from
# /usr/bin/time; the figure to compare on a loaded machine), each the median of 3 (recorded
# parser, no figure), after a warm-up; memory: 1 camera, colour 480 px wide, recorded parser.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
frames="${1:-24}"
long="${2:-500}"
short="${3:-100}"
bin="${BODYSEG:-target/release/bodyseg}"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
# The synthetic recordings are kept in RECS (default: a temporary folder) and reused.
recs="${RECS:-$tmp}"
mkdir -p "$recs"

synth() { # synth NAME ARGS...: the recording $recs/NAME, made once
    local name="$1"; shift
    [ -f "$recs/$name/rig.toml" ] || "$bin" synth --no-preview "$@" --out "$recs/$name" >/dev/null 2>&1
}
synth "handover$frames" --preset handover --frames "$frames" --seed 1

run() { # run OUT [extra args]: "wall cpu" seconds of one full run (cpu = user + sys)
    local out="$1"; shift
    /usr/bin/time -f "%e %U %S" -o "$tmp/time" \
        "$bin" --quiet run --recording "$recs/handover$frames" --out "$out" --parser recorded --figure none --force "$@" >/dev/null
    awk '{printf "%s %.2f\n", $1, $2 + $3}' "$tmp/time"
}
median() { printf '%s\n' "$@" | sort -g | sed -n 2p; }

run "$tmp/warm" >/dev/null
plain=(); with=(); plain_cpu=(); with_cpu=()
for _ in 1 2 3; do
    read -r wall cpu < <(run "$tmp/plain"); plain+=("$wall"); plain_cpu+=("$cpu")
    read -r wall cpu < <(run "$tmp/with" --rerun "$tmp/with/run.rrd"); with+=("$wall"); with_cpu+=("$cpu")
done
p=$(median "${plain[@]}"); w=$(median "${with[@]}")
pc=$(median "${plain_cpu[@]}"); wc=$(median "${with_cpu[@]}")
size=$(stat -c %s "$tmp/with/run.rrd")
printf 'run, %d frames, 3 cameras: %.3f s/frame without --rerun, %.3f s/frame with (ratio %.3f), .rrd %.1f MB\n' \
    "$frames" "$(echo "$p / $frames" | bc -l)" "$(echo "$w / $frames" | bc -l)" "$(echo "$w / $p" | bc -l)" \
    "$(echo "$size / 1000000" | bc -l)"
printf 'run, %d frames, 3 cameras: CPU (user + sys) %.2f s without --rerun, %.2f s with (ratio %.3f)\n' \
    "$frames" "$pc" "$wc" "$(echo "$wc / $pc" | bc -l)"

# Memory over a long recording: small images, one camera.
small=(--set rig.cameras=1 --set rig.color_width=480 --set people.count=1)
for n in "$short" "$long"; do
    synth "single$n" --preset single --frames "$n" --seed 2 "${small[@]}"
    rss=$( { /usr/bin/time -v "$bin" --quiet run --recording "$recs/single$n" --out "$tmp/long$n-out" --parser recorded \
        --figure none --no-label-images --rerun "$tmp/long$n-out/run.rrd" >/dev/null; } 2>&1 | awk '/Maximum resident/ {print $6}')
    printf 'run --rerun, %d frames, 1 camera: max RSS %.1f MB, .rrd %.1f MB\n' "$n" "$(echo "$rss / 1024" | bc -l)" \
        "$(echo "$(stat -c %s "$tmp/long$n-out/run.rrd") / 1000000" | bc -l)"
done
