#!/usr/bin/env bash
# The distributed path (scripts/slurm/) checked on a real Slurm: a private single-node
# cluster started here, in a temporary folder, and stopped again on exit.
#
#   scripts/test_slurm.sh [--beside-real-slurm] [--keep]
#
# Needs root on Debian (apt-get installs slurm-wlm, munge and jq when missing, ~25 s). Not
# part of scripts/test.sh (CI): it needs root, apt and free TCP ports, and it starts
# daemons. It takes about 1 minute on a 2-core machine (see
# docs/notes/2026-12-02-slurm-check.md).
#
# Starts munged (own key and socket), slurmctld and slurmd (own slurm.conf, ports, state,
# spool, pid files and logs; proctrack/linuxproc, task/none: no cgroups, as in a container;
# the node's real CPUs and memory from `slurmd -C`), waits for the node to be idle, then:
#   1. synthesizes a recording with ground truth (handover, 12 frames, seed 3) as a dataset;
#   2. converts it unsharded (bodyseg convert, no Slurm): the reference;
#   3. scripts/slurm/submit_convert.sh 3 ...: a 3-task array and the merge job; every task
#      and the merge complete, and the merged output equals the reference;
#   4. the same into a new folder, with task 1 killed (scancel) once it has completed a
#      frame: the merge fails naming shard 1; a lone `sbatch --array=1` without
#      BODYSEG_SHARDS is refused; task 1 resubmitted with BODYSEG_SHARDS=3 skips the frames
#      it had completed, and the new merge's output equals the reference.
# "Equals the reference": every file byte-identical (diff -r; no stray temporary files),
# report.json and report.md included, at the top and per recording (run*.json and the
# shard reports are left out): convert writes report.md as the tables only and report.json
# with a final newline, exactly what `bodyseg eval --merge` writes.
# Each check prints PASS or FAIL; the script exits 1 at the first failure, with the tails
# of the daemon and job logs.
#
# --beside-real-slurm  run even though a Slurm is configured on this machine (/etc/slurm);
#                      nothing of it is used or touched (own config, key, socket, ports)
# --keep               keep the temporary folder (printed) for inspection
# BODYSEG              the binary (default: target/release/bodyseg of this checkout, else
#                      bodyseg on the PATH)
set -euo pipefail

repo=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
beside_real=0
keep=0
for arg in "$@"; do
    case $arg in
    --beside-real-slurm) beside_real=1 ;;
    --keep) keep=1 ;;
    *)
        echo "usage: $0 [--beside-real-slurm] [--keep]" >&2
        exit 2
        ;;
    esac
done

step() { printf '\n==> %s\n' "$*"; }
pass() { printf 'PASS %s (%d s)\n' "$*" "$((SECONDS - check_start))"; }
fail() {
    printf 'FAIL %s\n' "$*"
    exit 1
}

# --- preconditions --------------------------------------------------------------------
if [ "$(id -u)" != 0 ]; then
    echo "error: run as root (slurmd runs jobs as their user and apt-get installs Slurm)" >&2
    exit 2
fi
if [ "$beside_real" = 0 ]; then
    for conf in /etc/slurm/slurm.conf /etc/slurm-llnl/slurm.conf "${SLURM_CONF:-}"; do
        if [ -n "$conf" ] && [ -e "$conf" ]; then
            echo "error: a Slurm is configured here ($conf); this test starts its own cluster" \
                "beside it only with --beside-real-slurm" >&2
            exit 2
        fi
    done
fi
unset SLURM_CONF

if [ -z "${BODYSEG:-}" ]; then
    if [ -x "$repo/target/release/bodyseg" ]; then
        BODYSEG=$repo/target/release/bodyseg
    else
        BODYSEG=$(command -v bodyseg || true)
    fi
fi
if [ -z "$BODYSEG" ] || [ ! -x "$BODYSEG" ]; then
    echo "error: no bodyseg binary: cargo build --release, or set BODYSEG=/path/to/bodyseg" >&2
    exit 2
fi
BODYSEG=$(realpath "$BODYSEG")
export BODYSEG

