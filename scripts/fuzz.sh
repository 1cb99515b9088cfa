#!/usr/bin/env bash
# Runs every cargo-fuzz target (fuzz/fuzz_targets/) for SECONDS each, one after the other,
# from seed corpora built out of the repository's own files, and prints per target the
# executions and the crashes, timeouts and out-of-memory inputs found.
#
#   scripts/fuzz.sh [SECONDS] [TARGET...]        default 120 s, every target
#   FUZZ_PARALLEL=2 scripts/fuzz.sh 600          two targets at a time
#
# Needs nightly and cargo-fuzz (`cargo install cargo-fuzz`). Limits per input: 10 s, 4 GB RSS.
# Findings land in fuzz/artifacts/TARGET/ (replay: cargo +nightly fuzz run TARGET FILE);
# logs in fuzz/logs/. fuzz/corpus, artifacts and logs are not committed.
set -euo pipefail
cd "$(dirname "$0")/.."
secs=${1:-120}
shift || true
all=(sop pcglns pcgtsp json_instance json_solution gcode svg dxf plan optimize_gcode optimize_drawing)
targets=("$@")
[ ${#targets[@]} -eq 0 ] && targets=("${all[@]}")
parallel=${FUZZ_PARALLEL:-1}
export CARGO_TARGET_DIR=${FUZZ_TARGET_DIR:-$PWD/fuzz/target}

# seed corpus of a target: repository files with the given name endings, at most 40 of at
# most 64 KB each (small inputs mutate faster), plus fuzz/seeds
seed() {
  local t=$1 dirs=$2 pat=$3 dir=fuzz/corpus/$1
  mkdir -p "$dir"
  # shellcheck disable=SC2086
  find $dirs -type f -size -64k 2>/dev/null | grep -E "$pat" | sort | head -40 |
    while read -r f; do cp -n "$f" "$dir/seed-$(echo "$f" | tr '/' '_')"; done
}
seed sop "instances/tsplib-sop fuzz/seeds" '\.sop$'
seed pcglns "instances/pcgtsplib fuzz/seeds" '\.pcglns$'
seed pcgtsp "tests/fixtures/pcgtsp fuzz/seeds" '\.pcgtsp$'
seed json_instance "instances/generated fuzz/seeds/json" '\.json$'
seed json_solution "results/reference fuzz/seeds/solution" '\.json$'
seed gcode "tests/fixtures fuzz/seeds" '\.(ngc|nc|gcode|gco|tap)$'
seed svg "tests/fixtures fuzz/seeds" '\.svg$'
seed dxf "tests/fixtures fuzz/seeds" '\.dxf$'
seed plan "experiments fuzz/seeds" '\.toml$'
seed optimize_gcode "tests/fixtures fuzz/seeds" '\.(ngc|nc|gcode|gco|tap)$'
# the drawing target's first byte chooses the reader: even SVG, odd DXF
mkdir -p fuzz/corpus/optimize_drawing
for f in tests/fixtures/svg/*.svg; do
  { printf '\000'; cat "$f"; } >"fuzz/corpus/optimize_drawing/seed-svg-$(basename "$f")"
done
for f in fuzz/seeds/dxf/*.dxf; do
  { printf '\001'; cat "$f"; } >"fuzz/corpus/optimize_drawing/seed-dxf-$(basename "$f")"
  { printf '\003'; cat "$f"; } >"fuzz/corpus/optimize_drawing/seed-dxf-gcode-$(basename "$f")"
done

# Build through `fuzz run` itself: `fuzz build` passes other profile settings than `fuzz run`,
# so building with it first made every run recompile the crate.
empty=$(mktemp -d)
for t in "${targets[@]}"; do
  nice cargo +nightly fuzz run -O "$t" "$empty" -- -runs=0 >/dev/null 2>&1 ||
    nice cargo +nightly fuzz run -O "$t" "$empty" -- -runs=0
done
rmdir "$empty"

mkdir -p fuzz/logs
run_one() {
  local t=$1 log=fuzz/logs/$1.log
  mkdir -p "fuzz/artifacts/$t"
  local before
  before=$(find "fuzz/artifacts/$t" -type f | wc -l)
  set +e
  nice cargo +nightly fuzz run -O "$t" "fuzz/corpus/$t" -- \
    -max_total_time="$secs" -timeout=10 -rss_limit_mb=4096 -print_final_stats=1 \
    >"$log" 2>&1
  local rc=$?
  set -e
  local execs after
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
  after=$(find "fuzz/artifacts/$t" -type f | wc -l)
  local kinds
  kinds=$(find "fuzz/artifacts/$t" -type f -newer "$log.start" -printf '%f\n' 2>/dev/null |
    sed 's/-.*//' | sort | uniq -c | awk '{printf "%s %s ", $1, $2}')
  printf '%-14s %6ss  execs %-10s new findings %-3s %s(exit %s)\n' \
    "$t" "$secs" "${execs:-?}" "$((after - before))" "$kinds" "$rc"
}
printf '%-14s %7s  %s\n' target time 'executions and findings (crash/timeout/oom files)'
running=0
for t in "${targets[@]}"; do
  touch "fuzz/logs/$t.log.start"
  run_one "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$parallel" ]; then
    wait -n
    running=$((running - 1))
  fi
done
wait
