#!/bin/bash
# Submits a sharded campaign and its merge step:  scripts/slurm/submit.sh PLAN.toml OUT_DIR N
set -euo pipefail
PLAN=${1:?usage: submit.sh PLAN.toml OUT_DIR N}
OUT=${2:?usage: submit.sh PLAN.toml OUT_DIR N}
N=${3:?usage: submit.sh PLAN.toml OUT_DIR N}
DIR=$(cd "$(dirname "$0")" && pwd)
"${CELLSEQ:-cellseq}" check "$PLAN"
JOB=$(N=$N sbatch --parsable --export=ALL,N="$N" --array=1-"$N" "$DIR/run-array.sbatch" "$PLAN" "$OUT")
sbatch --dependency=afterok:"$JOB" "$DIR/merge.sbatch" "$OUT"
echo "submitted array job $JOB ($N shards) and its merge step"
