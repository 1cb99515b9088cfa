"""The core API: reading, building, generating, solving, checking, bounds, errors."""

import json
import os

import numpy as np
import pytest

import cellseq
from conftest import ROOT, instance_path

ESC12 = instance_path("tsplib-sop", "ESC12.sop")


def tiny():
    """Five cells, cell 1 before cell 3 (the Rust doc example)."""
    costs = np.array(
        [
            [0, 4, 1, 9, 9],
            [9, 0, 3, 2, 8],
            [9, 1, 0, 9, 6],
            [9, 9, 1, 0, 1],
            [9, 9, 9, 9, 0],
        ],
        dtype=float,
    )
    return costs, [(1, 3)]


def brute_force(costs, prec):
    """The optimum of an open path over a small matrix, by enumeration."""
    import itertools

    n = len(costs)
    best = None
    for p in itertools.permutations(range(n)):
        pos = {c: i for i, c in enumerate(p)}
        if any(pos[a] > pos[b] for a, b in prec):
            continue
        c = sum(costs[p[i], p[i + 1]] for i in range(n - 1))
        best = c if best is None else min(best, c)
    return best


def test_from_matrix_exact_matches_enumeration():
    costs, prec = tiny()
    inst = cellseq.Instance.from_matrix(costs, prec)
    assert inst.n == 5 and len(inst) == 5 and inst.is_matrix
    assert inst.precedence == [(1, 3)]
    r = cellseq.solve(inst, "exact", max_evals=1_000_000)
    assert r.proven_optimal
    assert r.cost == brute_force(costs, prec)
    seq = [c for c, _ in r.sequence]
    assert seq.index(1) < seq.index(3)
    assert r.report["cost"] == r.cost
    assert cellseq.check(inst, r.sequence)["cost"] == r.cost


def test_from_matrix_layouts_and_dtypes():
    costs, prec = tiny()
    a = cellseq.solve(cellseq.Instance.from_matrix(costs, prec), "exact").cost
    # integer dtype, Fortran order, a transposed view, nested lists: all converted
    for m in (costs.astype(np.int64), np.asfortranarray(costs), costs.T.copy().T, costs.tolist()):
        assert cellseq.solve(cellseq.Instance.from_matrix(m, prec), "exact").cost == a


def test_from_matrix_with_modes_is_the_generalized_problem():
    rng = np.random.default_rng(5)
    modes = [2, 1, 3, 2]
    size = sum(modes)
    costs = rng.integers(1, 50, size=(size, size)).astype(float)
    inst = cellseq.Instance.from_matrix(costs, [(0, 3)], modes=modes)
    assert inst.modes == modes
    r = cellseq.solve(inst, "exact", max_evals=10_000_000)
    assert r.proven_optimal
    # enumerate orders and modes
    import itertools

    offs = np.cumsum([0] + modes[:-1])
    best = None
    for p in itertools.permutations(range(4)):
        if p.index(0) > p.index(3):
            continue
        for ms in itertools.product(*[range(modes[c]) for c in p]):
            nodes = [offs[c] + m for c, m in zip(p, ms)]
            c = sum(costs[nodes[i], nodes[i + 1]] for i in range(3))
            best = c if best is None else min(best, c)
    assert r.cost == best


def test_bad_matrices_are_refused():
    with pytest.raises(ValueError, match="square"):
        cellseq.Instance.from_matrix(np.zeros((3, 4)))
    with pytest.raises(ValueError):
        cellseq.Instance.from_matrix(np.array([[0, np.nan], [1, 0]]))
    with pytest.raises(ValueError):
        cellseq.Instance.from_matrix(np.array([[0, -1.0], [1, 0]]))
    with pytest.raises(ValueError, match="cycl|order"):
        cellseq.Instance.from_matrix(np.zeros((3, 3)), [(0, 1), (1, 0)])
    with pytest.raises(ValueError):
        cellseq.Instance.from_matrix(np.zeros((3, 3)), [(0, 7)])
    with pytest.raises(ValueError, match="precedence item 0"):
        cellseq.Instance.from_matrix(np.zeros((3, 3)), [(0, -1)])
    with pytest.raises(ValueError, match="entries"):
        cellseq.Instance.from_matrix(np.zeros((3, 3)), modes=[2, 2])


