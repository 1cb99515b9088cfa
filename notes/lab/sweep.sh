#!/bin/sh
# Beam proof sweep: one instance at a time, 60 s each. Usage: sh notes/lab/sweep.sh [instances...]
B=${CELLSEQ:-target/release/cellseq}
for i in "$@"; do
  timeout 75 $B solve instances/tsplib-sop/$i.sop --solver beam --time-limit 60 --json --no-bound 2>&1 | python3 -c "
import json,sys
t=sys.stdin.read()
try:
  d=json.loads(t); print(d['instance'], d['cost'], d['best_known'], 'proven' if d['proven_optimal'] else 'open', d['lower_bound'], round(d['elapsed_s'],2))
except Exception: print('$i', 'error', t[:200])"
done
