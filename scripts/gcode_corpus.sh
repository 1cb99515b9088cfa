#!/usr/bin/env bash
# The per-file table of the G-code corpus (issue 25): every program in tests/fixtures/gcode/
# (the real programs of real/, sources in real/SOURCES.md, and the small fixtures) rewritten by
# `cellseq optimize` with default options, --merge-tool-blocks and --reversible, each judged by
# LinuxCNC's interpreter (rs274) in tests/it/rs274.rs: state-exact yes/no (or refused, with the
# message), air, lifts and time before -> after (cellseq's report, and air and lifts recomputed
# from rs274's canonical calls), and the first problems found.
#
#   scripts/gcode_corpus.sh [OUT.md] [FILTER]
#
# OUT.md (default: results/gcode-corpus.md) receives the Markdown table; FILTER limits the run
# to files whose path contains it. Needs rs274 (Debian linuxcnc-uspace). The exit status is the
# test's: non-zero while any program is not machine-safe.
set -uo pipefail
cd "$(dirname "$0")/.."
out="${1:-results/gcode-corpus.md}"
mkdir -p "$(dirname "$out")"
command -v rs274 >/dev/null || { echo "rs274 not found: apt-get install linuxcnc-uspace" >&2; exit 2; }
echo "cellseq $(git rev-parse --short HEAD 2>/dev/null || echo '?'), rs274 $(dpkg-query -W -f '${Version}' linuxcnc-uspace 2>/dev/null || echo '?')" >&2
CELLSEQ_CORPUS_TABLE="$(realpath -m "$out")" CELLSEQ_CORPUS_FILTER="${2:-}" \
  nice cargo test --release --test it rs274::rs274_corpus_state_exact -- --nocapture >/dev/null
status=$?
if [ -f "$out" ]; then cat "$out"; else echo "no table written (build or test harness failed)" >&2; fi
exit $status