step "packages"
missing=()
for pair in slurmctld:slurm-wlm slurmd:slurm-wlm sbatch:slurm-wlm munged:munge jq:jq; do
    command -v "${pair%%:*}" >/dev/null 2>&1 || missing+=("${pair#*:}")
done
if ((${#missing[@]})); then
    mapfile -t missing < <(printf '%s\n' "${missing[@]}" | sort -u)
    echo "installing ${missing[*]}"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends \
        "${missing[@]}" >/dev/null
fi
slurm_version=$(dpkg-query -W -f '${Version}' slurm-wlm 2>/dev/null || slurmctld -V)
munge_version=$(munged --version | head -1)
echo "slurm-wlm $slurm_version, $munge_version, $("$BODYSEG" --version | head -1)"

# --- the private cluster --------------------------------------------------------------
tmp=$(mktemp -d /tmp/bodyseg-slurm.XXXXXX)
chmod 700 "$tmp"
pids=() # daemons started here, stopped in reverse order on exit

# Ends the cluster whatever happened (on failure after printing the logs' tails): jobs
# first, then the daemons, then the temporary folder.
cleanup() {
    local rc=$?
    set +e
    trap - EXIT INT TERM
    if [ "$rc" != 0 ] && [ -d "$tmp" ]; then
        for log in "$tmp"/slurmctld.log "$tmp"/slurmd.log "$tmp"/munged.log; do
            [ -f "$log" ] || continue
            printf '\n--- errors in %s (PMIx left out: no MPI here)\n' "$log"
            grep -iE 'error|fatal' "$log" | grep -v -i pmix | tail -n 10
        done
        # The three job logs written last (their names are ours: no odd characters).
        # shellcheck disable=SC2012
        for log in $(ls -t "$tmp"/work/*.log 2>/dev/null | head -n 3); do
            printf '\n--- tail of %s\n' "$log"
            tail -n 10 "$log"
        done
    fi
    if [ -f "$tmp/slurm.conf" ] && ((${#pids[@]})); then
        # Jobs first: their slurmstepd outlives slurmd.
        SLURM_CONF=$tmp/slurm.conf scancel --quiet --user=root 2>/dev/null
        for _ in $(seq 50); do
            [ -z "$(SLURM_CONF=$tmp/slurm.conf squeue -h -o %i 2>/dev/null)" ] && break
            sleep 0.2
        done
    fi
    local i pid
    for ((i = ${#pids[@]} - 1; i >= 0; i--)); do
        pid=${pids[i]}
        kill "$pid" 2>/dev/null || continue
        for _ in $(seq 50); do
            kill -0 "$pid" 2>/dev/null || break
            sleep 0.2
        done
        kill -9 "$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
    done
    # A job step left behind (its command line names our folder) is ours: end it by id.
    for pid in $(pgrep -f -- "$tmp/" 2>/dev/null); do
        [ "$pid" != $$ ] && kill -9 "$pid" 2>/dev/null
    done
    if [ "$keep" = 1 ]; then
        echo "kept $tmp"
    else
        rm -rf "$tmp"
    fi
    exit "$rc"
}
trap cleanup EXIT
trap 'exit 130' INT TERM

# Sets `port` to a TCP port nobody listens on (a connection to it is refused) other than
# the ones given.
free_port() {
    local p
    for p in $(shuf -i 20000-40000 -n 50); do
        [[ " $* " == *" $p "* ]] && continue
        if ! (exec 3<>"/dev/tcp/127.0.0.1/$p") 2>/dev/null; then
            port=$p
            return
        fi
    done
    fail "no free TCP port found"
}

step "cluster in $tmp"
mkdir -p "$tmp"/{munge,state,spool,work}
chmod 700 "$tmp/munge"
dd if=/dev/urandom of="$tmp/munge/munge.key" bs=1024 count=1 status=none
chmod 400 "$tmp/munge/munge.key"
# -F (foreground) logs to stderr, not --log-file.
munged -F -f --key-file="$tmp/munge/munge.key" --socket="$tmp/munge/munge.socket" \
    --pid-file="$tmp/munge/munged.pid" --seed-file="$tmp/munge/munged.seed" \
    2>"$tmp/munged.log" &
pids+=($!)
for _ in $(seq 50); do
    [ -S "$tmp/munge/munge.socket" ] && break
    sleep 0.1
done
[ -S "$tmp/munge/munge.socket" ] || fail "munged did not start"

node=$(hostname -s)
# e.g. "NodeName=vm CPUs=2 Boards=1 SocketsPerBoard=1 CoresPerSocket=2 ThreadsPerCore=1 RealMemory=24105"
hardware=$(slurmd -C | head -1)
hardware=${hardware#NodeName=* }
free_port
ctld_port=$port
free_port "$ctld_port"
slurmd_port=$port
cat >"$tmp/slurm.conf" <<EOF
# Written by scripts/test_slurm.sh: a private single-node cluster.
ClusterName=bodyseg-test
SlurmctldHost=$node(127.0.0.1)
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket=$tmp/munge/munge.socket
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
SlurmctldDebug=info
SlurmdDebug=info
PlugStackConfig=$tmp/plugstack.conf
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SelectType=select/cons_tres
SelectTypeParameters=CR_Core_Memory
SchedulerType=sched/backfill
MpiDefault=none
MailProg=/bin/true
ReturnToService=2
KillWait=5
MinJobAge=600
NodeName=$node NodeAddr=127.0.0.1 $hardware State=UNKNOWN
PartitionName=test Nodes=$node Default=YES MaxTime=INFINITE State=UP
EOF
: >"$tmp/plugstack.conf"
export SLURM_CONF=$tmp/slurm.conf
# -D: in the foreground of their own process (pids+=), logging to the log files, and to
# stderr as well (kept apart: *.stderr).
slurmctld -D -c -f "$SLURM_CONF" 2>"$tmp/slurmctld.stderr" &
pids+=($!)
slurmd -D -N "$node" -f "$SLURM_CONF" 2>"$tmp/slurmd.stderr" &
pids+=($!)
state=
for _ in $(seq 120); do
    state=$(sinfo -h -n "$node" -o %t 2>/dev/null || true)
    [ "$state" = idle ] && break
    sleep 0.5
done
[ "$state" = idle ] || fail "node $node is not idle after 60 s (sinfo: '$state')"
echo "node $node idle: $hardware; slurmctld port $ctld_port, slurmd port $slurmd_port"
total_start=$SECONDS

# --- helpers --------------------------------------------------------------------------
# Waits until the private cluster has no job left (pending or running), at most 10 minutes.
wait_queue_empty() {
    local start=$SECONDS
    while [ -n "$(squeue -h -o %i)" ]; do
        ((SECONDS - start < 600)) || fail "jobs still queued after 600 s: $(squeue -h)"
        sleep 0.5
    done
}

# Sets `state` to "STATE EXIT" of a job or array task that has ended, e.g. "COMPLETED 0:0"
# (from slurmctld's memory: no accounting database here).
job_state() {
    local line
    line=$(scontrol show job -o "$1") || fail "scontrol show job $1"
    [[ $line =~ JobState=([A-Z_]+) ]] || fail "no JobState for job $1: $line"
    state=${BASH_REMATCH[1]}
    [[ $line =~ ExitCode=([0-9]+:[0-9]+) ]] || fail "no ExitCode for job $1: $line"
    state="$state ${BASH_REMATCH[1]}"
}

expect_state() {
    job_state "$1"
    [ "$state" = "$2" ] || fail "job $1 ended $state, expected $2"
}

# Compares a conversion with the reference conversion (see the header).
same_as_reference() {
    local ref=$1 out=$2
    diff -r -x 'run*.json' -x 'report.shard-*' "$ref" "$out" ||
        fail "$out differs from the unsharded $ref"
    local want got
    want=$(cd "$ref" && find . -name report.json -o -name report.md | sort)
    got=$(cd "$out" && find . -name report.json -o -name report.md | sort)
    [ "$want" = "$got" ] || fail "reports of $out: $(echo "$got" | xargs), expected $(echo "$want" | xargs)"
    [ -n "$want" ] || fail "the reference $ref has no report"
}

# Converts the dataset into $1 with submit_convert.sh, 3 shards of one CPU each; sets
# `array` and `merge` to the job ids.
submit() {
    local line
    line=$(CONVERT_SBATCH_ARGS="--cpus-per-task=1 --mem=1G" \
        "$repo/scripts/slurm/submit_convert.sh" 3 "$dataset" recording "$1") ||
        fail "submit_convert.sh 3 ... $1"
    echo "  $line"
    [[ $line =~ array\ ([0-9]+)\ .*merge\ job\ ([0-9]+)$ ]] || fail "submit_convert.sh said: $line"
    array=${BASH_REMATCH[1]}
    merge=${BASH_REMATCH[2]}
}

cd "$tmp/work" # job logs land here
dataset=$tmp/work/dataset
frames=12

# --- 1. recording -----------------------------------------------------------------------
check_start=$SECONDS
step "1. synthesize a recording"
"$BODYSEG" synth --preset handover --frames "$frames" --seed 3 --no-preview -q \
    --out "$dataset/handover" || fail "1. bodyseg synth"
mapfile -t frame_names < <(find "$dataset/handover/cam0/depth" -name '*.png' -printf '%f\n' | sed 's/\.png$//' | sort)
[ "${#frame_names[@]}" = "$frames" ] || fail "1. $frames frames expected, found ${#frame_names[@]}"
pass "1. synthesized $dataset/handover ($frames frames with ground truth)"

# --- 2. reference -----------------------------------------------------------------------
check_start=$SECONDS
step "2. unsharded conversion"
"$BODYSEG" convert --input "$dataset" --format recording --out "$tmp/work/reference" -q ||
    fail "2. bodyseg convert (unsharded)"
[ -f "$tmp/work/reference/report.json" ] || fail "2. the unsharded conversion wrote no report.json"
pass "2. unsharded conversion into reference/"

# --- 3. array + merge -------------------------------------------------------------------
check_start=$SECONDS
step "3. a 3-task array and the merge job"
submit "$tmp/work/sharded"
wait_queue_empty
for k in 0 1 2; do expect_state "${array}_$k" "COMPLETED 0:0"; done
expect_state "$merge" "COMPLETED 0:0"
for k in 0 1 2; do
    grep -q "shard $k/3 of" "bodyseg-convert-${array}_$k.log" ||
        fail "3. bodyseg-convert-${array}_$k.log does not say shard $k/3"
done
same_as_reference "$tmp/work/reference" "$tmp/work/sharded"
pass "3. array $array (3 tasks) and merge $merge completed; merged output = unsharded"

# --- 4. a task killed and resubmitted ---------------------------------------------------
check_start=$SECONDS
step "4. task 1 killed after a frame, resubmitted alone"
victim=1
victim_frames=()
for ((i = victim; i < frames; i += 3)); do victim_frames+=("${frame_names[i]}"); done

# Frames of the victim shard whose record (written last, once the frame is complete) exists.
complete_frames() {
    local n=0 f
    for f in "${victim_frames[@]}"; do
        [ -f "$1/frames/handover/$f.json" ] && n=$((n + 1))
    done
    echo "$n"
}

done_before=
for attempt in 1 2 3; do
    out=$tmp/work/killed-$attempt
    submit "$out"
    # Stop the task's bodyseg (SIGSTOP) once it has completed a frame, so that it is
    # surely mid-run when cancelled; count its complete frames again once it is gone.
    pid=
    start=$SECONDS
    while ((SECONDS - start < 300)); do
        if [ -z "$pid" ]; then
            pid=$(pgrep -f -- "--out $out --shard $victim/3" | head -1 || true)
        fi
        if [ -n "$pid" ] && (($(complete_frames "$out") >= 1)); then
            kill -STOP "$pid" 2>/dev/null || true
            break
        fi
        sleep 0.02
    done
    [ -n "$pid" ] || fail "4. task ${array}_$victim never started bodyseg"
    stopped_at=$(complete_frames "$out")
    scancel "${array}_$victim"
    wait_queue_empty
    done_before=$(complete_frames "$out")
    echo "  task ${array}_$victim stopped with $stopped_at, cancelled with $done_before of ${#victim_frames[@]} frames complete"
    if ((done_before < ${#victim_frames[@]})); then
        break
    fi
    echo "  attempt $attempt: task $victim had completed all its frames; again"
    done_before=
done
[ -n "$done_before" ] || fail "4. could not cancel task $victim mid-run in 3 attempts"
((done_before >= 1)) || fail "4. task ${array}_$victim completed no frame before it was cancelled"
for k in 0 2; do expect_state "${array}_$k" "COMPLETED 0:0"; done
job_state "${array}_$victim"
[[ $state == CANCELLED* ]] || fail "4. task ${array}_$victim ended $state, expected CANCELLED"
job_state "$merge"
[[ $state == FAILED* ]] || fail "4. merge $merge ended $state with shard $victim missing, expected FAILED"
grep -q "report.shard-$victim-of-3.md is missing" "bodyseg-merge-$merge.log" ||
    fail "4. bodyseg-merge-$merge.log does not name the missing shard $victim"
[ ! -e "$out/report.json" ] || fail "4. the failed merge wrote $out/report.json"
echo "  merge $merge failed: $(grep -m1 missing "bodyseg-merge-$merge.log")"

# A lone task without the shard count is refused before it converts anything.
lone=$(sbatch --parsable --cpus-per-task=1 --mem=1G --array=$victim \
    "$repo/scripts/slurm/convert.sbatch" "$dataset" recording "$out" -q)
wait_queue_empty
expect_state "${lone}_$victim" "FAILED 1:0"
grep -q "BODYSEG_SHARDS" "bodyseg-convert-${lone}_$victim.log" ||
    fail "4. the refused lone task (job $lone) does not say BODYSEG_SHARDS"
[ -z "$(cd "$out" && find . -name '*shard-0-of-1*')" ] || fail "4. the refused lone task wrote a 0/1 shard"
[ "$(complete_frames "$out")" = "$done_before" ] || fail "4. the refused lone task converted frames"
echo "  a lone --array=$victim without BODYSEG_SHARDS (job $lone) was refused"

# The resubmission, as the scripts' headers say.
again=$(BODYSEG_SHARDS=3 sbatch --parsable --cpus-per-task=1 --mem=1G --array=$victim \
    "$repo/scripts/slurm/convert.sbatch" "$dataset" recording "$out")
merge2=$(sbatch --parsable --dependency=afterok:"$again" "$repo/scripts/slurm/merge.sbatch" "$out" 3)
wait_queue_empty
expect_state "${again}_$victim" "COMPLETED 0:0"
expect_state "$merge2" "COMPLETED 0:0"
log=bodyseg-convert-${again}_$victim.log
grep -q "shard $victim/3 of" "$log" || fail "4. $log does not say shard $victim/3"
grep -q "$done_before skipped as complete" "$log" ||
    fail "4. $log does not say $done_before skipped as complete"
echo "  $log: $(grep -m1 'skipped as complete' "$log")"
run=$out/run.shard-$victim-of-3.json
skipped=$(jq .skipped "$run")
processed=$(jq .processed "$run")
[ "$skipped" = "$done_before" ] ||
    fail "4. the resubmitted task skipped $skipped frames, $done_before were complete ($run)"
[ "$processed" = $((${#victim_frames[@]} - done_before)) ] ||
    fail "4. the resubmitted task processed $processed frames, expected $((${#victim_frames[@]} - done_before))"
same_as_reference "$tmp/work/reference" "$out"
pass "4. task $victim cancelled after $done_before frames; resubmitted (job $again) it skipped $skipped and processed $processed; merge $merge2 output = unsharded"

printf '\nall Slurm checks passed in %d s (cluster up to done; %d s in all)\n' \
    "$((SECONDS - total_start))" "$SECONDS"