def test_read_and_solve_tsplib():
    inst = cellseq.read(ESC12)
    assert inst.name == "ESC12" and inst.n == 14 and inst.is_matrix
    r = cellseq.solve(inst, "beam", time_limit=30, seed=3)
    # bks.csv: ESC12 1675, proven optimal
    assert r.cost == 1675 and r.proven_optimal
    assert r.lower_bound == pytest.approx(1675)
    assert r.solver == "beam" and r.seed == 3 and r.objective == "matrix"
    d = r.to_dict(best_known=1675)
    assert d["gap_percent"] == 0 and d["feasible"] and len(d["sequence"]) == 14


def test_read_every_format(root):
    for parts in (
        ("tsplib-sop", "ESC07.sop"),
        ("pcgtsplib", "ESC12.pcglns"),
    ):
        assert cellseq.read(instance_path(*parts)).n > 0
    assert cellseq.read(os.path.join(root, "tests", "fixtures", "pcgtsp", "ESC07.pcgtsp")).n > 0


def test_generate_and_save_round_trip(tmp_path):
    inst = cellseq.generate("casing", seed=1, params={"regions": 3})
    assert not inst.is_matrix and inst.n > 10
    assert inst.metadata["generator"] == "casing"
    assert inst.entry_points.shape == (inst.n, 2)
    p = tmp_path / "casing.json"
    inst.save(p)
    back = cellseq.read(p)
    assert back.n == inst.n and back.precedence == inst.precedence
    r1 = cellseq.solve(inst, "local-search", max_evals=50_000)
    r2 = cellseq.solve(back, "local-search", max_evals=50_000)
    assert r1.sequence == r2.sequence
    # the same kind, parameters and seed give the same instance
    again = cellseq.generate("casing", seed=1, params={"regions": 3})
    q = tmp_path / "again.json"
    again.save(q)
    assert p.read_bytes() == q.read_bytes()


def test_generate_refuses_unknown_names():
    with pytest.raises(ValueError, match="casing"):
        cellseq.generate("casingg")
    with pytest.raises(ValueError, match="regions"):
        cellseq.generate("casing", params={"regionz": 3})


def test_result_object_and_trace():
    inst = cellseq.generate("uniform", seed=2, params={"n": 60})
    seen = []
    r = cellseq.solve(
        inst, "ils", max_evals=200_000, progress=lambda e, s, b: seen.append((e, s, b))
    )
    t = r.trace
    assert t.dtype == np.float64 and t.ndim == 2 and t.shape[1] == 3 and len(t) >= 1
    assert np.all(np.diff(t[:, 0]) >= 0) and np.all(np.diff(t[:, 2]) < 0)
    assert t[-1, 2] == pytest.approx(r.cost)
    # the callback saw every improvement the trace holds
    assert [p[2] for p in seen] == list(t[:, 2])
    rep = r.report
    for k in ("air_length", "cut_length", "path_length", "lifts", "tool_changes", "machining_time"):
        assert k in rep
    assert rep["path_length"] == pytest.approx(rep["air_length"] + rep["cut_length"])
    assert r.evaluations >= 200_000 and r.elapsed_s > 0
    assert r.params["k"]
    assert "ils" in repr(r)
    assert sorted({c for c, _ in r.sequence}) == list(range(inst.n))


def test_objectives():
    inst = cellseq.generate("panel", seed=1, params={"rows": 2, "cols": 2})
    t = cellseq.solve(inst, "greedy", objective="time")
    a = cellseq.solve(inst, "greedy", objective="air")
    assert t.objective == "time" and a.objective == "air"
    assert a.cost == pytest.approx(a.report["air_length"])
    with pytest.raises(ValueError, match="objective"):
        cellseq.solve(inst, "greedy", objective="speed")
    with pytest.raises(ValueError, match="matrix"):
        cellseq.solve(cellseq.read(ESC12), "greedy", objective="air")


