#!/usr/bin/env bash
# Writes the instance families (docs/families.md): the training set into OUTDIR/train and a
# held-back part with other seeds into OUTDIR/heldback.
#
# usage: scripts/families.sh OUTDIR [--quick]
#   CELLSEQ=path/to/cellseq (default target/release/cellseq)
#   --quick: only n <= 500 and one seed per part (118 files per part, about 170 MB in all)
#
# SOP-shaped matrix families are written as TSPLIB SOP (.sop, readable by LKH-3 through
# scripts/peers/lkh_sop.py); geometric-sparse and generalized as cellseq JSON.
# The same binary, list and seeds give byte-identical files.
set -euo pipefail
OUT=${1:?usage: scripts/families.sh OUTDIR [--quick]}
QUICK=${2:-}
B=${CELLSEQ:-target/release/cellseq}
[ -x "$B" ] || { echo "no cellseq binary at $B (cargo build --release, or set CELLSEQ)" >&2; exit 1; }

TRAIN_SEEDS="1 2"
HELD_SEEDS="1001 1002"
SIZES="50 200 500 1000"
if [ "$QUICK" = "--quick" ]; then
  TRAIN_SEEDS="1"; HELD_SEEDS="1001"; SIZES="50 200 500"
fi

gen() { # part seed kind ext params...
  local part=$1 seed=$2 kind=$3 ext=$4; shift 4
  local tag; tag=$(printf '%s' "$*" | tr ' =' '_-')
  local f="$OUT/$part/$kind${tag:+_$tag}_s$seed.$ext"
  local args=(); for kv in "$@"; do args+=(--param "$kv"); done
  "$B" generate "$kind" "${args[@]}" --seed "$seed" -o "$f" > /dev/null
}

part() { # part seeds
  local part=$1 seeds=$2
  mkdir -p "$OUT/$part"
  for s in $seeds; do
    for n in $SIZES; do
      for c in 100 1000; do
        for p in 0 1 5 15 30 60; do gen "$part" "$s" random-sop sop n=$n c=$c p=$p; done
      done
      [ "$n" -ge 200 ] || continue
      [ "$n" -le 500 ] || continue
      for cls in amat tmat; do gen "$part" "$s" atsp sop n=$n c=100 class=$cls; done
      for p in 0 15; do
        gen "$part" "$s" symmetric sop n=$n c=1000 p=$p
        gen "$part" "$s" near-symmetric sop n=$n c=1000 p=$p asym=5
      done
    done
    for n in 100 200 300 435; do
      for ch in 2 3 4; do gen "$part" "$s" compiler-dag sop n=$n chains=$ch; done
    done
    # small asymmetric instances with medium and dense precedence (closure density 0.3-0.9,
    # n <= 60: a region the families above leave empty)
    for n in 20 40 60; do
      for p in 30 60 85; do
        gen "$part" "$s" near-symmetric sop n=$n c=1000 p=$p asym=5
        gen "$part" "$s" random-sop sop n=$n c=10 p=$p
      done
    done
    # asymmetric instances with dense precedence (closure density 0.8-0.95), where the
    # `dense` rule's plan was raced (notes/lab/dense-race.md); c alternates between 1000 and 100
    local i=0
    for n in 150 250 350 450; do
      for p in 80 90 95; do
        i=$((i + 1))
        gen "$part" "$s" random-sop sop n=$n c=$(( i % 2 ? 1000 : 100 )) p=$p
      done
    done
    # crane jobs in time windows (precedence an interval order, closure density 0.7-0.99):
    # the dense rule's beam bound was raced here (notes/lab/time-window-race.md)
    for n in 150 250 350 450 600 800 1000; do
      [ "$QUICK" = "--quick" ] && [ "$n" -gt 500 ] && continue
      for w in 5 20; do gen "$part" "$s" time-window sop n=$n w=$w c=100; done
    done
    for n in 50 100 200; do
      for p in 0 15; do gen "$part" "$s" generalized json n=$n p=$p modes=4; done
      # half the cells open features cut either way: asymmetric costs, several modes per
      # cell, sparse precedence (the `sparse` rule's instances with modes > 1)
      for p in 1 5 15 30; do gen "$part" "$s" generalized json n=$n p=$p modes=4 open=0.5; done
    done
    for n in 1000 10000; do gen "$part" "$s" geometric-sparse json n=$n; done
    [ "$QUICK" = "--quick" ] || gen "$part" "$s" geometric-sparse json n=100000
  done
  echo "$part: $(ls "$OUT/$part" | wc -l) files in $OUT/$part"
}

part train "$TRAIN_SEEDS"
part heldback "$HELD_SEEDS"
