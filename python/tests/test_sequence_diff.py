"""scripts/sequence_diff.py (notes/lab/dense-traps.md): the windows where two solutions of one
TSPLIB SOP instance differ, the best mix of them, and a window written as an instance."""

import json
import os
import subprocess
import sys

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
SCRIPTS = os.path.join(ROOT, "scripts")
sys.path.insert(0, SCRIPTS)

import sequence_diff  # noqa: E402
from sop_common import write_sop  # noqa: E402  (scripts/peers, put on the path by sequence_diff)


def write_solution(path, seq):
    path.write_text(json.dumps({"format": "cellseq-solution/1",
                                "sequence": [{"cell": str(v + 1), "mode": 0} for v in seq]}))


def matrix(n, cheap, pred=()):
    """Links cost 10, those in `cheap` 1; node 0 first, node n-1 last; (a, b) in pred: a
    before b."""
    M = [[0 if i == j else (1 if (i, j) in cheap else 10) for j in range(n)] for i in range(n)]
    for i in range(1, n):
        M[i][0] = -1
    for j in range(n - 1):
        M[n - 1][j] = -1
    for a, b in pred:
        M[b][a] = -1
    return M


def test_windows_are_the_runs_between_equal_prefix_sets_and_touching_ones_merge():
    assert sequence_diff.windows([0, 1, 2, 3, 4, 5, 6], [0, 2, 1, 3, 5, 4, 6]) == [(1, 2), (4, 5)]
    # (1, 2) and (3, 4) touch: the link between them depends on both, so they are one window
    assert sequence_diff.windows([0, 1, 2, 3, 4, 5], [0, 2, 1, 4, 3, 5]) == [(1, 4)]
    assert sequence_diff.windows([0, 1, 2], [0, 1, 2]) == []


def test_displaced_counts_the_cells_off_a_longest_common_order():
    # b moves cell 1 from the front of the window to its end: one cell displaced
    assert sequence_diff.displaced([0, 1, 2, 3, 4, 5], [0, 2, 3, 4, 1, 5], 1, 4) == 1
    assert sequence_diff.displaced([0, 1, 2, 3, 4, 5], [0, 4, 3, 2, 1, 5], 1, 4) == 3


def test_the_best_mix_takes_each_window_from_the_cheaper_solution(tmp_path, capsys):
    # a is cheap in the first window (0-1-2-3), b in the second (3-5-4-6)
    cheap = {(0, 1), (1, 2), (2, 3), (3, 5), (5, 4), (4, 6)}
    M = matrix(7, cheap)
    a, b = [0, 1, 2, 3, 4, 5, 6], [0, 2, 1, 3, 5, 4, 6]
    sequence_diff.compare(M, [("a", a), ("b", b)])
    out = capsys.readouterr().out
    assert "a (33) against b (33)" in out
    # a window's cost holds the links from the cell before it to the cell after it
    assert "positions 1-2: 2 cells, 1 displaced, cost 3 against 30" in out
    assert "positions 4-5: 2 cells, 1 displaced, cost 30 against 3" in out
    assert "best mix (partition crossover): 6" in out
    assert sequence_diff.tour_cost(M, [0, 1, 2, 3, 5, 4, 6]) == 6


def test_a_window_written_out_keeps_its_precedence_and_the_exact_solver_improves_it(tmp_path, cli):
    # 0 1 2 3 4 5 6 is the cheapest order, but 3 must come before 2; the window (positions
    # 2..4) of the order 0 1 4 3 2 5 6 costs 40 with its anchors 1 and 5; its best order that
    # keeps 3 before 2 costs 22 (without the pair, 1 2 3 4 5 would cost 4)
    cheap = {(0, 1), (1, 2), (2, 3), (3, 4), (4, 5), (5, 6), (1, 3)}
    M = matrix(7, cheap, pred=[(3, 2)])
    inst, sol, out = tmp_path / "t.sop", tmp_path / "a.json", tmp_path / "w.sop"
    write_sop(inst, "t", M)
    write_solution(sol, [0, 1, 4, 3, 2, 5, 6])
    run = subprocess.run([sys.executable, os.path.join(SCRIPTS, "sequence_diff.py"), str(inst),
                          str(sol), "--window", "2", "4", "--out", str(out)],
                         capture_output=True, text=True, check=True)
    assert "5 nodes, the window's cost in the sequence 40" in run.stdout
    w = [list(map(int, line.split())) for line in out.read_text().split("SECTION\n")[1]
         .split("EOF")[0].strip().splitlines()[1:]]
    # nodes: 1 (anchor), 4, 3, 2, 5 (anchor); 3 before 2: 2's row holds -1 at 3's column
    assert w[3][2] == -1 and w[2][3] == 10
    assert all(w[k][0] == -1 for k in range(1, 5)) and all(w[4][k] == -1 for k in range(4))
    solved = cli("solve", out, "--solver", "exact", "--json")
    assert solved["cost"] == 22
    bad = subprocess.run([sys.executable, os.path.join(SCRIPTS, "sequence_diff.py"), str(inst),
                          str(sol), "--window", "0", "4", "--out", str(out)],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "must lie within 1..5" in bad.stderr


def test_unreadable_files_are_refused_naming_the_file(tmp_path):
    inst, sol = tmp_path / "t.sop", tmp_path / "a.json"
    write_sop(inst, "t", matrix(4, set()))
    for text in ["not json", '{"sequence": [{"mode": 0}]}', '{"sequence": [{"cell": "x"}]}']:
        sol.write_text(text)
        run = subprocess.run([sys.executable, os.path.join(SCRIPTS, "sequence_diff.py"),
                              str(inst), str(sol), str(sol)], capture_output=True, text=True)
        assert run.returncode != 0 and str(sol) in run.stderr
        assert "Traceback" not in run.stderr
    write_solution(sol, [0, 1, 2, 3])
    (tmp_path / "bad.sop").write_text("TYPE: SOP\nDIMENSION: 3\nEDGE_WEIGHT_SECTION\n3\n0 1\n")
    run = subprocess.run([sys.executable, os.path.join(SCRIPTS, "sequence_diff.py"),
                          str(tmp_path / "bad.sop"), str(sol), str(sol)],
                         capture_output=True, text=True)
    assert run.returncode != 0 and "bad.sop" in run.stderr and "Traceback" not in run.stderr
