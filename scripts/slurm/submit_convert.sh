#!/bin/bash
# Converts a dataset on a Slurm cluster: N array tasks (one shard each) and a merge job
# that runs when they have all ended.
#
#   scripts/slurm/submit_convert.sh N INPUT FORMAT OUT [bodyseg convert flags]
#   e.g. scripts/slurm/submit_convert.sh 16 /data/recs recording /scratch/converted
#
# Set BODYSEG=/path/to/bodyseg when it is not on the PATH of the compute nodes.
set -euo pipefail
if [ $# -lt 4 ]; then
    echo "usage: $0 N INPUT FORMAT OUT [bodyseg convert flags]" >&2
    exit 1
fi
N=$1
shift
OUT=$3
here=$(cd "$(dirname "$0")" && pwd)
array=$(sbatch --parsable --export=ALL --array=0-$((N - 1)) "$here/convert.sbatch" "$@")
merge=$(sbatch --parsable --export=ALL --dependency=afterany:"$array" "$here/merge.sbatch" "$OUT" "$N")
echo "submitted conversion array $array ($N shards) and merge job $merge"
