#!/usr/bin/env python3
"""Race `auto` plans on instance files at wall-clock limits, one run at a time.

Each instance runs with every variant at every limit and seed, one thread. A variant is a
plan (`--plan NAME=PLAN`, run as `--param plan=...`; an empty PLAN runs the built-in
portfolio's choice), a whole portfolio file (`--portfolio NAME=FILE`, run as
`--portfolio FILE`: its rules' beam shares and `after_beam` phases apply) or another cellseq
binary with its built-in portfolio (`--bin NAME=PATH`: a solver before and after a change
inside it). The table gives each variant's median cost over the seeds and its ratio to the
best median of that row; the last rows compare every variant with the first one (the
`--plan` variants come first, in the order given, then the `--portfolio` ones, then the
`--bin` ones) (geometric mean of the ratios, on how many rows it is better, worse or equal,
and a sign test on those rows); with several seeds a last row gives each variant's spread
between seeds, the noise a difference has to beat. Used to choose the `geometric-free` and
`dense` rules on generated families (notes/portfolio.md); for timed comparisons run it alone
at high priority.

    python3 scripts/plan_race.py FILES... --plan default='local-search:0.3,eacs:0.5,ils*:1' \\
        --plan free='local-search[two-level=on]:1' --plan rule= --limits 1 10 \\
        --objective air --tsv out.tsv --out out.md
    python3 scripts/plan_race.py FILES... --plan built-in= --portfolio mine=mine.toml \\
        --limits 10 --seeds 1 2 3
    python3 scripts/plan_race.py FILES... --bin before=/tmp/cellseq-before \\
        --bin after=target/release/cellseq --limits 10 --seeds 1 2 3
"""
import argparse
import math
import os
import statistics
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
from sop_common import cellseq_solve  # noqa: E402
import safe_files  # noqa: E402


def run(cellseq, path, variant, limit, objective, seed):
    kind, text = variant
    if kind == "bin":
        cellseq = text
    budget = ["--time-limit", str(limit)]
    if objective:
        budget += ["--objective", objective]
    if kind == "plan" and text:
        budget += ["--param", "plan=" + text]
    if kind == "portfolio":
        budget += ["--portfolio", text]
    try:
        d = cellseq_solve(cellseq, path, budget, seed)
    except RuntimeError as e:
        sys.exit(str(e))
    return d["cost"], d["evaluations"], d["elapsed_s"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--plan", action="append", default=[],
                    help="NAME=PLAN (an empty PLAN: the portfolio's rule); repeatable")
    ap.add_argument("--portfolio", action="append", default=[],
                    help="NAME=FILE: a portfolio file as a variant; repeatable")
    ap.add_argument("--bin", action="append", default=[],
                    help="NAME=PATH: a cellseq binary (its built-in portfolio) as a variant; repeatable")
    ap.add_argument("--limits", nargs="+", type=float, default=[1.0, 10.0])
    ap.add_argument("--objective", default=None, help="time, air or matrix (default: the file's)")
    ap.add_argument("--seeds", type=int, nargs="+", default=None,
                    help="solver seeds (the table shows the median cost); default 1")
    ap.add_argument("--seed", type=int, default=1, help="one solver seed (see --seeds)")
    ap.add_argument("--cellseq", default="target/release/cellseq")
    ap.add_argument("--tsv", help="write every run here")
    ap.add_argument("--out", help="write the markdown table here (default: stdout)")
    a = ap.parse_args()
    variants = []
    given_all = ([("plan", p) for p in a.plan] + [("portfolio", p) for p in a.portfolio]
                 + [("bin", p) for p in a.bin])
    for kind, given in given_all:
        name, eq, text = given.partition("=")
        if not name or not eq or (kind != "plan" and not text):
            sys.exit(f"--{kind} {given!r}: expected NAME={'PATH' if kind == 'bin' else kind.upper()}")
        if kind == "bin" and not os.access(text, os.X_OK):
            sys.exit(f"--bin {given!r}: {text} is not an executable file")
        if any(name == n for n, _ in variants):
            sys.exit(f"--{kind} {given!r}: the name {name!r} is used twice")
        variants.append((name, (kind, text)))
    if not variants:
        sys.exit("give at least one --plan, --portfolio or --bin")
    seeds = a.seeds or [a.seed]
    runs = []  # (file, limit, variant, cost, evaluations, seconds, seed)
    summary = []  # (file, limit, {variant: median cost}, {variant: [cost per seed]})
    for f in a.files:
        for lim in a.limits:
            costs = {}
            for seed in seeds:
                for name, variant in variants:
                    cost, evals, secs = run(a.cellseq, f, variant, lim, a.objective, seed)
                    costs.setdefault(name, []).append(cost)
                    runs.append((os.path.basename(f), lim, name, cost, evals, secs, seed))
                    print(f"{os.path.basename(f)} {lim} s seed {seed} {name}: {cost:.3f} "
                          f"({secs:.2f} s)", file=sys.stderr, flush=True)
            summary.append((os.path.basename(f), lim,
                            {n: statistics.median(c) for n, c in costs.items()}, costs))
    if a.tsv:
        rows = ["file\tlimit_s\tplan\tseed\tcost\tevaluations\telapsed_s\n"]
        rows += [f"{r[0]}\t{r[1]}\t{r[2]}\t{r[6]}\t{r[3]:.6f}\t{r[4]}\t{r[5]:.3f}\n" for r in runs]
        safe_files.write_text(a.tsv, "".join(rows))
    lines = table([n for n, _ in variants], summary)
    text = "\n".join(lines) + "\n"
    if a.out:
        safe_files.write_text(a.out, text)
    else:
        sys.stdout.write(text)


