"""The robustness summary of scripts/peers/targets.py (issue 51: the chance that a seed triple
meets the TSPLIB target), from run records written by hand."""

import json
import os
import subprocess
import sys

import pytest

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
PEERS = os.path.join(ROOT, "scripts", "peers")
sys.path.insert(0, PEERS)

import targets  # noqa: E402


def runs(instance, best, costs, limit=10):
    return [{"instance": instance, "set": "s", "time_limit": limit, "seed": k + 1, "cost": c,
             "best_known": best, "elapsed_s": limit, "loadavg": 1.0}
            for k, c in enumerate(costs)]


def test_triple_chance_is_the_chance_that_two_of_three_hit():
    assert targets.triple_chance(1.0) == 1.0
    assert targets.triple_chance(0.0) == 0.0
    assert targets.triple_chance(0.5) == pytest.approx(0.5)
    assert targets.triple_chance(2 / 3) == pytest.approx(20 / 27)


def test_robustness_multiplies_the_instances_chances():
    records = (runs("a", 100, [100, 100, 100]) + runs("b", 50, [50, 51, 50])
               + runs("c", 10, [11, 10, 10, 12, 10, 11]))
    text = targets.robustness(targets.group(records), None)
    # a: 1; b: 2/3 -> 20/27; c: 1/2 -> 1/2
    assert "with probability %.3f" % (20 / 27 * 0.5) in text
    assert "b 2/3 (0.74)" in text and "c 3/6 (0.50)" in text and "a 3/3" not in text


def test_the_gap_estimate_draws_three_runs_per_instance():
    # one instance always at 0 %, one at 0 % in two runs of four and 2 % in the others:
    # a triple's median is 0 % when at least two of its three draws are, half the time
    records = runs("a", 100, [100] * 4) + runs("b", 100, [100, 100, 102, 102])
    text = targets.robustness(targets.group(records), 0.5)
    line = [t for t in text.splitlines() if "drawn at random" in t][0]
    p = float(line.rsplit("probability ", 1)[1])
    assert 0.45 < p < 0.55


def test_from_jsonl_summarizes_without_running(tmp_path):
    f = tmp_path / "runs.jsonl"
    f.write_text("".join(json.dumps(r) + "\n"
                         for r in runs("a", 100, [100, 101, 100]) + runs("b", 7, [7, 7, 7])))
    out = subprocess.run([sys.executable, os.path.join(PEERS, "targets.py"),
                          "--from-jsonl", str(f), "--cellseq", "/nonexistent"],
                         capture_output=True, text=True, check=True).stdout
    assert "| s | 10 | 1 2 3 | 2 | 2/2 | 0.000 | 0.000 |" in out
    assert "a 2/3 (0.74)" in out
    bad = subprocess.run([sys.executable, os.path.join(PEERS, "targets.py"),
                          "--from-jsonl", str(f), "--gap-target", "nan"],
                         capture_output=True, text=True)
    assert bad.returncode != 0 and "--gap-target" in bad.stderr
