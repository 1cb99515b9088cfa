#!/usr/bin/env python3
"""cellseq and LKH-3 side by side on TSPLIB SOP files (the generated families), run alternately.

For every instance, time limit and seed, cellseq (`solve --json`, one thread) and LKH-3
(`lkh_sop.py`, SPECIAL, RUNS = 1, MAX_TRIALS = 10^9 so that only TIME_LIMIT stops it) run
one after the other on the same file; both tours are re-checked by `sop_common.check_tour`.
The table gives per instance and time limit the median cost of each over the seeds, the
best known value (a bks.csv beside the instance, see sop_common.best_known) or else
cellseq's lower bound (computed after its search), and cellseq / LKH-3.

The family, n and p columns (p: closure density %, or w= the window length of
`time-window`) come from the COMMENT line `cellseq generate` writes.

usage: families_vs_lkh.py FILE.sop... --lkh PATH [--cellseq PATH] [--time-limit 1 10]
                          [--seeds 1 2 3] [--out notes.md] [--jsonl runs.jsonl]
                          [--lkh-from-jsonl OLD.jsonl...]

`--lkh-from-jsonl` takes LKH-3's runs from earlier `--jsonl` files (same instance, time limit
and seed) instead of running it again, for a new cellseq against the same LKH-3 runs; those
records are written to the new `--jsonl` too, marked `"reused": true`. A run not found there
is made as usual.

Note: LKH's TIME_LIMIT counts its own user CPU time (getrusage) and excludes its
preprocessing; cellseq's --time-limit is wall-clock. On a loaded machine LKH therefore gets
more CPU than cellseq for the same limit; the table reports both wall times.
"""

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import lkh_sop  # noqa: E402
import safe_files  # noqa: E402
import sop_common as sc  # noqa: E402

UNBOUNDED_TRIALS = 1_000_000_000


def describe(path):
    """(family, n, p) from the `cellseq generate` COMMENT, else (name, dimension - 2, '')."""
    family, params = None, {}
    dim = None
    with open(path) as f:
        for line in f:
            if line.startswith("COMMENT:") and "cellseq generate" in line:
                words = line.split("cellseq generate", 1)[1].split()
                family = words[0]
                params = dict(w.split("=", 1) for w in words[1:] if "=" in w)
            elif line.startswith("DIMENSION"):
                dim = int(line.split(":")[1])
            elif line.startswith("EDGE_WEIGHT_SECTION"):
                break
    if family is None:
        return sc.instance_name(path), (dim or 2) - 2, ""
    # the precedence parameter: p (closure density %) or, for time-window, w (window length)
    prec = params.get("p") or (f"w={params['w']}" if "w" in params else "-")
    return family, int(params.get("n", (dim or 2) - 2)), prec


def run_cellseq(binary, path, limit, seed, bound=True):
    env = dict(os.environ, RAYON_NUM_THREADS="1")
    t0 = time.time()
    cmd = [binary, "solve", path, "--json", "--time-limit", str(limit), "--seed", str(seed)]
    if not bound:
        cmd.append("--no-bound")
    out = subprocess.run(cmd, capture_output=True, text=True, check=True, env=env).stdout
    wall = time.time() - t0
    r = json.loads(out)
    _, _, matrix = sc.read_sop(path)
    tour = [int(v["cell"]) - 1 for v in r["sequence"]]
    cost = sc.check_tour(matrix, tour)
    return {"peer": "cellseq", "cost": cost, "wall_s": round(wall, 2),
            "lower_bound": r.get("lower_bound")}


def run_lkh(binary, path, limit, seed, bound=True):
    r = lkh_sop.solve(path, binary, time_limit=limit, runs=1, max_trials=UNBOUNDED_TRIALS,
                      seed=seed, special=True)
    return {"peer": "lkh3", "cost": r["cost"], "wall_s": r["wall_s"], "lower_bound": None}


def fmt(x):
    if x is None:
        return "–"
    if isinstance(x, float) and not x.is_integer():
        return "%.1f" % x
    return "%d" % x


def best_known_summary(rows):
    """Per time limit, over the rows with a best known value: the mean gap of each peer's
    medians to it, how many are at it, and how many cellseq rows are at or below LKH-3."""
    out = ""
    for limit in sorted({r[3] for r in rows}):
        sel = [r for r in rows if r[3] == limit and r[6] not in (None, 0)]
        if not sel:
            continue
        gap = lambda v, b: 100.0 * (v - b) / b  # noqa: E731
        out += ("\n%g s, %d instances with a best known value: mean gap of the medians "
                "cellseq %.3f %%, LKH-3 %.3f %%; at the best known cellseq %d, LKH-3 %d; "
                "cellseq at or below LKH-3 on %d.\n" % (
                    limit, len(sel),
                    statistics.mean(gap(r[4], r[6]) for r in sel),
                    statistics.mean(gap(r[5], r[6]) for r in sel),
                    sum(r[4] <= r[6] for r in sel), sum(r[5] <= r[6] for r in sel),
                    sum(r[4] <= r[5] for r in sel)))
    return out


