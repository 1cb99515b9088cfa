#!/usr/bin/env bash
# Measures [profile.release] variants against the committed profile: the cost of the builds
# (wall and user CPU time) and the user CPU time of fixed-evaluation solver runs, variants
# interleaved (A B C A B C ...) so that drifting machine load hits all of them alike. The runs
# are deterministic (--max-evals, --seed, one thread), so each variant must print the same
# cost and evaluation count; the script records both so that this can be checked.
#
# usage: bash notes/lab/release-profile.sh [OUT_DIR]      (default /tmp/cellseq-profile)
#   PHASES="build runs" (default both; "summary" prints the base/cgu1 table of runs.tsv), VARIANTS="base cgu1 thin" (default), ROUNDS=5.
# Variants (set through cargo's --config and CARGO_PROFILE_RELEASE_* variables, so Cargo.toml
# is left alone): base = the committed profile; cgu1 = codegen-units = 1 for the cellseq crate
# only (its target directory starts as a copy of base's, so only cellseq recompiles and the
# dependencies are shared); thin = lto = "thin"; fat = lto = "fat" with codegen-units = 1.
# Each variant builds a `git archive` of HEAD in its own target directory.
# Output: OUT_DIR/build.tsv (variant, step, wall s, user s, sys s, load) and OUT_DIR/runs.tsv
# (round, variant, instance, solver, evals, user s, cost, evaluations).
set -u
OUT=${1:-/tmp/cellseq-profile}
OUT=$(realpath -m "$OUT")
PHASES=${PHASES:-build runs}
VARIANTS=${VARIANTS:-base cgu1 thin}
ROUNDS=${ROUNDS:-5}
mkdir -p "$OUT"
if [ ! -d "$OUT/src" ]; then
  mkdir -p "$OUT/src"
  git archive HEAD | tar -x -C "$OUT/src"
  git rev-parse HEAD > "$OUT/commit"
fi
cd "$OUT/src"
CFG=()
variant_env() {
  CFG=()
  unset CARGO_PROFILE_RELEASE_LTO CARGO_PROFILE_RELEASE_CODEGEN_UNITS
  case $1 in
    base) ;;
    cgu1) CFG=(--config 'profile.release.package.cellseq.codegen-units=1') ;;
    thin) export CARGO_PROFILE_RELEASE_LTO=thin ;;
    fat) export CARGO_PROFILE_RELEASE_LTO=fat CARGO_PROFILE_RELEASE_CODEGEN_UNITS=1 ;;
    *) echo "unknown variant $1" >&2; exit 2 ;;
  esac
  export CARGO_TARGET_DIR="$OUT/target-$1"
}
ld() { cut -d' ' -f1 /proc/loadavg; }
# timed VARIANT STEP CMD...: one row of build.tsv
timed() {
  local v=$1 step=$2; shift 2
  local l; l=$(ld)
  /usr/bin/time -o "$OUT/time.tmp" -f "%e	%U	%S" "$@" >/dev/null 2>>"$OUT/build.err" || echo "FAILED: $v $step" >> "$OUT/build.err"
  printf '%s\t%s\t%s\t%s\n' "$v" "$step" "$(cat "$OUT/time.tmp")" "$l" >> "$OUT/build.tsv"
}
build_variant() {
  variant_env "$1"
  if [ "$1" = cgu1 ] && [ -d "$OUT/target-base" ] && [ ! -d "$CARGO_TARGET_DIR" ]; then
    cp -a "$OUT/target-base" "$CARGO_TARGET_DIR"
  fi
  timed "$1" "cellseq binary (from scratch; cgu1: from base's dependencies)" \
    nice cargo build "${CFG[@]}" --release --bin cellseq
  touch src/lib.rs
  timed "$1" "cellseq crate only (lib + bin)" nice cargo build "${CFG[@]}" --release --bin cellseq
  timed "$1" "test binaries after the binary (cargo test --release --no-run)" \
    nice cargo test "${CFG[@]}" --release --no-run
  touch src/lib.rs
  timed "$1" "test binaries, cellseq crate only (touch src/lib.rs)" \
    nice cargo test "${CFG[@]}" --release --no-run
}
# instance solver max-evals: each run takes about 2-5 s of user time on a quiet machine
RUNS=(
  "instances/tsplib-sop/ft70.1.sop ils 2e8"
  "instances/tsplib-sop/ft70.1.sop atsp 5e7"
  "instances/tsplib-sop/ft70.1.sop auto 1e6"
  "instances/tsplib-sop/kro124p.2.sop eacs 1e8"
  "instances/tsplib-sop/kro124p.2.sop local-search 1e8"
  "instances/generated/panel-1000.json ils 1e8"
  "instances/generated/panel-1000.json eacs 5e7"
  "instances/generated/panel-1000.json local-search 1e8"
  "instances/generated/panel-1000.json auto 5e7"
  "instances/pcgtsplib/rbg150a.pcglns ils 1e8"
  "instances/pcgtsplib/rbg150a.pcglns eacs 1e8"
)
one_run() { # round variant instance solver evals
  local bin="$OUT/target-$2/release/cellseq"
  RAYON_NUM_THREADS=1 /usr/bin/time -o "$OUT/time.tmp" -f "%U" nice "$bin" solve "$3" \
    --solver "$4" --max-evals "$5" --seed 1 --no-bound --json > "$OUT/run.json" 2>/dev/null
  local res
  res=$(python3 -c "import json,sys; j=json.load(open(sys.argv[1])); print(j['cost'], j['evaluations'], sep='\t')" "$OUT/run.json")
  printf '%s\t%s\t%s\t%s\t%s\t%s\t%s\n' "$1" "$2" "$3" "$4" "$5" "$(cat "$OUT/time.tmp")" "$res" >> "$OUT/runs.tsv"
}
case " $PHASES " in *" build "*)
  for v in $VARIANTS; do build_variant "$v"; done ;;
