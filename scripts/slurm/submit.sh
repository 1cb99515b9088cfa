#!/bin/bash
# Submits a sharded cellseq campaign to SLURM: an array job of N shards (run-array.sbatch, one
# `cellseq run --shard I/N` per task) and a merge step that runs after all of them succeeded
# (merge.sbatch: `cellseq merge` then `cellseq report`). Prints the two job ids.
#
#   scripts/slurm/submit.sh PLAN.toml OUT_DIR N [extra sbatch options for both jobs...]
#
# Environment (all optional):
#   CELLSEQ         the binary (default: `cellseq` on PATH, else target/release/cellseq here)
#   CPUS_PER_TASK   threads per shard (default 4)
#   TIME_PER_SHARD  time limit of one shard, e.g. 01:30:00 (default: run-array.sbatch's 02:00:00);
#                   `cellseq check PLAN --shards N --threads CPUS_PER_TASK` prints an estimate
#   PARTITION       partition of both jobs (default: the cluster's default partition)
#   SUBMIT_WAIT=1   wait until the merge step ends and exit with its status (sbatch --wait)
# SLURM's own input variables (SBATCH_ACCOUNT, SBATCH_QOS, ...) apply as usual.
set -euo pipefail
usage="usage: submit.sh PLAN.toml OUT_DIR N [sbatch options...]"
PLAN=${1:?$usage}
OUT=${2:?$usage}
N=${3:?$usage}
shift 3
case $N in
'' | *[!0-9]* | 0) echo "submit.sh: N must be a whole number >= 1, not '$N'" >&2; exit 2 ;;
esac
DIR=$(cd "$(dirname "$0")" && pwd)
if [ -z "${CELLSEQ:-}" ]; then
    if command -v cellseq >/dev/null; then
        CELLSEQ=$(command -v cellseq)
    else
        CELLSEQ=$(cd "$DIR/../.." && pwd)/target/release/cellseq
    fi
fi
[ -x "$CELLSEQ" ] || { echo "submit.sh: no cellseq binary at $CELLSEQ (set CELLSEQ)" >&2; exit 2; }
# the jobs may start in another shell on another node: pass absolute paths
CELLSEQ=$(cd "$(dirname "$CELLSEQ")" && pwd)/$(basename "$CELLSEQ")
export CELLSEQ
"$CELLSEQ" check "$PLAN"
mkdir -p "$OUT"

common=("$@")
[ -n "${PARTITION:-}" ] && common+=(--partition="$PARTITION")
array=(--cpus-per-task="${CPUS_PER_TASK:-4}")
[ -n "${TIME_PER_SHARD:-}" ] && array+=(--time="$TIME_PER_SHARD")

JOB=$(sbatch --parsable --export=ALL,N="$N",CELLSEQ="$CELLSEQ" --array=1-"$N" \
    "${array[@]}" "${common[@]}" "$DIR/run-array.sbatch" "$PLAN" "$OUT")
JOB=${JOB%%;*}
echo "array job $JOB: $N shards of $PLAN into $OUT"
merge=(--parsable --export=ALL,CELLSEQ="$CELLSEQ" --dependency=afterok:"$JOB"
    --kill-on-invalid-dep=yes "${common[@]}")
if [ "${SUBMIT_WAIT:-0}" = 1 ]; then
    # --wait prints the id only at the end; the merge step's status becomes ours
    echo "merge job after $JOB (waiting for it)"
    rc=0
    MJOB=$(sbatch --wait "${merge[@]}" "$DIR/merge.sbatch" "$OUT") || rc=$?
    MJOB=${MJOB%%;*}
    # a merge step cancelled because a shard failed can end with status 0: ask for its state
    state=$(scontrol show job "$MJOB" 2>/dev/null | grep -o 'JobState=[A-Z_]*' | cut -d= -f2 || true)
    echo "merge job $MJOB ended: ${state:-state no longer known}, status $rc"
    if [ "$rc" -eq 0 ] && [ -n "$state" ] && [ "$state" != COMPLETED ]; then
        echo "submit.sh: the merge step did not run ($state): a shard failed; see its slurm-${JOB}_*.out" >&2
        rc=1
    fi
    exit "$rc"
else
    MJOB=$(sbatch "${merge[@]}" "$DIR/merge.sbatch" "$OUT")
    echo "merge job ${MJOB%%;*} after $JOB"
fi
