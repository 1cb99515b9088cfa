"""The Python package against the command line on the same inputs and seeds: identical
sequences under evaluation budgets, identical programs and drawings."""

import pytest

import cellseq
from conftest import ROOT, instance_path


def refs(inst, seq):
    """A sequence as the CLI's `{cell, mode}` list."""
    ids = inst.cell_ids
    return [{"cell": ids[c], "mode": m} for c, m in seq]


@pytest.mark.parametrize(
    "file,solver,seed,evals",
    [
        (("tsplib-sop", "ESC25.sop"), "ils", 1, 200_000),
        (("tsplib-sop", "rbg109a.sop"), "auto", 7, 300_000),
        (("tsplib-sop", "ft53.1.sop"), "aco", 2, 100_000),
        (("pcgtsplib", "ESC12.pcglns"), "local-search", 3, 100_000),
    ],
)
def test_solve_matches_the_cli(cli, file, solver, seed, evals):
    path = instance_path(*file)
    inst = cellseq.read(path)
    r = cellseq.solve(inst, solver, max_evals=evals, seed=seed)
    c = cli("solve", path, "--solver", solver, "--seed", seed, "--max-evals", evals, "--json")
    assert refs(inst, r.sequence) == c["sequence"]
    assert r.cost == c["cost"]
    assert r.lower_bound == c["lower_bound"]
    assert r.proven_optimal == c["proven_optimal"]


def test_generated_instance_matches_the_cli(cli, tmp_path):
    out = tmp_path / "casing.json"
    cli("generate", "casing", "--param", "regions=3", "--seed", "4", "-o", out)
    mine = tmp_path / "mine.json"
    cellseq.generate("casing", seed=4, params={"regions": 3}).save(mine)
    assert mine.read_bytes() == out.read_bytes()
    inst = cellseq.read(out)
    r = cellseq.solve(inst, "tabu", max_evals=100_000, seed=5, objective="air")
    c = cli("solve", out, "--solver", "tabu", "--seed", 5, "--max-evals", 100_000,
            "--objective", "air", "--json")
    assert refs(inst, r.sequence) == c["sequence"] and r.cost == c["cost"]


def test_parameters_match_the_cli(cli):
    path = instance_path("tsplib-sop", "ESC25.sop")
    inst = cellseq.read(path)
    r = cellseq.solve(inst, "ils", max_evals=100_000, seed=2, params={"k": 5, "accept": 0.5})
    c = cli("solve", path, "--solver", "ils", "--seed", 2, "--max-evals", 100_000,
            "--param", "k=5", "--param", "accept=0.5", "--json")
    assert refs(inst, r.sequence) == c["sequence"]


def test_gcode_matches_the_cli(cli, tmp_path):
    src = f"{ROOT}/tests/fixtures/gcode/real"
    # a mill (Z, no reversal), a plasma program (2-D: reversal on), a drilling program
    files = ["linuxcnc_cds.ngc", "linuxcnc_plasmatest.ngc", "pcb2gcode_easysdr_outline.ngc"]
    for f in files:
        out = tmp_path / (f + ".opt.ngc")
        c = cli("optimize", f"{src}/{f}", "-o", out, "--max-evals", 50_000, "--json")
        mine = cellseq.optimize_gcode(f"{src}/{f}", max_evals=50_000)
        assert mine.text == out.read_text(), f
        rep = mine.report
        for k in ("cells", "groups", "verified_cutting_moves", "verified_events", "kept",
                  "reversal", "reversed_cells", "before", "after"):
            assert rep[k] == c[k], (f, k)
        # from text too
        with open(f"{src}/{f}") as fh:
            again = cellseq.optimize_gcode(text=fh.read(), max_evals=50_000)
        assert again.text == mine.text


def test_svg_matches_the_cli(cli, tmp_path):
    f = f"{ROOT}/tests/fixtures/svg/real/boxespy_Clock.svg"
    out = tmp_path / "clock.svg"
    c = cli("optimize", f, "-o", out, "--max-evals", 200_000, "--json")
    mine = cellseq.optimize_drawing(f, max_evals=200_000)
    assert mine.text == out.read_text()
    rep = mine.report
    assert rep["verified_segments"] == c["verified_segments"]
    assert rep["before"] == c["before"] and rep["after"] == c["after"]
    # text in, the same out
    with open(f) as fh:
        assert cellseq.optimize_drawing(text=fh.read(), max_evals=200_000).text == mine.text


def test_dxf_matches_the_cli(cli, tmp_path):
    import os

    f = os.path.join(ROOT, "fuzz", "seeds", "dxf", "shapes.dxf")
    out = tmp_path / "part.ngc"
    c = cli("optimize", f, "-o", out, "--max-evals", 100_000, "--json")
    mine = cellseq.optimize_drawing(f, max_evals=100_000)
    assert mine.text == out.read_text()
    assert mine.report["after"] == c["after"]


def test_gcode_errors_carry_the_line(tmp_path):
    # O-word control flow is refused, naming the line
    program = tmp_path / "osub.ngc"
    program.write_text("G21\nG0 X0 Y0 Z5\no100 sub\nG1 Z-1 F100\no100 endsub\nM2\n")
    with pytest.raises(cellseq.ParseError) as e:
        cellseq.optimize_gcode(program)
    assert e.value.line == 3 and e.value.file.endswith("osub.ngc")
    with pytest.raises(cellseq.ParseError) as e:
        cellseq.optimize_gcode(text=program.read_text())
    assert e.value.line == 3 and e.value.file == "<text>"
    with pytest.raises(ValueError, match="exactly one"):
        cellseq.optimize_gcode()
    with pytest.raises(ValueError, match="solver"):
        cellseq.optimize_gcode(text="G0 X1\n", solver="nope")
    with pytest.raises(ValueError, match="margin"):
        cellseq.optimize_gcode(text="G0 X1\n", margin=-1)


def test_optimized_save_refuses_the_input(tmp_path):
    src = tmp_path / "p.ngc"
    with open(f"{ROOT}/tests/fixtures/gcode/real/linuxcnc_cds.ngc") as fh:
        src.write_text(fh.read())
    o = cellseq.optimize_gcode(src, max_evals=20_000)
    with pytest.raises(ValueError):
        o.save(src)
    o.save(tmp_path / "q.ngc")
    assert (tmp_path / "q.ngc").read_text() == o.text


def test_drawing_pens_and_blocks_match_the_cli(cli, tmp_path):
    f = f"{ROOT}/tests/fixtures/svg/real/boxespy_Spool.svg"
    out = tmp_path / "spool.svg"
    c = cli("optimize", f, "-o", out, "--max-evals", 100_000, "--pens", "layer", "--blocks", "none", "--json")
    mine = cellseq.optimize_drawing(f, max_evals=100_000, pens="layer", blocks="none")
    assert mine.text == out.read_text()
    assert mine.report["semantics"] == c["semantics"]
    assert (mine.report["semantics"]["pens"], mine.report["semantics"]["blocks"]) == ("layer", "none")
    with pytest.raises(ValueError, match="pens"):
        cellseq.optimize_drawing(f, pens="marker")
    with pytest.raises(ValueError, match="scopes"):
        cellseq.optimize_drawing(f, scopes=False, pens="layer")
