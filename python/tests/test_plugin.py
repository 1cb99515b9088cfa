"""The vpype plugin `cellsort` on the real SVGs: no more pen-up travel than
`linesort --two-opt` on every file and layer, the same pen-down length, layers and their
properties kept."""

import copy
import glob
import os
import subprocess
import sys

import numpy as np
import pytest

vpype_cli = pytest.importorskip("vpype_cli")
import vpype as vp  # noqa: E402

from conftest import ROOT  # noqa: E402

# the `vpype` command of this interpreter's environment
VPYPE = os.path.join(os.path.dirname(sys.executable), "vpype")

FILES = sorted(glob.glob(os.path.join(ROOT, "tests", "fixtures", "svg", "real", "*.svg")))


def test_the_corpus_is_there():
    assert len(FILES) >= 20


def test_the_plugin_is_registered():
    out = subprocess.run(
        [VPYPE, "cellsort", "--help"], capture_output=True, text=True
    )
    assert out.returncode == 0, out.stderr
    assert "--time-limit" in out.stdout and "--no-flip" in out.stdout


def read(path):
    return vpype_cli.execute(f"read --no-crop '{path}'")


@pytest.mark.parametrize("path", FILES, ids=os.path.basename)
def test_cellsort_against_linesort_two_opt(path, capfd):
    doc = read(path)
    ls = vpype_cli.execute("linesort --two-opt", document=copy.deepcopy(doc))
    cs = vpype_cli.execute("cellsort", document=copy.deepcopy(doc))
    assert "cellsort: pen-up" in capfd.readouterr().err
    assert list(cs.layers) == list(doc.layers)
    for lid, lc in doc.layers.items():
        a, b = ls.layers[lid], cs.layers[lid]
        assert len(b) == len(lc)
        assert b.pen_up_length()[0] <= a.pen_up_length()[0] * (1 + 1e-12) + 1e-9, lid
        assert b.length() == pytest.approx(lc.length(), rel=1e-12)
        assert b.metadata == lc.metadata
    assert cs.metadata == doc.metadata


def test_no_flip_keeps_every_line_as_it_is():
    doc = read(os.path.join(ROOT, "tests", "fixtures", "svg", "real", "boxespy_SkadisBoard.svg"))
    cs = vpype_cli.execute("cellsort --no-flip", document=copy.deepcopy(doc))
    for lid, lc in doc.layers.items():
        given = {tuple(np.round(line, 9)) for line in lc}
        assert {tuple(np.round(line, 9)) for line in cs.layers[lid]} == given


def test_time_limit_and_options():
    path = os.path.join(ROOT, "tests", "fixtures", "svg", "real", "vpype_issue58_voronoi.svg")
    doc = read(path)
    cs = vpype_cli.execute("cellsort --time-limit 0.5 --max-starts 1 --from-origin",
                           document=copy.deepcopy(doc))
    assert cs.layers[1].pen_up_length()[0] < doc.layers[1].pen_up_length()[0]
    with pytest.raises(BaseException):
        vpype_cli.execute("cellsort --time-limit -1", document=copy.deepcopy(doc))


def test_cellsort_on_the_command_line(tmp_path):
    src = os.path.join(ROOT, "tests", "fixtures", "svg", "real", "vpype_multilayer_3layers.svg")
    out = tmp_path / "o.svg"
    r = subprocess.run(
        [VPYPE, "read", src, "cellsort", "--time-limit", "5",
         "write", str(out)],
        capture_output=True, text=True,
    )
    assert r.returncode == 0, r.stderr
    assert "cellsort: pen-up" in r.stderr and out.exists()
    back = vp.read_multilayer_svg(str(out), 0.1)
    assert len(back.layers) == 3