def reused_lkh_runs(paths):
    """LKH-3's runs in earlier --jsonl files, by (instance, time limit, seed); the last wins."""
    old = {}
    for path in paths:
        try:
            for r in sc.read_jsonl([path]):
                if r.get("peer") == "lkh3":
                    old[(r["instance"], float(r["time_limit"]), int(r["seed"]))] = r
        except (OSError, ValueError, KeyError, TypeError, AttributeError) as e:
            sys.exit("%s: not a --jsonl file of this script (%s)" % (path, e))
    return old


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--lkh", default=os.environ.get("LKH_BIN", "/work/scratch/lkh3/LKH"))
    ap.add_argument("--cellseq", default="target/release/cellseq")
    ap.add_argument("--time-limit", type=float, nargs="+", default=[1.0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--out", help="write the Markdown table here (else stdout)")
    ap.add_argument("--jsonl", help="append every run as a JSON line here")
    ap.add_argument("--lkh-from-jsonl", nargs="+", default=[], metavar="OLD.jsonl",
                    help="take LKH-3's runs from these earlier --jsonl files where they hold one")
    a = ap.parse_args()
    old = reused_lkh_runs(a.lkh_from_jsonl)
    if not os.path.exists(a.lkh) and not old:
        ap.error("no LKH-3 binary at %s (--lkh PATH or LKH_BIN)" % a.lkh)
    rows, loads = [], []
    for path in a.files:
        bound = None
        family, n, p = describe(path)
        best = sc.best_known(path)
        for limit in a.time_limit:
            runs = {"cellseq": [], "lkh3": []}
            for seed in a.seeds:
                # alternately: cellseq, then LKH-3, for every seed
                for peer, fn, binary in (("cellseq", run_cellseq, a.cellseq),
                                         ("lkh3", run_lkh, a.lkh)):
                    # cellseq's lower bound (after its search, outside the time limit) is
                    # computed on the first run of an instance only
                    key = (sc.instance_name(path), float(limit), seed)
                    if peer == "lkh3" and key in old:
                        r = dict(old[key], reused=True)
                    else:
                        if peer == "lkh3" and not os.path.exists(binary):
                            sys.exit("no LKH-3 run of %s at %g s seed %d in %s, and no binary "
                                     "at %s" % (key[0], limit, seed, a.lkh_from_jsonl, binary))
                        r = fn(binary, path, limit, seed, bound=(bound is None))
                        r.update(instance=key[0], time_limit=limit, seed=seed,
                                 loadavg=round(os.getloadavg()[0], 2))
                    loads.append(r["loadavg"])
                    runs[peer].append(r)
                    if r["lower_bound"] is not None:
                        bound = max(bound or 0, r["lower_bound"])
                    if a.jsonl:
                        safe_files.append_line(a.jsonl, json.dumps(r))
                    print(json.dumps(r), file=sys.stderr)
            med = {k: statistics.median(x["cost"] for x in v) for k, v in runs.items()}
            wall = {k: statistics.median(x["wall_s"] for x in v) for k, v in runs.items()}
            ratio = med["cellseq"] / med["lkh3"] if med["lkh3"] else float("inf")
            rows.append((family, n, p, limit, med["cellseq"], med["lkh3"], best, bound,
                         ratio, wall["cellseq"], wall["lkh3"], sc.instance_name(path)))
    lines = ["| family | n | p % | limit s | cellseq | LKH-3 | best known | cellseq lower bound "
             "| cellseq / LKH-3 | wall s cellseq / LKH-3 | instance |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append("| %s | %d | %s | %g | %s | %s | %s | %s | %s | %.1f / %.1f | %s |" % (
            r[0], r[1], r[2], r[3], fmt(r[4]), fmt(r[5]), fmt(r[6]), fmt(r[7]),
            "∞" if r[8] == float("inf") else "%.3f" % r[8], r[9], r[10], r[11]))
    text = "\n".join(lines) + "\n" + best_known_summary(rows)
    if loads:
        text += "\n1-minute load average at the end of each run: %.2f to %.2f (median %.2f).\n" % (
            min(loads), max(loads), statistics.median(loads))
    if a.out:
        safe_files.write_text(a.out, text)
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