def sign_test_p(better, worse):
    """Two-sided sign test: the chance of a split at least this uneven between `better` and
    `worse` rows if either were as likely (ties left out); 1 when there is nothing to split."""
    n = better + worse
    k = min(better, worse)
    return min(1.0, 2 * sum(math.comb(n, i) for i in range(k + 1)) / 2 ** n) if n else 1.0


def seed_spread(names, summary):
    """Per variant: the median over rows of (max − min) ÷ median of its costs over the
    seeds, the noise a difference between variants has to beat."""
    spread = {n: [] for n in names}
    for _, _, med, costs in summary:
        for n in names:
            if len(costs[n]) > 1 and med[n] > 0:
                spread[n].append((max(costs[n]) - min(costs[n])) / med[n])
    return {n: statistics.median(v) if v else None for n, v in spread.items()}


def table(names, summary):
    """The markdown table: per row the medians and their ratio to the row's best, then every
    variant against the first (geometric mean of the ratios; better / worse / equal rows and
    the sign test's p on them) and, with several seeds, each variant's spread between seeds."""
    lines = ["| instance | limit s | " + " | ".join(names) + " | best |",
             "|---|---|" + "---|" * len(names) + "---|"]
    logs = {n: [] for n in names}
    tally = {n: [0, 0, 0] for n in names}
    for f, lim, costs, _ in summary:
        best = min(costs.values())
        cells = [f"{costs[n]:.1f} ({costs[n] / best:.4f})" if best > 0 else f"{costs[n]:.1f}"
                 for n in names]
        winner = min(names, key=lambda n: costs[n])
        lines.append(f"| {f} | {lim:g} | " + " | ".join(cells) + f" | {winner} |")
        ref = costs[names[0]]
        for n in names:
            if ref > 0 and costs[n] > 0:
                logs[n].append(math.log(costs[n] / ref))
            tally[n][0 if costs[n] < ref else 1 if costs[n] > ref else 2] += 1
    if len(names) > 1:
        gm = [f"{math.exp(sum(v) / len(v)):.4f}" if v else "–" for v in logs.values()]
        lines.append(f"| geometric mean ÷ {names[0]} | | " + " | ".join(gm) + " | |")
        lines.append("| better / worse / equal | | –" + "".join(
            " | {} / {} / {}".format(*tally[n]) for n in names[1:]) + " | |")
        lines.append("| sign test p (two-sided, ties left out) | | –" + "".join(
            f" | {sign_test_p(tally[n][0], tally[n][1]):.3f}" for n in names[1:]) + " | |")
    spread = seed_spread(names, summary)
    if any(v is not None for v in spread.values()):
        lines.append("| spread between seeds (median of (max − min) ÷ median) | | " + " | ".join(
            f"{spread[n]:.4f}" if spread[n] is not None else "–" for n in names) + " | |")
    return lines


if __name__ == "__main__":
    main()
