#!/usr/bin/env bash
# The project's one test command (README; CI runs it): the Rust tests of the workspace, then the
# Python package `cellseq` and the vpype plugin, built and installed into a virtual environment
# (target/py-venv, or $CELLSEQ_VENV) with what python/requirements-test.txt pins from PyPI, and
# their pytest suite (python/tests).
#
#   scripts/test.sh              # everything
#   scripts/test.sh --python     # only the Python part (after a `cargo test --release`)
#
# The extension is built by maturin into the workspace's target/ with the release profile, so
# what the test build compiled with the same features is reused (notes/python.md has the times).
set -euo pipefail
cd "$(dirname "$0")/.."
# where the time goes: each part prints the seconds taken so far
mark() { echo "test.sh: +${SECONDS}s $*" >&2; }

if [[ "${1:-}" != "--python" ]]; then
    mark "cargo test --release"
    cargo test --release
fi

venv="${CELLSEQ_VENV:-target/py-venv}"
python="${PYTHON:-python3}"
if [[ ! -x "$venv/bin/python" ]]; then
    "$python" -m venv "$venv"
fi
pip=("$venv/bin/python" -m pip --disable-pip-version-check -q)
mark "the venv's packages (python/requirements-test.txt)"
"${pip[@]}" install -r python/requirements-test.txt
# the package, as `pip install .` would build it (maturin, release profile), installed editable
mark "maturin develop --release"
VIRTUAL_ENV="$PWD/$venv" "$venv/bin/maturin" develop --release --quiet
# the plugin is pure Python (setuptools comes with the venv; no build isolation to download)
"${pip[@]}" install --no-build-isolation --no-deps ./python/vpype-cellseq
# the round-trip tests run the command line that `cargo test --release` built
export CELLSEQ_BIN="${CARGO_TARGET_DIR:-$PWD/target}/release/cellseq"
[[ -x "$CELLSEQ_BIN" ]] || cargo build --release --quiet -p cellseq-cli
mark "pytest python/tests"
"$venv/bin/python" -m pytest python/tests -q -p no:cacheprovider
mark "done"
