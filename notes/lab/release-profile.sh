#!/usr/bin/env bash
# Measures [profile.release] variants against the current profile: build times and the
# criterion benches, baseline and variant side by side, in rounds so that drifting load hits
# both. Run it on a quiet machine: it makes four release builds from scratch (a quiet 2-core
# machine needs about 4.5 min for one of the current profile) plus the bench runs.
#
# usage: bash notes/lab/release-profile.sh [OUT_DIR]      (default /tmp/cellseq-profile)
# Variants: base (the committed profile), cgu1 (codegen-units = 1 for the cellseq crate
# only; the dependencies compile as in base), thin (lto = "thin" and codegen-units = 1 everywhere),
# fat (lto = "fat" and codegen-units = 1). Each builds from a copy of HEAD in its own target
# directory, so the working tree and its target/ are left alone.
# Output: OUT_DIR/build.txt (wall seconds per build step, with the load average) and
# OUT_DIR/bench-ROUND-VARIANT.txt (criterion's time lines).
set -u
OUT=${1:-/tmp/cellseq-profile}
mkdir -p "$OUT/src"
git archive HEAD | tar -x -C "$OUT/src"
cd "$OUT/src"
CFG=()
variant_env() {
  CFG=()
  unset CARGO_PROFILE_RELEASE_LTO CARGO_PROFILE_RELEASE_CODEGEN_UNITS CARGO_PROFILE_BENCH_LTO CARGO_PROFILE_BENCH_CODEGEN_UNITS
  case $1 in
    base) ;;
    cgu1) CFG=(--config 'profile.release.package.cellseq.codegen-units=1' --config 'profile.bench.package.cellseq.codegen-units=1') ;;
    thin) export CARGO_PROFILE_RELEASE_LTO=thin CARGO_PROFILE_RELEASE_CODEGEN_UNITS=1 CARGO_PROFILE_BENCH_LTO=thin CARGO_PROFILE_BENCH_CODEGEN_UNITS=1 ;;
    fat)  export CARGO_PROFILE_RELEASE_LTO=fat CARGO_PROFILE_RELEASE_CODEGEN_UNITS=1 CARGO_PROFILE_BENCH_LTO=fat CARGO_PROFILE_BENCH_CODEGEN_UNITS=1 ;;
  esac
  export CARGO_TARGET_DIR="$OUT/target-$1"
}
t() { local s; s=$(date +%s.%N); "$@" >/dev/null 2>>"$OUT/build.err"; local rc=$?; echo "$(echo "$(date +%s.%N) - $s" | bc) s rc=$rc"; }
ld() { cut -d' ' -f1-3 /proc/loadavg; }
BENCHES="--bench engine --bench core --bench end_to_end"
build_variant() {
  variant_env "$1"
  echo "$1 release build from scratch, load $(ld): $(t nice cargo build "${CFG[@]}" --release)" >> "$OUT/build.txt"
  echo "$1 bench binaries, load $(ld): $(t nice cargo bench "${CFG[@]}" --no-run $BENCHES)" >> "$OUT/build.txt"
  touch src/lib.rs
  echo "$1 cellseq crate only (lib + bin), load $(ld): $(t nice cargo build "${CFG[@]}" --release)" >> "$OUT/build.txt"
}
bench_variant() {
  variant_env "$2"
  {
    echo "=== round $1 variant $2 $(date -u +%H:%M:%S) load $(ld)"
    nice cargo bench "${CFG[@]}" --bench engine -- --noplot 2>&1 | grep -E "^engine|time:|thrpt:"
    nice cargo bench "${CFG[@]}" --bench core -- --noplot "evaluate|greedy/uniform_100k|sparse_precedence_100k/insertion" 2>&1 | grep -E "^(evaluate|greedy|sparse)|time:"
    nice cargo bench "${CFG[@]}" --bench end_to_end -- --noplot "end_to_end_n60/(ils|eacs|beam|local-search)$" 2>&1 | grep -E "^end_to_end|time:"
    echo "=== end $(date -u +%H:%M:%S) load $(ld)"
  } >> "$OUT/bench-$1-$2.txt" 2>&1
}
VARIANTS=${VARIANTS:-base cgu1 thin fat}
for v in $VARIANTS; do build_variant "$v"; done
for round in 1 2; do for v in $VARIANTS; do bench_variant "$round" "$v"; done; done
echo "done $(date -u +%H:%M:%S)" >> "$OUT/build.txt"
