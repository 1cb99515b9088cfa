#!/usr/bin/env python3
"""Run the SOP peers (OR-Tools, LKH-3) over a list of instances; print a
markdown table and (optionally) append JSON lines to a results file.

usage: bench_sop.py SOP_FILES... [--peers ortools,lkh,lkh-quick] [--time-limit S]
                    [--lkh PATH/TO/LKH] [--seed K] [--out results.jsonl]

peers:
  ortools    OR-Tools routing, greedy feasible start + guided local search,
             stops at --time-limit (wall clock)
  lkh        LKH-3, SPECIAL, RUNS=1, MAX_TRIALS=10^9, TIME_LIMIT=--time-limit
             (LKH counts user CPU time of the search, preprocessing excluded)
  lkh-quick  LKH-3, SPECIAL, RUNS=1, MAX_TRIALS=n (LKH default trials), no limit
  vrpcli-levels  Rust vrp-cli with hard job order = precedence-DAG depth
             (restricted model, see vrpcli_sop.py); needs --vrp-cli PATH
  cellseq    this project's `cellseq solve --json` (--cellseq PATH, --solver NAME,
             --time-limit S); one thread
  cpsat      OR-Tools CP-SAT exact model (see cpsat_sop.py), --workers threads;
             the JSON output also records status and lower_bound
"""

import argparse
import json
import os
import sys

import sop_common as sc
import safe_files


def run_cellseq(path, a):
    import subprocess
    import time
    t0 = time.time()
    cmd = [a.cellseq, "solve", path, "--json", "--time-limit", str(a.time_limit),
           "--seed", str(a.seed)]
    if a.solver:
        cmd += ["--solver", a.solver]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    r = json.loads(out)
    # re-check the path with the peers' own checker, as for every other peer
    _, _, matrix = sc.read_sop(path)
    tour = [int(v["cell"]) - 1 for v in r["sequence"]]
    cost = sc.check_tour(matrix, tour)
    return {"peer": "cellseq", "instance": sc.instance_name(path), "cost": cost,
            "wall_s": time.time() - t0, "solver": r["solver"]}


def run_one(peer, path, a):
    if peer == "cellseq":
        return run_cellseq(path, a)
    if peer == "ortools":
        import ortools_sop
        return ortools_sop.solve(path, time_limit=a.time_limit)
    if peer == "vrpcli-levels":
        import vrpcli_sop
        if not a.vrp_cli:
            raise SystemExit("--vrp-cli PATH (or VRP_CLI) is required for vrpcli-levels")
        return vrpcli_sop.solve(path, a.vrp_cli, time_limit=a.time_limit, mode="levels")
    if peer == "cpsat":
        import cpsat_sop
        return cpsat_sop.solve(path, time_limit=a.time_limit, workers=a.workers)
    if peer in ("lkh", "lkh-quick"):
        import lkh_sop
        if not a.lkh:
            raise SystemExit("--lkh PATH (or LKH_BIN) is required for the lkh peers")
        if peer == "lkh":
            r = lkh_sop.solve(path, a.lkh, time_limit=a.time_limit, runs=1,
                              max_trials=10 ** 9, seed=a.seed)
        else:
            r = lkh_sop.solve(path, a.lkh, time_limit=10 ** 6, runs=1, seed=a.seed)
        r["peer"] = peer
        return r
    raise SystemExit("unknown peer " + peer)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--peers", default="cellseq,ortools,lkh")
    ap.add_argument("--time-limit", type=float, default=10.0)
    ap.add_argument("--lkh", default=os.environ.get("LKH_BIN"))
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=2, help="CP-SAT workers")
    ap.add_argument("--vrp-cli", default=os.environ.get("VRP_CLI"))
    ap.add_argument("--out", default=None, help="append JSON lines here")
    ap.add_argument("--cellseq", default=os.environ.get("CELLSEQ_BIN", "target/release/cellseq"),
                    help="path of the cellseq binary")
    ap.add_argument("--solver", default=None, help="cellseq solver (default: its default)")
    a = ap.parse_args()
    peers = [p for p in a.peers.split(",") if p]
    if not a.lkh:
        peers = [p for p in peers if not p.startswith("lkh")]
    print("| instance | n | best known | " + " | ".join(
        "%s cost | %s gap %% | %s time s" % (p, p, p) for p in peers) + " |")
    print("|---|---:|---:|" + "---:|---:|---:|" * len(peers))
    for path in a.files:
        name, n, _ = sc.read_sop(path)
        best = sc.best_known(path)
        cells = []
        for p in peers:
            try:
                r = run_one(p, path, a)
            except Exception as e:  # keep going, record the failure
                r = {"peer": p, "instance": sc.instance_name(path), "cost": None,
                     "error": str(e)[:300], "wall_s": None}
            if a.out:
                r2 = dict(r)
                r2.pop("tour", None)
                r2.pop("workdir", None)  # temp path of this machine
                safe_files.append_line(a.out, json.dumps(r2))
            g = sc.gap_pct(r.get("cost"), best)
            cost = r.get("cost")
            if p == "cpsat" and cost is not None:
                cost = "%s%s (lb %s)" % (cost, "*" if r.get("status") == "OPTIMAL" else "",
                                          r.get("lower_bound"))
            cells.append("%s | %s | %s" % (
                cost, "-" if g is None else "%.2f" % g,
                "-" if r.get("wall_s") is None else "%.2f" % r["wall_s"]))
        print("| %s | %d | %s | %s |" % (sc.instance_name(path), n, best, " | ".join(cells)))
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
