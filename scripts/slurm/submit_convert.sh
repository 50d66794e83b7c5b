#!/bin/bash
# Converts a dataset on a Slurm cluster: N array tasks (one shard each) and a merge job
# that runs when they have all ended.
#
#   scripts/slurm/submit_convert.sh N INPUT FORMAT OUT [bodyseg convert flags]
#   e.g. scripts/slurm/submit_convert.sh 16 /data/recs recording /scratch/converted
#
# Set BODYSEG=/path/to/bodyseg when it is not on the PATH of the compute nodes, and
# CONVERT_SBATCH_ARGS to override the array's resources of convert.sbatch, e.g.
# CONVERT_SBATCH_ARGS="--cpus-per-task=4 --mem=4G" (split on spaces). The tasks get
# BODYSEG_SHARDS=N, so a task that died is redone alone with
#   BODYSEG_SHARDS=N sbatch --array=K scripts/slurm/convert.sbatch INPUT FORMAT OUT [flags]
# followed by a new merge job (sbatch --dependency=afterok:JOB scripts/slurm/merge.sbatch OUT N).
set -euo pipefail
if [ $# -lt 4 ]; then
    echo "usage: $0 N INPUT FORMAT OUT [bodyseg convert flags]" >&2
    exit 1
fi
N=$1
shift
OUT=$3
if ! [[ "$N" =~ ^[1-9][0-9]*$ ]]; then
    echo "error: N must be a positive number of shards, got '$N'" >&2
    exit 1
fi
here=$(cd "$(dirname "$0")" && pwd)
read -r -a extra <<<"${CONVERT_SBATCH_ARGS:-}"
array=$(sbatch --parsable --export=ALL,BODYSEG_SHARDS="$N" "${extra[@]}" --array=0-$((N - 1)) \
    "$here/convert.sbatch" "$@")
array=${array%%;*} # --parsable prints JOBID;CLUSTER on a federation
merge=$(sbatch --parsable --export=ALL --dependency=afterany:"$array" "$here/merge.sbatch" "$OUT" "$N")
merge=${merge%%;*}
echo "submitted conversion array $array ($N shards) and merge job $merge"
