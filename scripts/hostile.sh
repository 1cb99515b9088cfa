#!/usr/bin/env bash
# Runs the hostile suite (crates/cellseq-cli/tests/it/hostile.rs): seeded hostile inputs made
# from the repository's files, through every command that reads files, each run classified
# (clean result, clean refusal naming the file, refusal naming no input, crash, hang,
# overtime, NaN/inf in the output). CI runs a sample of 120 cases; this runs more.
#
#   scripts/hostile.sh                 the CI sample
#   scripts/hostile.sh --full          1500 cases, 4 jobs
#   scripts/hostile.sh --full --seed 7 --cases 3000 --jobs 2
#
# Runs that are not clean leave their case (input, command, stderr) in
# target/tmp/hostile/seed-S/; the test lists them.
set -euo pipefail
cd "$(dirname "$0")/.."
while [ $# -gt 0 ]; do
  case $1 in
    --full) export CELLSEQ_HOSTILE=full ;;
    --seed) export CELLSEQ_HOSTILE_SEED=$2; shift ;;
    --cases) export CELLSEQ_HOSTILE_CASES=$2; shift ;;
    --jobs) export CELLSEQ_HOSTILE_JOBS=$2; shift ;;
    *) echo "unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
nice cargo test --release --test it -- hostile:: --nocapture
