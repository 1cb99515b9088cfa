"""Shared fixtures of the Python tests: the repository, the `cellseq` command line."""

import os
import shutil
import subprocess
import json

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def cli_path():
    """The command line built by `cargo build --release` (or $CELLSEQ_BIN)."""
    p = os.environ.get("CELLSEQ_BIN") or os.path.join(ROOT, "target", "release", "cellseq")
    return p if os.path.exists(p) else shutil.which("cellseq")


@pytest.fixture(scope="session")
def root():
    return ROOT


@pytest.fixture(scope="session")
def cli():
    """Runs `cellseq ARGS...` and returns its stdout (parsed when `--json` is among ARGS)."""
    exe = cli_path()
    if exe is None:
        pytest.fail("the cellseq command line is not built: run `cargo build --release` first")

    def run(*args):
        out = subprocess.run(
            [exe, *map(str, args)], cwd=ROOT, capture_output=True, text=True, timeout=600
        )
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout) if "--json" in args else out.stdout

    return run


def instance_path(*parts):
    return os.path.join(ROOT, "instances", *parts)
