#!/usr/bin/env bash
# Regenerates the shipped instance suite instances/generated/*.json from suite.tsv.
#
#   scripts/generate-suite.sh            # the committed suite (about 20, 100, 1000 cells)
#   scripts/generate-suite.sh --large    # also the ~10 000-cell instances (not committed)
#
# Uses $CELLSEQ if set, else builds and runs the release binary with cargo.
set -euo pipefail
cd "$(dirname "$0")/.."
large=0
if [[ "${1:-}" == "--large" ]]; then large=1; fi
if [[ -z "${CELLSEQ:-}" ]]; then
    cargo build --release --quiet
    CELLSEQ="${CARGO_TARGET_DIR:-target}/release/cellseq"
fi
dir=instances/generated
while IFS=$'\t' read -r file kind seed params; do
    [[ -z "$file" || "$file" == \#* ]] && continue
    if [[ "$file" == large/* && $large -eq 0 ]]; then continue; fi
    args=()
    if [[ "$params" != "-" ]]; then
        for p in $params; do args+=(--param "$p"); done
    fi
    mkdir -p "$(dirname "$dir/$file")"
    "$CELLSEQ" generate "$kind" "${args[@]}" --seed "$seed" -o "$dir/$file"
done < "$dir/suite.tsv"
