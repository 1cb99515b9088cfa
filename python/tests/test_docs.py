"""docs/python.md's Python code blocks run as written, in order, in one namespace, from the
repository's root."""

import os
import re

from conftest import ROOT


def blocks():
    with open(os.path.join(ROOT, "docs", "python.md")) as fh:
        text = fh.read()
    return re.findall(r"```python\n(.*?)```", text, re.S)


def test_the_guide_runs_as_written(monkeypatch, tmp_path):
    code = blocks()
    assert len(code) >= 6
    monkeypatch.chdir(ROOT)
    ns = {"__name__": "__guide__"}
    for i, block in enumerate(code):
        exec(compile(block, f"docs/python.md block {i + 1}", "exec"), ns)
    # the plot was written (into the root: moved away so the checkout stays clean)
    png = os.path.join(ROOT, "casing-trace.png")
    assert os.path.getsize(png) > 10_000
    os.replace(png, tmp_path / "casing-trace.png")
