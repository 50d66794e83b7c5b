#!/usr/bin/env bash
# Runs bodyseg on the bad-input classes of issue 27 and prints the markdown table of
# docs/notes/reliability.md: class | example input | message | exit status | left behind.
#
#   scripts/reliability_table.sh [BODYSEG] > table.md
#
# BODYSEG defaults to target/release/bodyseg (build it first: cargo build --release).
# Each case runs in a fresh copy of a small synthetic recording and its clouds; "left
# behind" lists the files the failed command added (temporaries included), "nothing" when
# none. A case that takes over 60 s is cut ("timeout", exit 124). Needs bash, coreutils,
# python3 (to write a PCD header).
set -u
B=$(realpath "${1:-target/release/bodyseg}")
[ -x "$B" ] || { echo "no bodyseg binary at $B: cargo build --release" >&2; exit 1; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
base=$work/base
mkdir -p "$base"
(
    cd "$base" || exit 1
    "$B" synth --preset handover --frames 2 --seed 3 --no-preview --out rec -q &&
        "$B" project --recording rec --frame 000000 --out f0.ply -q &&
        "$B" project --recording rec --frame 000001 --out f1.ply -q &&
        "$B" boxes --recording rec --frame 000000 --out boxes.json -q
) || { echo "setup failed" >&2; exit 1; }

echo "| class | example input | message (first error: or warning: line) | exit status | left behind |"
echo "|---|---|---|---|---|"
n=0
# case CLASS EXAMPLE SETUP COMMAND...: SETUP is shell run first in the case's folder.
case_() {
    local class=$1 example=$2 setup=$3
    shift 3
    n=$((n + 1))
    local d=$work/case$n
    cp -a "$base" "$d"
    (cd "$d" && eval "$setup") >/dev/null 2>&1
    local before after
    before=$(cd "$d" && find . -mindepth 1 | sort)
    local err rc
    err=$(cd "$d" && timeout 60 "$B" "$@" 2>&1)
    rc=$?
    after=$(cd "$d" && find . -mindepth 1 | sort)
    local left
    left=$(comm -13 <(echo "$before") <(echo "$after") | sed 's|^\./||' | head -4 | tr '\n' ' ')
    [ -n "$left" ] || left=nothing
    [ "$rc" = 0 ] && [ "$left" != nothing ] && left="its outputs: $left"
    local msg
    msg=$(echo "$err" | grep -m1 -E '^(error|warning|ONNX Runtime library):' || echo "$err" | head -1)
    [ "$rc" = 124 ] && msg="timeout (60 s)"
    msg=${msg//|/\\|}
    printf '| %s | %s | %s | %s | %s |\n' "$class" "$example" "${msg:0:300}" "$rc" "$left"
}

rig_name() { NAME=$1 python3 -c 'import os; p = "rec/rig.toml"; t = open(p).read(); open(p, "w").write(t.replace("name = \"cam0\"", "name = \"%s\"" % os.environ["NAME"], 1))'; }

case_ "library planted in the current folder" "ORT_DYLIB_PATH unset, ./.deps/onnxruntime/libonnxruntime.so" \
    'mkdir -p .deps/onnxruntime && echo x > .deps/onnxruntime/libonnxruntime.so' \
    version -v
case_ "name leading out of the recording" 'camera `../../x` in rig.toml' 'rig_name ../../x' \
    run --recording rec --out out
case_ "absolute name" 'camera `/tmp/x` in rig.toml' 'rig_name /tmp/x' \
    run --recording rec --out out
case_ "unicode name" 'camera `kamera_ä` in rig.toml' 'rig_name kamera_ä' \
    run --recording rec --out out
case_ "name leading out (frame)" '`--frame ../x`' '' \
    project --recording rec --frame ../x --out p.ply
case_ "--out is an input" 'refine --out equal to --cloud' '' \
    refine --cloud f0.ply --boxes boxes.json --out f0.ply
case_ "--out is an input via a link" 'refine --out link.ply → f0.ply' 'ln -s f0.ply link.ply' \
    refine --cloud f0.ply --boxes boxes.json --out link.ply
case_ "--out replaces a file not ours" 'eval --out f1.ply (a cloud)' '' \
    eval --pred f0.ply --gt f0.ply --out f1.ply
# A FIFO, not /dev/null: an older bodyseg replaced the device node with a file.
case_ "--out is a device or FIFO" 'refine --out fifo.ply (mkfifo)' 'mkfifo fifo.ply' \
    refine --cloud f0.ply --boxes boxes.json --out fifo.ply
case_ "--out inside the recording" 'run --out rec' '' \
    run --recording rec --out rec
case_ "--out is a file, a folder expected" 'run --out f0.ply' '' \
    run --recording rec --out f0.ply
case_ "PCD header: huge POINTS" 'POINTS 10^18 in a 200-byte PCD' \
    "printf 'VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1000000000000000000\nHEIGHT 1\nPOINTS 1000000000000000000\nDATA binary\n' > big.pcd" \
    boxes --cloud big.pcd --out b.json
case_ "PCD header: huge COUNT" 'COUNT 10^18' \
    "printf 'VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1000000000000000000 1 1\nWIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA binary\n' > count.pcd" \
    boxes --cloud count.pcd --out b.json
case_ "refine eps too small" 'refine --eps-m 1e-7' '' \
    refine --cloud f0.ply --boxes boxes.json --eps-m 1e-7 --out r.ply
case_ "config value that hung" 'refine.smooth_radius_m = 1e20' '' \
    refine --cloud f0.ply --boxes boxes.json --set refine.smooth_radius_m=1e20 --out r.ply
case_ "config value that hung" 'boxes.head_separation_m = 1000' '' \
    boxes --cloud f0.ply --set boxes.head_separation_m=1000 --out b.json
case_ "config value that took gigabytes" 'boxes.voxel_m = 0.001' '' \
    boxes --cloud f0.ply --set boxes.voxel_m=0.001 --out b.json
case_ "side file cannot be written" 'refine --out r.ply, r.config.resolved.toml a folder' \
    'mkdir r.config.resolved.toml' \
    refine --cloud f0.ply --boxes boxes.json --out r.ply
case_ "depth scale implausible" 'depth_scale = 1 in rig.toml' \
    'sed -i "s/depth_scale = 1000.0/depth_scale = 1.0/" rec/rig.toml' \
    project --recording rec --frame 000000 --out p.ply
case_ "cloud in millimetres" 'boxes --cloud of a cloud ×1000' \
    "\"$B\" project --recording rec --frame 000000 --ascii --out a.ply -q && awk 'BEGIN{h=1} h{print; if(\$0==\"end_header\") h=0; next} {\$1*=1000; \$2*=1000; \$3*=1000; print}' a.ply > mm.ply" \
    boxes --cloud mm.ply --out b.json
case_ "a box far from the cloud" 'refine with a box 500 m away' \
    "python3 -c 'import json; b = json.load(open(\"boxes.json\")); b[\"boxes\"][0][\"center_m\"][0] += 500; json.dump(b, open(\"far.json\", \"w\"))'" \
    refine --cloud f0.ply --boxes far.json --out r.ply
case_ "no person" 'refine with no box' "echo '{\"frame\": \"000000\", \"boxes\": []}' > none.json" \
    refine --cloud f0.ply --boxes none.json --out r.ply
case_ "clouds of different frames" 'eval --pred frame 1 --gt frame 0' '' \
    eval --pred f1.ply --gt f0.ply
case_ "frame a camera lacks" 'rm rec/cam1/depth/000001.png' 'rm rec/cam1/depth/000001.png' \
    run --recording rec --out out -q
case_ "ground truth missing for a camera" 'rm -r rec/cam1/depth_labels' 'rm -r rec/cam1/depth_labels' \
    run --recording rec --out out -q
