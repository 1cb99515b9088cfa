#!/usr/bin/env python3
"""The benchmark targets of issue 28 on TSPLIB SOP / PCGTSPLIB: `auto` at a time limit.

For every instance file (`.sop`, `.pcglns`, `.pcgtsp`) in the given directories and every
seed, runs `cellseq solve FILE --time-limit S --seed K --json --no-bound` with one thread
(RAYON_NUM_THREADS=1) and compares the cost with the `best_known` that `solve` reads from
the `bks.csv` beside the instance. Per directory it prints the number of instances whose
median cost over the seeds is at or below the best known, and the mean gap of the medians.
Every run is also written as a JSON line (--jsonl). Run it at a high priority on a quiet
core (`nice -n -10`): it is wall-clock timed.

usage: targets.py DIR... [--time-limit 10] [--seeds 1 2 3] [--cellseq PATH]
                  [--portfolio FILE] [--jsonl runs.jsonl] [--out table.md]
"""

import argparse
import json
import os
import statistics
import sys

from sop_common import cellseq_solve

EXTS = (".sop", ".pcglns", ".pcgtsp")


def solve(binary, path, limit, seed, portfolio):
    return cellseq_solve(binary, path, ["--time-limit", str(limit)], seed, portfolio)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--cellseq", default="target/release/cellseq")
    ap.add_argument("--time-limit", type=float, default=10.0)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1])
    ap.add_argument("--portfolio")
    ap.add_argument("--jsonl")
    ap.add_argument("--out")
    a = ap.parse_args()
    lines = ["| set | limit s | seeds | instances | median at or below best known | "
             "mean gap % (medians) | worst gap % | load average |",
             "|---|---|---|---|---|---|---|---|"]
    misses = []
    for d in a.dirs:
        files = sorted(os.path.join(d, f) for f in os.listdir(d) if f.endswith(EXTS))
        at, gaps, loads = 0, [], []
        for path in files:
            costs, best = [], None
            for seed in a.seeds:
                r = solve(a.cellseq, path, a.time_limit, seed, a.portfolio)
                load = round(os.getloadavg()[0], 2)
                loads.append(load)
                costs.append(r["cost"])
                best = r.get("best_known")
                rec = {"instance": r["instance"], "set": os.path.basename(d.rstrip("/")),
                       "time_limit": a.time_limit, "seed": seed, "cost": r["cost"],
                       "best_known": best, "elapsed_s": r["elapsed_s"], "loadavg": load}
                print(json.dumps(rec), file=sys.stderr)
                if a.jsonl:
                    with open(a.jsonl, "a") as f:
                        f.write(json.dumps(rec) + "\n")
            med = statistics.median(costs)
            if best is None:
                continue
            gap = 100.0 * (med - best) / best if best else 0.0
            gaps.append(gap)
            if med <= best + 1e-9:
                at += 1
            else:
                misses.append((os.path.basename(path), med, best, gap))
        lines.append("| %s | %g | %s | %d | %d/%d | %.3f | %.3f | %.2f–%.2f |" % (
            os.path.basename(d.rstrip("/")), a.time_limit, " ".join(map(str, a.seeds)),
            len(files), at, len(gaps), statistics.mean(gaps) if gaps else 0.0,
            max(gaps) if gaps else 0.0, min(loads or [0]), max(loads or [0])))
    text = "\n".join(lines) + "\n"
    if misses:
        text += "\nAbove the best known: " + ", ".join(
            "%s %g vs %g (+%.2f %%)" % m for m in misses) + "\n"
    if a.out:
        with open(a.out, "w") as f:
            f.write(text)
    sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