def test_unknown_solver_and_parameter_list_the_valid_ones():
    inst = cellseq.read(ESC12)
    with pytest.raises(ValueError) as e:
        cellseq.solve(inst, "ilss")
    for name in ("auto", "ils", "beam", "drawing"):
        assert name in str(e.value)
    with pytest.raises(ValueError) as e:
        cellseq.solve(inst, "ils", params={"kk": 3})
    assert "kicks" in str(e.value) and isinstance(e.value, cellseq.CellseqError)
    with pytest.raises(ValueError, match="k"):
        cellseq.solve(inst, "ils", params={"k": "many"})
    with pytest.raises(ValueError, match="k"):
        cellseq.solve(inst, "ils", params={"k": -1})
    with pytest.raises(ValueError, match="time_limit"):
        cellseq.solve(inst, "ils", time_limit=-1)
    with pytest.raises(ValueError, match="callable"):
        cellseq.solve(inst, "ils", max_evals=10, progress=3)


def test_parameters_change_the_run():
    inst = cellseq.read(ESC12)
    r = cellseq.solve(inst, "ils", max_evals=30_000, params={"k": 4, "walks": 1})
    assert r.params["k"] == "4"


def test_check_names_the_broken_rule():
    costs, prec = tiny()
    inst = cellseq.Instance.from_matrix(costs, prec)
    assert cellseq.check(inst, [0, 1, 2, 3, 4])["cost"] == 4 + 3 + 9 + 1
    assert cellseq.check(inst, [(0, 0), (1, 0), (2, 0), (3, 0), (4, 0)])["cost"] == 17
    with pytest.raises(ValueError, match="precedence|before|after"):
        cellseq.check(inst, [3, 1, 0, 2, 4])
    with pytest.raises(ValueError, match="missing"):
        cellseq.check(inst, [0, 1, 2])
    with pytest.raises(ValueError, match="more than once"):
        cellseq.check(inst, [0, 1, 1, 2, 3, 4])
    with pytest.raises(ValueError, match="mode"):
        cellseq.check(inst, [(0, 1), 1, 2, 3, 4])
    with pytest.raises(ValueError, match="position 1"):
        cellseq.check(inst, [0, "x", 2, 3, 4])


def test_bounds_are_below_the_optimum():
    inst = cellseq.read(ESC12)
    b = cellseq.bounds(inst)
    assert b["best"] <= 1675
    assert b["best_name"] in [p["name"] for p in b["parts"]]
    assert max(p["value"] for p in b["parts"]) <= 1675 + 1e-9


def test_solvers_and_generators_listing():
    s = cellseq.solvers()
    names = [x["name"] for x in s]
    assert names[0] == "auto" and "drawing" in names and cellseq.solver_names() == names
    ils = next(x for x in s if x["name"] == "ils")
    assert any(p["name"] == "k" and p["kind"] == "int" for p in ils["params"])
    g = [x["name"] for x in cellseq.generators()]
    assert {"panel", "casing", "cabin", "uniform", "random-sop"} <= set(g)


def test_parse_errors_carry_file_and_line(tmp_path):
    p = tmp_path / "bad.sop"
    p.write_text("TYPE: SOP\nDIMENSION: 3\nEDGE_WEIGHT_SECTION\n3\n0 1 x\n")
    with pytest.raises(cellseq.ParseError) as e:
        cellseq.read(p)
    assert isinstance(e.value, ValueError)
    assert e.value.file == str(p) and e.value.line == 5
    assert "bad.sop:5" in str(e.value)


def test_io_errors():
    with pytest.raises(FileNotFoundError) as e:
        cellseq.read(os.path.join(ROOT, "no-such-file.sop"))
    assert "no-such-file.sop" in str(e.value)
    with pytest.raises(OSError):
        cellseq.read(ROOT)  # a directory


def test_invalid_instance_file(tmp_path):
    p = tmp_path / "bad.json"
    p.write_text(json.dumps({"format": "cellseq-instance/1", "cells": "nope"}))
    with pytest.raises(ValueError) as e:
        cellseq.read(p)
    assert e.value.file is not None


def test_result_save_is_read_by_the_cli(tmp_path, cli):
    inst = cellseq.read(ESC12)
    r = cellseq.solve(inst, "ils", max_evals=50_000)
    out = tmp_path / "sol.json"
    r.save(out)
    text = cli("eval", ESC12, out)
    assert str(int(r.cost)) in text
