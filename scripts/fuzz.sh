#!/usr/bin/env bash
# Coverage-guided fuzzing of bodyseg's file readers and configuration parser with
# libFuzzer, on stable Rust (fuzz/README.md).
#
#   scripts/fuzz.sh SECONDS [TARGET...]     each target (default: all) for SECONDS
#   scripts/fuzz.sh --list                  the targets
#
# Builds fuzz/ (its own workspace, target dir fuzz/target/) in release with overflow
# checks and debug assertions, instrumented for libFuzzer with stable -C flags: no nightly
# toolchain, no RUSTC_BOOTSTRAP, no cargo-fuzz install. libfuzzer-sys compiles libFuzzer
# itself (C++, with the machine's g++) on the first build.
#
# Each target starts from its committed seeds (fuzz/corpus/TARGET/) and crash regressions
# (fuzz/regressions/TARGET/), read only; what it learns goes to fuzz/target/corpus/TARGET/
# (kept between runs, ignored by git). Limits: 2048 MB resident (-rss_limit_mb), 2 GiB
# live heap (fuzz/src/alloc_limit.rs: a reservation that is never touched counts too),
# 10 s per input (-timeout: a hang). A crash, hang or memory failure saves its input
# under fuzz/artifacts/TARGET/, prints the command that replays it, and makes the script
# exit 1 after the other targets ran. Prints runs and runs/s per target, and the total.
#
# On a shared machine: nice -n 19 scripts/fuzz.sh 150
set -euo pipefail

cd "$(dirname "${BASH_SOURCE[0]}")/.."

# One target per fuzz/fuzz_targets/NAME.rs.
targets_all=()
for f in fuzz/fuzz_targets/*.rs; do
    targets_all+=("$(basename "$f" .rs)")
done

if [[ "${1:-}" == "--list" ]]; then
    printf '%s\n' "${targets_all[@]}"
    exit 0
fi
if [[ ! "${1:-}" =~ ^[0-9]+$ ]]; then
    echo "usage: scripts/fuzz.sh SECONDS [TARGET...]   (targets: ${targets_all[*]})" >&2
    exit 2
fi
seconds=$1
shift
targets=("$@")
if ((${#targets[@]} == 0)); then
    targets=("${targets_all[@]}")
fi
for t in "${targets[@]}"; do
    if [[ ! " ${targets_all[*]} " =~ " $t " ]]; then
        echo "unknown target '$t' (targets: ${targets_all[*]})" >&2
        exit 2
    fi
    if [[ -z "$(ls -A "fuzz/corpus/$t" 2>/dev/null)" ]]; then
        echo "fuzz/corpus/$t/ has no seed (python3 fuzz/gen_seeds.py writes them)" >&2
        exit 2
    fi
done

triple=$(rustc -vV | sed -n 's/^host: //p')
# What cargo-fuzz passes for `--sanitizer none`: SanitizerCoverage's inline 8-bit
# counters, PC table and comparison tracing, which libFuzzer reads. All stable -C flags.
# --target keeps them off build scripts and proc macros.
export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing"
bins=()
for t in "${targets[@]}"; do bins+=(--bin "$t"); done
echo "==> building fuzz targets (fuzz/target/$triple/release/)"
build_start=$SECONDS
cargo build --manifest-path fuzz/Cargo.toml --release --target "$triple" "${bins[@]}"
echo "built in $((SECONDS - build_start)) s"

failed=()
total_runs=0
summary=()
for t in "${targets[@]}"; do
    work="fuzz/target/corpus/$t"
    artifacts="fuzz/artifacts/$t"
    mkdir -p "$work" "$artifacts" "fuzz/regressions/$t"
    log="fuzz/target/fuzz-$t.log"
    echo "==> $t for $seconds s"
    status=0
    "fuzz/target/$triple/release/$t" \
        -max_total_time="$seconds" -timeout=10 \
        -rss_limit_mb=2048 -malloc_limit_mb=2048 \
        -print_final_stats=1 -artifact_prefix="$artifacts/" \
        "$work" "fuzz/corpus/$t" "fuzz/regressions/$t" >"$log" 2>&1 || status=$?
    runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n 1)
    per_s=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -n 1)
    runs=${runs:-0}
    total_runs=$((total_runs + runs))
    if ((status != 0)); then
        failed+=("$t")
        tail -n 40 "$log"
        crash=$(ls -t "$artifacts" 2>/dev/null | head -n 1)
        echo "$t FAILED (exit $status) after $runs runs; input: $artifacts/$crash"
        echo "  replay: fuzz/target/$triple/release/$t $artifacts/$crash"
        summary+=("$(printf '%-16s FAILED after %s runs' "$t" "$runs")")
    else
        summary+=("$(printf '%-16s %10s runs  %6s runs/s' "$t" "$runs" "${per_s:-?}")")
    fi
done

echo
echo "==> fuzz summary (${seconds} s per target)"
printf '%s\n' "${summary[@]}"
echo "total: $total_runs runs over ${#targets[@]} targets"
if ((${#failed[@]})); then
    echo "failed: ${failed[*]} (inputs under fuzz/artifacts/; each becomes a regression test, fuzz/README.md)" >&2
    exit 1
fi
