"""Experiment plans from Python: the rows of results.csv, the same as `cellseq run`'s."""

import csv

import pytest

import cellseq

PLAN = """
name = "py-tiny"
seed = 7
replicates = 2
objective = "air"
reference = "greedy"

[budget]
evaluations = 20000

[[instances]]
generator = "uniform"
seeds = [1, 2]
grid = { n = [25] }

[[solvers]]
name = "greedy"
[[solvers]]
name = "ils"
params = { k = [4, 8] }
"""

DETERMINISTIC = ("instance", "solver", "solver_id", "params", "replicate", "seed", "cost",
                 "lifts", "path_length", "feasible", "evaluations")


def write_plan(tmp_path):
    p = tmp_path / "tiny.toml"
    p.write_text(PLAN)
    return p


def test_run_plan_rows_match_the_cli(tmp_path, cli):
    plan = write_plan(tmp_path)
    rows = cellseq.run_plan(plan, out=tmp_path / "py", threads=2, frame=False)
    assert isinstance(rows, list) and len(rows) == 2 * 3 * 2
    assert all(r["feasible"] for r in rows)
    assert [r["trial"] for r in rows] == list(range(len(rows)))
    cli("run", plan, "--out", tmp_path / "cli", "--threads", "1")
    with open(tmp_path / "cli" / "results.csv") as fh:
        theirs = list(csv.DictReader(fh))
    assert len(theirs) == len(rows)
    for a, b in zip(rows, theirs):
        for k in DETERMINISTIC:
            va, vb = a[k], b[k]
            if isinstance(va, bool):
                vb = vb == "true"
            elif isinstance(va, int):
                vb = int(vb)
            elif isinstance(va, float):
                vb = float(vb)
            assert va == vb, (k, va, vb)


def test_run_plan_resumes_and_refuses_bad_input(tmp_path):
    plan = write_plan(tmp_path)
    first = cellseq.run_plan(plan, out=tmp_path / "r", frame=False)
    again = cellseq.run_plan(plan, out=tmp_path / "r", frame=False)
    assert [r["cost"] for r in again] == [r["cost"] for r in first]
    with pytest.raises(ValueError, match="threads"):
        cellseq.run_plan(plan, out=tmp_path / "x", threads=0)
    with pytest.raises(ValueError, match="shard"):
        cellseq.run_plan(plan, out=tmp_path / "x", shard=(3, 2))
    bad = tmp_path / "bad.toml"
    bad.write_text(PLAN.replace('name = "greedy"', 'name = "greedyy"'))
    with pytest.raises(ValueError, match="greedyy"):
        cellseq.run_plan(bad, out=tmp_path / "y")
    with pytest.raises(FileNotFoundError):
        cellseq.run_plan(tmp_path / "none.toml")


def test_run_plan_as_a_dataframe(tmp_path):
    pd = pytest.importorskip("pandas")
    df = cellseq.run_plan(write_plan(tmp_path), out=tmp_path / "df")
    assert isinstance(df, pd.DataFrame) and len(df) == 12
    assert set(df["solver"]) == {"greedy", "ils"}
    assert (df.groupby("solver")["cost"].mean()["ils"]
            <= df.groupby("solver")["cost"].mean()["greedy"] + 1e-9)
