"""scripts/paired_runs.py (notes/lab/carry.md): paired runs of two variants per section, with
the sign test on lower / higher pairs and McNemar's test on who reaches the best seen."""

import os
import subprocess
import sys

import pytest

ROOT = os.path.join(os.path.dirname(__file__), "..", "..")
SCRIPTS = os.path.join(ROOT, "scripts")
sys.path.insert(0, SCRIPTS)

import paired_runs  # noqa: E402


def test_summary_counts_pairs_hits_and_the_tests():
    rows = [
        # file a: best seen 10; after reaches it twice alone, before once alone
        ("a", 1, 12.0, 10.0),
        ("a", 2, 11.0, 10.0),
        ("a", 3, 10.0, 13.0),
        ("a", 4, 10.0, 10.0),
        # file b: equal pairs, both at the best seen
        ("b", 1, 5.0, 5.0),
        ("b", 2, 5.0, 5.0),
    ]
    line = paired_runs.summary(rows)
    # score: a: mean after 43/4 over mean before 43/4 = 1; b: 1
    assert "2 files, 6 pairs: score 1.0000" in line
    assert "lower 2 / higher 1 / equal 3" in line
    # hits: before at 10 in a (2 runs) and b (2); after in a (3) and b (2)
    assert "hits 4 -> 5, only before 1 / only after 2" in line
    # the sign test of a 2-1 split: 2 * (1 + 3) / 8 = 1
    assert "sign test p = 1.000" in line and "McNemar p = 1.000" in line


def test_a_one_sided_split_is_significant():
    rows = [("f", s, 10.0, 9.0) for s in range(8)]
    line = paired_runs.summary(rows)
    # 8 of 8 lower: 2 / 2^8
    assert "lower 8 / higher 0" in line and "sign test p = 0.008" in line
    assert "only before 0 / only after 8 (McNemar p = 0.008)" in line


def test_sections_and_bad_rows(tmp_path):
    good = tmp_path / "runs.txt"
    good.write_text("# comment\n## one.txt: a section\nf 1 3 2\n\n## two\nf 1 2 2\n")
    assert paired_runs.read_sections(str(good)) == {
        "one.txt": [("f", 1, 3.0, 2.0)], "two": [("f", 1, 2.0, 2.0)]}
    out = subprocess.run([sys.executable, os.path.join(SCRIPTS, "paired_runs.py"), str(good),
                          "--section", "two"], capture_output=True, text=True, check=True)
    assert out.stdout.startswith("two: 1 files, 1 pairs") and "one.txt" not in out.stdout
    for text, what in [("f 1 3 2\n", "after a `## NAME` line"),
                       ("## s\nf x 3 2\n", "SEED must be an integer"),
                       ("## s\nf 1 3\n", "expected `FILE SEED BEFORE AFTER`")]:
        bad = tmp_path / "bad.txt"
        bad.write_text(text)
        r = subprocess.run([sys.executable, os.path.join(SCRIPTS, "paired_runs.py"), str(bad)],
                           capture_output=True, text=True)
        assert r.returncode != 0 and f"{bad}:" in r.stderr and what in r.stderr
    r = subprocess.run([sys.executable, os.path.join(SCRIPTS, "paired_runs.py"), str(good),
                        "--section", "three"], capture_output=True, text=True)
    assert r.returncode != 0 and "no section 'three'" in r.stderr


if __name__ == "__main__":
    sys.exit(pytest.main([__file__]))
