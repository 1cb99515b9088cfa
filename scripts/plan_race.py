#!/usr/bin/env python3
"""Race `auto` plans on instance files at wall-clock limits, one run at a time.

Each instance runs with every plan (`--param plan=...`; the name `rule` runs the built-in
portfolio's choice) at every limit, one thread, and the table gives each plan's cost over
the best cost of that row. Used to choose the `geometric-free` rule on the generated
`uniform` family (notes/portfolio.md); for timed comparisons run it alone at high priority.

    python3 scripts/plan_race.py FILES... --plan default='local-search:0.3,eacs:0.5,ils*:1' \\
        --plan free='local-search[two-level=on]:1' --plan rule= --limits 1 10 \\
        --objective air --tsv out.tsv --out out.md
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
from sop_common import cellseq_solve  # noqa: E402


def run(cellseq, path, plan, limit, objective, seed):
    budget = ["--time-limit", str(limit)]
    if objective:
        budget += ["--objective", objective]
    if plan:
        budget += ["--param", "plan=" + plan]
    try:
        d = cellseq_solve(cellseq, path, budget, seed)
    except RuntimeError as e:
        sys.exit(str(e))
    return d["cost"], d["evaluations"], d["elapsed_s"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--plan", action="append", required=True,
                    help="NAME=PLAN (an empty PLAN: the portfolio's rule); repeatable")
    ap.add_argument("--limits", nargs="+", type=float, default=[1.0, 10.0])
    ap.add_argument("--objective", default=None, help="time, air or matrix (default: the file's)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--cellseq", default="target/release/cellseq")
    ap.add_argument("--tsv", help="write every run here")
    ap.add_argument("--out", help="write the markdown table here (default: stdout)")
    a = ap.parse_args()
    plans = []
    for p in a.plan:
        name, _, text = p.partition("=")
        if not name:
            sys.exit(f"--plan {p!r}: expected NAME=PLAN")
        plans.append((name, text))
    rows = []
    for f in a.files:
        for lim in a.limits:
            costs = {}
            for name, plan in plans:
                cost, evals, secs = run(a.cellseq, f, plan, lim, a.objective, a.seed)
                costs[name] = cost
                rows.append((os.path.basename(f), lim, name, cost, evals, secs))
                print(f"{os.path.basename(f)} {lim} s {name}: {cost:.3f} ({secs:.2f} s)",
                      file=sys.stderr, flush=True)
            rows.append((os.path.basename(f), lim, None, costs, None, None))
    if a.tsv:
        with open(a.tsv, "w") as t:
            t.write("file\tlimit_s\tplan\tcost\tevaluations\telapsed_s\n")
            for r in rows:
                if r[2] is not None:
                    t.write(f"{r[0]}\t{r[1]}\t{r[2]}\t{r[3]:.6f}\t{r[4]}\t{r[5]:.3f}\n")
    names = [n for n, _ in plans]
    lines = ["| instance | limit s | " + " | ".join(names) + " | best |",
             "|---|---|" + "---|" * len(names) + "---|"]
    for r in rows:
        if r[2] is None:
            costs = r[3]
            best = min(costs.values())
            cells = [f"{costs[n]:.1f} ({costs[n] / best:.4f})" if best > 0 else f"{costs[n]:.1f}"
                     for n in names]
            winner = min(names, key=lambda n: costs[n])
            lines.append(f"| {r[0]} | {r[1]:g} | " + " | ".join(cells) + f" | {winner} |")
    text = "\n".join(lines) + "\n"
    if a.out:
        with open(a.out, "w") as o:
            o.write(text)
    else:
        sys.stdout.write(text)


if __name__ == "__main__":
    main()
