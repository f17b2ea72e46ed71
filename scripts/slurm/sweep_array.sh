#!/usr/bin/env bash
# One task of a SLURM job array computing one shard of a gearbif sweep: task i of an array
# 0..N-1 runs `gearbif sweep ARGS --shard i/N --out OUT/shard-i` (resumable: a requeued or
# resubmitted task continues from its checkpoint). Merge when all tasks are done:
# `gearbif sweep merge OUT/shard-* --out OUT/merged` (scripts/slurm/submit_sweep.sh submits both).
#
#   sbatch --array=0-7 scripts/slurm/sweep_array.sh OUT --fig8 --tol 1e-9 --settle-tol 1e-8
#
# GEARBIF: path of the gearbif binary (default: gearbif on PATH). Each task uses the CPUs SLURM
# gives it (--cpus-per-task) for the rows of its shard.
#SBATCH --job-name=gearbif-sweep
#SBATCH --cpus-per-task=1
#SBATCH --output=slurm-%A_%a.out
set -euo pipefail

if [ $# -lt 1 ] || [ -z "${SLURM_ARRAY_TASK_ID:-}" ]; then
    echo "usage: sbatch --array=0-(N-1) $0 OUT [gearbif sweep args...]" >&2
    exit 2
fi
if [ "${SLURM_ARRAY_TASK_MIN:-0}" -ne 0 ]; then
    echo "the array must start at 0 (--array=0-(N-1))" >&2
    exit 2
fi
OUT=$1
shift
N=$((SLURM_ARRAY_TASK_MAX + 1))
I=$SLURM_ARRAY_TASK_ID
export RAYON_NUM_THREADS=${SLURM_CPUS_PER_TASK:-1}
mkdir -p "$OUT"
exec "${GEARBIF:-gearbif}" sweep "$@" --quiet --shard "$I/$N" --out "$OUT/shard-$I"