esac
case " $PHASES " in *" runs "*)
  for round in $(seq 1 "$ROUNDS"); do
    for r in "${RUNS[@]}"; do
      set -- $r
      for v in $VARIANTS; do one_run "$round" "$v" "$1" "$2" "$3"; done
    done
  done ;;
esac
case " $PHASES " in *" summary "*)
  # medians per run kind, base against cgu1 (the table in release-profile.md)
  python3 - "$OUT/runs.tsv" <<'PY'
import sys, collections, statistics as st
rows=[l.rstrip('\n').split('\t') for l in open(sys.argv[1]) if l.strip()]
t=collections.defaultdict(lambda: collections.defaultdict(list)); res=collections.defaultdict(set)
rounds=collections.defaultdict(set)
for r,v,inst,s,ev,u,cost,evals in rows:
    k=(inst.split('/')[-1],s,ev); t[k][v].append(float(u)); res[k].add((cost,evals)); rounds[k].add(r)
tb=tc=0; ratios=[]
print('| instance | solver | --max-evals | runs | base user s (median) | cgu1 user s (median) | cgu1/base | same cost and evaluations |')
print('|---|---|---|---|---|---|---|---|')
for k in t:
    b=t[k]['base']; c=t[k].get('cgu1',[])
    n=min(len(b),len(c))
    if n==0: continue
    b,c=b[:n],c[:n]
    mb,mc=st.median(b),st.median(c); ratios.append(mc/mb); tb+=sum(b); tc+=sum(c)
    print(f'| {k[0]} | {k[1]} | {k[2]} | {n}+{n} | {mb:.2f} | {mc:.2f} | {mc/mb:.3f} | {"yes" if len(res[k])==1 else "NO: "+str(res[k])} |')
import math
g=math.exp(sum(map(math.log,ratios))/len(ratios))
print(f'\ngeometric mean of the median ratios cgu1/base: {g:.3f} over {len(ratios)} runs kinds; total user s base {tb:.1f}, cgu1 {tc:.1f} ({tc/tb:.3f})')
PY
  ;;
esac
echo "done $(date -u +%H:%M:%S)" >> "$OUT/build.tsv"
