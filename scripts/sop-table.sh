#!/usr/bin/env bash
# Per-instance table (solver x instance: cost, gap, time) on the TSPLIB SOP instances,
# from `cellseq solve --json`. Runs one solve at a time (single thread).
#
# usage: scripts/sop-table.sh [SECONDS] [SOLVER...]
#   env: CELLSEQ=path/to/cellseq (default: target/release/cellseq), SEED (default 1),
#        INSTANCES=dir (default instances/tsplib-sop)
# output: TSV on stdout (solver, instance, n, cost, best_known, gap_percent, elapsed_s),
#         then one summary line per solver (mean gap) on stderr.
set -euo pipefail
limit=${1:-2}
shift || true
solvers=("$@")
[ ${#solvers[@]} -eq 0 ] && solvers=(local-search sa tabu aco)
bin=${CELLSEQ:-target/release/cellseq}
dir=${INSTANCES:-instances/tsplib-sop}
seed=${SEED:-1}
command -v jq >/dev/null || { echo "sop-table.sh: jq is required" >&2; exit 1; }
[ -x "$bin" ] || { echo "sop-table.sh: no executable at $bin (cargo build --release, or set CELLSEQ)" >&2; exit 1; }
printf 'solver\tinstance\tn\tcost\tbest_known\tgap_percent\telapsed_s\n'
for s in "${solvers[@]}"; do
  sum=0; cnt=0
  for f in "$dir"/*.sop; do
    out=$("$bin" solve "$f" --solver "$s" --seed "$seed" --time-limit "$limit" --json)
    line=$(jq -r '[.instance, (.sequence|length), .cost, .best_known, .gap_percent, .elapsed_s] | @tsv' <<<"$out")
    printf '%s\t%s\n' "$s" "$line"
    gap=$(jq -r '.gap_percent // empty' <<<"$out")
    if [ -n "$gap" ]; then sum=$(awk -v a="$sum" -v b="$gap" 'BEGIN{print a+b}'); cnt=$((cnt+1)); fi
  done
  awk -v s="$s" -v a="$sum" -v c="$cnt" -v t="$limit" 'BEGIN{printf "%s: mean gap %.3f %% over %d instances at %s s\n", s, (c?a/c:0), c, t}' >&2
done
