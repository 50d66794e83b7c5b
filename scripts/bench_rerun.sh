#!/usr/bin/env bash
# What `--rerun` (issue 31) costs `bodyseg run`: per-frame time with and without writing
# the .rrd on the same synthetic recording in the same session (ratio; issue 31 wants
# <= 1.15), and the peak memory (max RSS, /usr/bin/time -v) of `run --rerun` at two
# recording lengths (flat memory: the file streams frame by frame).
#
#   scripts/bench_rerun.sh [FRAMES] [LONG_FRAMES] [SHORT_FRAMES] [MODEL_FRAMES]
#                                                          (default 96, 500, 100, 8)
#
# Needs a release binary built with the feature: cargo build --release --features rerun.
# Time, for two runs of the handover scene (3 cameras), each the ratio of `run`'s wall-clock
# times and of its CPU times (user + sys, from /usr/bin/time; the figure to compare on a
# loaded machine; user time alone too: on a VM the system time also holds the host's cost of
# fresh pages, which varies several-fold between identical runs), and the `rerun` stage's
# time over the other stages' within the `--rerun` run (run.json; the direct cost, which
# the machine's noise weighs alike), medians of ROUNDS rounds (default 5; one run without
# and one with `--rerun` per round) after a warm-up, no figure:
#   - the default parser (BlazePose + BodyPix, `--parser model`: what `--parser auto` picks
#     on a recording without recorded labels) on MODEL_FRAMES frames: a user's run. Needs
#     the ONNX Runtime (ORT_DYLIB_PATH, else .deps/onnxruntime/); skipped, saying so,
#     without it. The 2D parsing dominates its time, so few frames are enough;
#   - the recorded parser (`--parser recorded`: no 2D parsing, the cheapest run there is) on
#     FRAMES frames: the worst case for the ratio. Enough frames that what a run pays once
#     (the SDK's start, the file's footer, the first touch of the writer's memory: ~0.25 s
#     on this project's VM, where a fresh 2 MB page costs ~10 ms) weighs little per frame.
# Memory: 1 camera, colour 480 px wide, recorded parser.
# With INSTRUCTIONS=1 (needs valgrind): the recorded parser's instructions per frame too,
# without and with --rerun (callgrind, 3 and 24 frames: the difference per frame), a
# figure this VM's timing noise (host page faults: +-15 % between identical runs) leaves alone.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
frames="${1:-96}"
long="${2:-500}"
short="${3:-100}"
model_frames="${4:-8}"
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

run() { # run REC OUT [extra args]: "wall cpu user" seconds of one full run (cpu = user + sys)
    local rec="$1" out="$2"; shift 2
    # Into a new folder, as a first run: over a previous run's files each replacing rename
    # waits for the file system to write the new file out (ext4), which the .rrd's own
    # writes make slower (docs/notes/2026-12-02-rerun.md, 2026-12-04b).
    rm -rf "$out"
    /usr/bin/time -f "%e %U %S" -o "$tmp/time" \
        "$bin" --quiet run --recording "$recs/$rec" --out "$out" --figure none --force "$@" >/dev/null
    awk '{printf "%s %.2f %s\n", $1, $2 + $3, $2}' "$tmp/time"
}
rounds="${ROUNDS:-5}"
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR] = $1} END {print (NR % 2) ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2}'; }

ratio() { # ratio LABEL REC FRAMES PARSER: prints the wall and CPU ratios of --rerun
    local label="$1" rec="$2" n="$3" parser="$4"
    run "$rec" "$tmp/warm" --parser "$parser" >/dev/null
    local plain=() with=() plain_cpu=() with_cpu=() plain_user=() with_user=() share=() wall cpu user
    for _ in $(seq "$rounds"); do
        read -r wall cpu user < <(run "$rec" "$tmp/plain" --parser "$parser")
        plain+=("$wall"); plain_cpu+=("$cpu"); plain_user+=("$user")
        read -r wall cpu user < <(run "$rec" "$tmp/with" --parser "$parser" --rerun "$tmp/with/run.rrd")
        with+=("$wall"); with_cpu+=("$cpu"); with_user+=("$user")
        share+=("$(stage_share "$tmp/with/run.json")")
    done
    local p w pc wc pu wu size
    p=$(median "${plain[@]}"); w=$(median "${with[@]}")
    pc=$(median "${plain_cpu[@]}"); wc=$(median "${with_cpu[@]}")
    pu=$(median "${plain_user[@]}"); wu=$(median "${with_user[@]}")
    size=$(stat -c %s "$tmp/with/run.rrd")
    printf '%s, %d frames, 3 cameras: wall %.3f s/frame without --rerun, %.3f s/frame with (ratio %.3f), .rrd %.1f MB (%.1f MB/frame)\n' \
        "$label" "$n" "$(echo "$p / $n" | bc -l)" "$(echo "$w / $n" | bc -l)" "$(echo "$w / $p" | bc -l)" \
        "$(echo "$size / 1000000" | bc -l)" "$(echo "$size / 1000000 / $n" | bc -l)"
    printf '%s, %d frames, 3 cameras: CPU (user + sys) %.2f s without --rerun, %.2f s with (ratio %.3f); user alone %.2f s, %.2f s (ratio %.3f)\n' \
        "$label" "$n" "$pc" "$wc" "$(echo "$wc / $pc" | bc -l)" "$pu" "$wu" "$(echo "$wu / $pu" | bc -l)"
    printf '%s, %d frames, 3 cameras: the rerun stage took %.3f of the other stages'"'"' time in the same run (1 + it: %.3f)\n' \
        "$label" "$n" "$(median "${share[@]}")" "$(echo "1 + $(median "${share[@]}")" | bc -l)"
}

