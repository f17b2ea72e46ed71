#!/usr/bin/env bash
# Submits a sharded gearbif sweep to SLURM: an array of N shard tasks (sweep_array.sh) and a merge
# job that runs when all of them succeeded. Prints the two job ids.
#
#   scripts/slurm/submit_sweep.sh N OUT [gearbif sweep args...]
#   e.g. scripts/slurm/submit_sweep.sh 37 fig8 --fig8 --tol 1e-9 --settle-tol 1e-8
set -euo pipefail
if [ $# -lt 2 ]; then
    echo "usage: $0 N OUT [gearbif sweep args...]" >&2
    exit 2
fi
N=$1
OUT=$2
shift 2
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
ARRAY=$(sbatch --parsable --array=0-$((N - 1)) --output="$OUT/slurm-%A_%a.out" \
    "$HERE/sweep_array.sh" "$OUT" "$@")
MERGE=$(sbatch --parsable --dependency=afterok:"$ARRAY" --job-name=gearbif-merge \
    --output="$OUT/slurm-merge-%j.out" \
    --wrap="${GEARBIF:-gearbif} sweep merge $(for i in $(seq 0 $((N - 1))); do printf '%s ' "$OUT/shard-$i"; done)--out $OUT/merged")
echo "array job $ARRAY, merge job $MERGE"
