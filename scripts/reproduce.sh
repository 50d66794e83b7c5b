#!/usr/bin/env bash
# Regenerates docs/results.md from nothing: renders the fixed benchmark of
# configs/benchmarks/paper.toml (3 presets x 4 seeds x 25 frames, exact ground truth),
# runs the paper's five configurations (Reference, M, N, M-N, M-R-N) for three 2D prediction
# sources (the synthetic parser errors recorded with the recording, the bundled
# synthetic-trained ONNX model, and the default parser, BlazePose full on the people found
# from depth) and both projection modes (naive, DSA), then the improved refinement
# (configs/benchmarks/improved.toml; for the model also without its probabilities,
# improved_weighted.toml) and the improved refinement with the multi-view vote
# (configs/benchmarks/improved_vote.toml), each for both projections, the projection study,
# the figures and the regression subset, and writes the tables and their reading into
# docs/results.md.
#
#   scripts/reproduce.sh [WORK_DIR]        (default: target/reproduce; reused when run again)
#   SOURCES=blazepose scripts/reproduce.sh  (re-runs only these 2D sources, of "recorded model
#                                           blazepose", and their figure; the other sources'
#                                           reports are read from WORK_DIR's last full run)
#
# About 35 minutes on a quiet 2-core machine (estimated: 22 without BlazePose, whose paper-mode
# run takes 1.3 min; the improved refinement adds to each run); 66 minutes measured while other
# builds shared the cores. A second run reuses the rendered recordings (the same seeds give the
# same bytes) but runs every configuration again: the code may have changed since.
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."
work="${1:-target/reproduce}"
mkdir -p "$work"
sources="${SOURCES:-recorded model blazepose}"
for source in $sources; do
    case $source in
        recorded | model | blazepose) ;;
        *) echo "reproduce.sh: SOURCES: unknown source '$source' (recorded, model, blazepose)" >&2; exit 2 ;;
    esac
done
if [ "$sources" = "recorded model blazepose" ]; then
    rm -rf "$work/runs" "$work/subset" "$work"/figure_*
else
    for source in $sources; do
        if [ ! -d "$work/runs" ]; then
            echo "reproduce.sh: SOURCES=$sources needs the reports of a full run in $work/runs" >&2
            exit 2
        fi
        rm -rf "$work/runs/${source}"_*
    done
fi
start=$(date +%s)

echo "==> ONNX Runtime (once), release build"
scripts/setup_onnxruntime.sh
cargo build --release --quiet --bin bodyseg
cargo build --release --quiet -p bodyseg-lab --example projection_report
bodyseg=target/release/bodyseg

# "preset seed frames" lines of the benchmark, and the subset's frame count.
recordings=$(python3 - <<'PY'
import tomllib
b = tomllib.load(open("configs/benchmarks/paper.toml", "rb"))
for r in b["recording"]:
    for s in r["seeds"]:
        print(r["preset"], s, r["frames"])
PY
)
subset_frames=$(python3 -c 'import tomllib; print(tomllib.load(open("configs/benchmarks/paper.toml","rb"))["subset"]["frames"])')

echo "==> rendering the benchmark ($(echo "$recordings" | wc -l) recordings)"
while read -r preset seed frames; do
    rec="$work/rec/${preset}_${seed}"
    if [ ! -f "$rec/rig.toml" ]; then
        "$bodyseg" synth --preset "$preset" --seed "$seed" --frames "$frames" --no-preview --out "$rec" -q
    fi
done <<< "$recordings"

# bodyseg convert exits 3 when some frames failed: they are listed in the reports, go on.
convert() {
    local out=$1
    shift
    echo "==> $out"
    "$bodyseg" convert --input "$work/rec" --format recording --out "$work/runs/$out" -q "$@" \
        || [ $? -eq 3 ]
    # Only the reports are read: the clouds and label images (~2 GB per run) go.
    find "$work/runs/$out" \( -name '*.ply' -o -path '*/labels/*.png' \) -delete
}
# "model" is the bundled synthetic-trained model (parsing.segmenter = "onnx"); "blazepose" is
# the default parser (trained on real photographs: the renders are outside its domain), named
# here so that its rows stay BlazePose's if the default changes.
for source in $sources; do
    case $source in
        recorded) parser=(--parser recorded) ;;
        model) parser=(--parser model --set parsing.segmenter=onnx) ;;
        blazepose) parser=(--parser model --set parsing.segmenter=blazepose) ;;
    esac
    for mode in naive dsa; do
        convert "${source}_${mode}" "${parser[@]}" --mode "$mode"
    done
    for mode in naive dsa; do
        convert "${source}_${mode}_improved" "${parser[@]}" --mode "$mode" --config configs/benchmarks/improved.toml
        convert "${source}_${mode}_vote" "${parser[@]}" --mode "$mode" --config configs/benchmarks/improved_vote.toml
        if [ "$source" = model ]; then
            # What the parser's probabilities add (recorded label images carry none).
            convert "${source}_${mode}_weighted" "${parser[@]}" --mode "$mode" --config configs/benchmarks/improved_weighted.toml
        fi
    done
done

echo "==> projection study (perfect parser: every wrong point is a DSA error)"
target/release/examples/projection_report 10 > "$work/projection.md"

echo "==> figures"
fig_rec="$work/rec/handover_2005"
for cfg in paper improved blazepose; do
    args=()
    [ "$cfg" = improved ] && args=(--config configs/benchmarks/improved.toml)
    [ "$cfg" = blazepose ] && args=(--parser model --set parsing.segmenter=blazepose)
    "$bodyseg" run --recording "$fig_rec" --out "$work/figure_$cfg" --frame 000012 --figure 000012 \
        --no-label-images -q "${args[@]}" > /dev/null
    mkdir -p docs/images
    cp "$work/figure_$cfg/figures/000012.png" "docs/images/results_$cfg.png"
done

echo "==> regression subset (first seed of each preset, $subset_frames frames)"
subset_reports=()
while read -r preset seed frames; do
    case " ${subset_done:-} " in *" $preset "*) continue ;; esac
    subset_done="${subset_done:-} $preset"
    "$bodyseg" run --recording "$work/rec/${preset}_${seed}" --out "$work/subset/$preset" \
        --limit "$subset_frames" --figure none --no-label-images -q > /dev/null
    subset_reports+=("$work/subset/$preset/report.json")
done <<< "$recordings"
"$bodyseg" eval --merge "${subset_reports[@]}" --format json --out "$work/subset/report.json" -q

elapsed=$(( $(date +%s) - start ))
echo "==> docs/results.md"
# The time of the whole script is stated only for a full run.
timing=("$elapsed")
[ "$sources" = "recorded model blazepose" ] || timing=()
python3 scripts/results_doc.py "$work" "${timing[@]}" > docs/results.md.tmp
mv docs/results.md.tmp docs/results.md
echo "done in ${elapsed} s: docs/results.md"
