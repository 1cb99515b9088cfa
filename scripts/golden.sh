#!/usr/bin/env bash
# Golden set for behaviour-preserving refactors: every registry solver on a dozen instances
# (TSPLIB SOP, PCGTSPLIB, each generator) at a fixed evaluation budget and seed, recording
# cost, evaluation count, lower bound, proof flag and sequence (never wall-clock figures).
#
#   scripts/golden.sh OUTDIR [BINARY]      # record (BINARY defaults to target/release/cellseq)
#   scripts/golden.sh --compare A B        # identical? (exit 1 and the differences if not)
#
# Record once with the binary of the commit before a refactor, then after every commit with
# the new binary, and compare: costs, evaluation counts and sequences must be identical.
# GOLDEN_JOBS (default 2) runs that many solves at once; GOLDEN_BIG=0 skips the large
# uniform instances (two-level list and linked-list search paths of `local-search`).
set -euo pipefail
cd "$(dirname "$0")/.."

if [[ "${1:-}" == "--compare" ]]; then
    [[ $# -eq 3 ]] || { echo "usage: $0 --compare A B" >&2; exit 2; }
    if diff -r "$2" "$3" >/dev/null; then
        echo "golden: identical ($(ls "$2" | grep -c '\.out$') runs)"
        exit 0
    fi
    echo "golden: DIFFERENT" >&2
    diff -rq "$2" "$3" >&2 || true
    exit 1
fi

[[ $# -ge 1 ]] || { echo "usage: $0 OUTDIR [BINARY] | --compare A B" >&2; exit 2; }
out=$1
bin=${2:-${CARGO_TARGET_DIR:-target}/release/cellseq}
bin=$(realpath "$bin")
mkdir -p "$out/instances"
out=$(realpath "$out")
evals=${GOLDEN_EVALS:-200000}
seed=${GOLDEN_SEED:-7}

small=(
    instances/tsplib-sop/ESC12.sop
    instances/tsplib-sop/br17.10.sop
    instances/tsplib-sop/p43.1.sop
    instances/tsplib-sop/ry48p.1.sop
    instances/tsplib-sop/rbg048a.sop
    instances/tsplib-sop/prob.42.sop
    instances/tsplib-sop/ft70.1.sop
    instances/tsplib-sop/rbg109a.sop
    instances/pcgtsplib/ESC12.pcglns
    instances/pcgtsplib/br17.10.pcglns
    instances/pcgtsplib/p43.1.pcglns
    instances/generated/panel-20.json
    instances/generated/casing-100.json
    instances/generated/cabin-20.json
)
"$bin" generate uniform --param n=150 --param tools=2 --seed 3 -o "$out/instances/uniform-150.json" >/dev/null
small+=("$out/instances/uniform-150.json")

solvers=$("$bin" solvers | grep -E '^[a-z]' | awk '{print $1}')

jobs=()
for f in "${small[@]}"; do
    for s in $solvers; do
        jobs+=("$f|$s|--max-evals $evals")
    done
done
if [[ "${GOLDEN_BIG:-1}" != 0 ]]; then
    "$bin" generate uniform --param n=25000 --param tools=1 --param lift=0 --seed 5 \
        -o "$out/instances/uniform-25000.json" >/dev/null
    "$bin" generate uniform --param n=200000 --param tools=1 --seed 5 \
        -o "$out/instances/uniform-200000.json" >/dev/null
    for f in "$out/instances/uniform-25000.json" "$out/instances/uniform-200000.json"; do
        for s in greedy greedy-edge insertion local-search; do
            jobs+=("$f|$s|--max-evals 2000000 --no-bound")
        done
    done
fi

one() {
    local f s args key
    IFS='|' read -r f s args <<<"$1"
    key="$(basename "$f")__$s"
    # shellcheck disable=SC2086
    if "$bin" solve "$f" --solver "$s" --seed "$seed" $args --json >"$out/$key.raw" 2>"$out/$key.err"; then
        jq -S '{cost, evaluations, lower_bound, proven_optimal, feasible,
                sequence: [.sequence[] | "\(.cell)/\(.mode)"] | join(" ")}' \
            "$out/$key.raw" >"$out/$key.out"
    else
        echo "exit $?: $(cat "$out/$key.err")" >"$out/$key.out"
    fi
    rm -f "$out/$key.raw" "$out/$key.err"
}
export -f one
export bin out seed
printf '%s\n' "${jobs[@]}" | xargs -d '\n' -P "${GOLDEN_JOBS:-2}" -I{} bash -c 'one "$@"' _ {}
rm -rf "$out/instances"
echo "golden: $(ls "$out" | grep -c '\.out$') runs in $out"
