#!/usr/bin/env python3
"""Paired runs of two variants (before, after) summarized per section of a runs file.

The runs file holds one row per instance file and seed, `FILE SEED BEFORE AFTER` (the costs
of the two variants' runs with that seed, run side by side), in sections that start with a
`## NAME` line; other `#` lines are comments (notes/lab/carry-runs.txt is one). Per section:

- score: geometric mean over files of (mean cost after) / (mean cost before);
- lower / higher / equal: pairs where `after` is below, above or equal to `before`, with the
  two-sided sign test on the unequal pairs;
- hits: runs at the best cost either variant reached on that file, and the pairs where only
  one of the two reached it, with the exact McNemar test on those (the sign test on the
  discordant pairs): whether one variant reaches the best seen more often, the quantity a
  target "at the best known in the median of three seeds" depends on.

    python3 scripts/paired_runs.py notes/lab/carry-runs.txt [--section t1n.txt]...   (repeatable)
"""
import argparse
import math
import os
import statistics
import sys
from collections import defaultdict

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from plan_race import sign_test_p  # noqa: E402


def read_sections(path):
    """{section: [(file, seed, before, after)]} in the order of the file."""
    sections = {}
    name = None
    with open(path, encoding="utf-8") as f:
        for no, line in enumerate(f, 1):
            if line.startswith("## "):
                name = line.split()[1].rstrip(":")
                sections[name] = []
                continue
            if line.startswith("#") or not line.strip():
                continue
            parts = line.split()
            if name is None or len(parts) < 4:
                sys.exit(f"{path}:{no}: expected `FILE SEED BEFORE AFTER` after a `## NAME` line")
            try:
                row = (parts[0], int(parts[1]), float(parts[2]), float(parts[3]))
            except ValueError:
                sys.exit(f"{path}:{no}: SEED must be an integer and the costs numbers")
            sections[name].append(row)
    return sections


def summary(rows):
    """One line of the section's statistics."""
    by_file = defaultdict(lambda: ([], []))
    best = defaultdict(lambda: math.inf)
    for f, _, a, b in rows:
        by_file[f][0].append(a)
        by_file[f][1].append(b)
        best[f] = min(best[f], a, b)
    score = math.exp(statistics.mean(
        math.log(statistics.mean(b) / statistics.mean(a)) for a, b in by_file.values()))
    lower = sum(b < a for _, _, a, b in rows)
    higher = sum(b > a for _, _, a, b in rows)
    equal = len(rows) - lower - higher
    hits_a = sum(a == best[f] for f, _, a, _ in rows)
    hits_b = sum(b == best[f] for f, _, _, b in rows)
    only_a = sum(a == best[f] and b != best[f] for f, _, a, b in rows)
    only_b = sum(b == best[f] and a != best[f] for f, _, a, b in rows)
    return (f"{len(by_file)} files, {len(rows)} pairs: score {score:.4f}; "
            f"lower {lower} / higher {higher} / equal {equal} (sign test p = "
            f"{sign_test_p(lower, higher):.3f}); hits {hits_a} -> {hits_b}, only before "
            f"{only_a} / only after {only_b} (McNemar p = {sign_test_p(only_b, only_a):.3f})")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("runs")
    ap.add_argument("--section", action="append", default=[],
                    help="only these sections (repeatable; default: all)")
    a = ap.parse_args()
    sections = read_sections(a.runs)
    for name in a.section:
        if name not in sections:
            sys.exit(f"{a.runs}: no section {name!r} (there are: {', '.join(sections)})")
    for name, rows in sections.items():
        if (not a.section or name in a.section) and rows:
            print(f"{name}: {summary(rows)}")


if __name__ == "__main__":
    main()