# The rerun stage's time over the other stages' (run.json's stage_seconds, summed over the
# workers): the direct cost of writing the .rrd, measured within one run, so that the
# machine's speed at that moment weighs both alike. The ratios above also hold what the
# writing costs the other stages (caches, memory, threads), and this VM's noise.
stage_share() {
    python3 -c 'import json, sys
s = dict(json.load(open(sys.argv[1]))["stage_seconds"])
r = s.pop("rerun")
print("%.4f" % (r / sum(s.values())))' "$1"
}

# A user's run: the default parser (BlazePose + BodyPix).
if [ -z "${ORT_DYLIB_PATH:-}" ]; then
    ORT_DYLIB_PATH="$(ls .deps/onnxruntime/libonnxruntime.so* 2>/dev/null | head -1 || true)"
    export ORT_DYLIB_PATH
fi
if [ -n "$ORT_DYLIB_PATH" ] && [ -e "$ORT_DYLIB_PATH" ]; then
    synth "handover$model_frames" --preset handover --frames "$model_frames" --seed 1
    ratio "default parser (BlazePose + BodyPix)" "handover$model_frames" "$model_frames" model
else
    echo "default parser (BlazePose + BodyPix): skipped, no ONNX Runtime (set ORT_DYLIB_PATH)"
fi

# The worst case: no 2D parsing at all.
synth "handover$frames" --preset handover --frames "$frames" --seed 1
ratio "recorded parser (no 2D parsing, worst case)" "handover$frames" "$frames" recorded

if [ "${INSTRUCTIONS:-0}" = 1 ]; then
    synth handover3 --preset handover --frames 3 --seed 1
    synth handover24 --preset handover --frames 24 --seed 1
    instructions() { # instructions REC [extra args]: instructions of one run (callgrind)
        local rec="$1"; shift
        rm -rf "$tmp/vg"
        valgrind --tool=callgrind --callgrind-out-file="$tmp/cg.out" "$bin" --quiet run \
            --recording "$recs/$rec" --out "$tmp/vg" --parser recorded --figure none "$@" \
            >/dev/null 2>"$tmp/vg.log"
        awk '/Collected :/ {gsub(",", "", $4); print $4}' "$tmp/vg.log"
    }
    p3=$(instructions handover3); w3=$(instructions handover3 --rerun "$tmp/vg/run.rrd")
    pn=$(instructions handover24); wn=$(instructions handover24 --rerun "$tmp/vg/run.rrd")
    printf 'recorded parser, instructions per frame (24 - 3 frames): %.1f M without --rerun, %.1f M with (ratio %.3f); whole 24-frame run %.3f\n' \
        "$(echo "($pn - $p3) / 21 / 1000000" | bc -l)" \
        "$(echo "($wn - $w3) / 21 / 1000000" | bc -l)" \
        "$(echo "($wn - $w3) / ($pn - $p3)" | bc -l)" "$(echo "$wn / $pn" | bc -l)"
fi

# Memory over a long recording: small images, one camera.
small=(--set rig.cameras=1 --set rig.color_width=480 --set people.count=1)
for n in "$short" "$long"; do
    synth "single$n" --preset single --frames "$n" --seed 2 "${small[@]}"
    rss=$( { /usr/bin/time -v "$bin" --quiet run --recording "$recs/single$n" --out "$tmp/long$n-out" --parser recorded \
        --figure none --no-label-images --rerun "$tmp/long$n-out/run.rrd" >/dev/null; } 2>&1 | awk '/Maximum resident/ {print $6}')
    printf 'run --rerun, %d frames, 1 camera: max RSS %.1f MB, .rrd %.1f MB\n' "$n" "$(echo "$rss / 1024" | bc -l)" \
        "$(echo "$(stat -c %s "$tmp/long$n-out/run.rrd") / 1000000" | bc -l)"
done
