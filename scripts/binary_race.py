#!/usr/bin/env python3
"""Race two or more cellseq binaries (`auto`, its built-in portfolio) on the same files.

For a change inside a solver rather than in the portfolio (which `plan_race.py` races):
build the binary before and after the change, then run them alternately on every file and
seed, one thread each (`--no-bound`), at a wall-clock limit or an evaluation budget. The
table gives each binary's median cost over the seeds; the last rows compare every binary
with the first one (geometric mean of the ratios of the medians, and on how many files it
is better, worse or equal). For timed comparisons run it alone at high priority.

    python3 scripts/binary_race.py FILES... --bin before=/tmp/cellseq-before \\
        --bin after=target/release/cellseq --limit 10 --seeds 1 2 3 --tsv runs.tsv --out t.md
"""
import argparse
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
from sop_common import cellseq_solve  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--bin", action="append", required=True,
                    help="NAME=PATH of a cellseq binary; repeatable, the first is the reference")
    ap.add_argument("--limit", type=float, help="wall-clock limit per run, seconds")
    ap.add_argument("--max-evals", help="evaluation budget per run instead of --limit")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--tsv", help="write every run here")
    ap.add_argument("--out", help="write the markdown table here (default: stdout)")
    a = ap.parse_args()
    bins = []
    for given in a.bin:
        name, eq, path = given.partition("=")
        if not name or not eq or not path:
            sys.exit(f"--bin {given!r}: expected NAME=PATH")
        if any(name == n for n, _ in bins):
            sys.exit(f"--bin {given!r}: the name {name!r} is used twice")
        if not os.access(path, os.X_OK):
            sys.exit(f"--bin {given!r}: {path} is not an executable file")
        bins.append((name, path))
    if len(bins) < 2:
        sys.exit("give at least two --bin")
    if (a.limit is None) == (a.max_evals is None):
        sys.exit("give one of --limit and --max-evals")
    budget = ["--time-limit", str(a.limit)] if a.limit is not None else ["--max-evals", a.max_evals]
    tsv = open(a.tsv, "w") if a.tsv else None
    if tsv:
        tsv.write("file\tbinary\tseed\tcost\tevaluations\telapsed_s\n")
    rows = []
    for f in a.files:
        costs = {n: [] for n, _ in bins}
        for seed in a.seeds:
            for name, path in bins:
                try:
                    d = cellseq_solve(path, f, budget, seed)
                except RuntimeError as e:
                    sys.exit(str(e))
                costs[name].append(d["cost"])
                print(f"{f} seed {seed} {name}: {d['cost']:.3f} ({d['elapsed_s']:.2f} s)",
                      file=sys.stderr, flush=True)
                if tsv:
                    tsv.write(f"{f}\t{name}\t{seed}\t{d['cost']:.6f}\t{d['evaluations']}\t"
                              f"{d['elapsed_s']:.3f}\n")
                    tsv.flush()
        rows.append((os.path.basename(f), {n: statistics.median(v) for n, v in costs.items()}))
    names = [n for n, _ in bins]
    what = f"{a.limit:g} s" if a.limit is not None else f"{a.max_evals} evaluations"
    out = [f"Median cost over seeds {' '.join(map(str, a.seeds))}, {what} per run, one thread.",
           "", "| file | " + " | ".join(names) + " |", "|---" * (len(names) + 1) + "|"]
    for f, med in rows:
        out.append(f"| {f} | " + " | ".join(f"{med[n]:.6g}" for n in names) + " |")
    ref = names[0]
    for n in names[1:]:
        r = [med[n] / med[ref] for _, med in rows if med[ref] > 0]
        if not r:
            continue
        g = math.exp(sum(math.log(x) for x in r) / len(r))
        better = sum(x < 1 - 1e-12 for x in r)
        worse = sum(x > 1 + 1e-12 for x in r)
        out.append(f"| {n} ÷ {ref}: geometric mean {g:.4f}; better / worse / equal "
                   f"{better} / {worse} / {len(r) - better - worse} |" + " |" * (len(names) - 1))
    text = "\n".join(out) + "\n"
    if a.out:
        with open(a.out, "w") as fh:
            fh.write(text)
    print(text)


if __name__ == "__main__":
    main()
