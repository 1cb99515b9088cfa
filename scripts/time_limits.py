#!/usr/bin/env python3
"""Hold every solver to `--time-limit` on generated instances, from small to large.

For each instance of the set below (generated with `cellseq generate` into OUT, seeded) and
each solver of the registry (`cellseq solvers`; those that do not apply to the instance are
skipped by their own refusal), runs

    cellseq solve FILE --solver NAME --time-limit L --json [--no-bound]

one at a time, and records the wall time of the whole command, its peak resident memory
(from wait4), the exit status and the cost, beside the time `cellseq validate FILE` takes
(reading and validating, the median of three). The overrun is wall - max(L, read): the
promise of docs/bad-input.md ("Time limits"). Prints one table row per run and, at the end,
the largest overrun. Writes OUT/time_limits.tsv.

usage: time_limits.py OUT [--cellseq target/release/cellseq] [--limit 1] [--set small|large|all]
                          [--solvers a,b,...] [--no-bound]

The `small` set is the defect's regime (issue 50): random asymmetric costs in a small range
without inner precedence (`random-sop` p=0, `atsp` amat) at 200-400 cells, plus dense and
sparse precedence; `large` adds 1000-5000 matrix nodes and 10^4-10^5 geometric cells. The
machine's load shows in the wall times: compare runs made side by side, not across days.
"""

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
import safe_files  # noqa: E402

SMALL = [
    ("random-sop", {"n": 198, "c": 100, "p": 0}),
    ("random-sop", {"n": 298, "c": 100, "p": 0}),
    ("random-sop", {"n": 398, "c": 100, "p": 0}),
    ("random-sop", {"n": 398, "c": 1000, "p": 1}),
    ("random-sop", {"n": 298, "c": 10, "p": 15}),
    ("atsp", {"n": 400, "c": 100, "class": "amat"}),
    ("random-sop", {"n": 300, "c": 100, "p": 90}),
    ("generalized", {"n": 200, "p": 5, "modes": 4, "open": 0.5}),
    ("geometric-sparse", {"n": 1000}),
]

LARGE = [
    ("random-sop", {"n": 1000, "c": 100, "p": 0}),
    ("random-sop", {"n": 3000, "c": 100, "p": 0}),
    ("random-sop", {"n": 4998, "c": 100, "p": 15}),
    ("atsp", {"n": 4998, "c": 100, "class": "amat"}),
    ("geometric-sparse", {"n": 10000}),
    ("geometric-sparse", {"n": 100000}),
    ("uniform", {"n": 100000}),
]


def generate(binary, out, kind, params, seed=1):
    name = kind + "-" + "-".join(f"{k}{v}" for k, v in params.items()) + f"-s{seed}"
    ext = ".sop" if kind in ("random-sop", "atsp") else ".json"
    path = out / (name + ext)
    if not path.exists():
        cmd = [binary, "generate", kind, "--seed", str(seed), "-o", str(path)]
        for k, v in params.items():
            cmd += ["--param", f"{k}={v}"]
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
    return path


def read_time(binary, path):
    """Median wall time of `cellseq validate FILE` over three runs: reading and validating."""
    times = []
    for _ in range(3):
        t0 = time.monotonic()
        subprocess.run([binary, "validate", str(path)], check=True, stdout=subprocess.DEVNULL)
        times.append(time.monotonic() - t0)
    return sorted(times)[1]


def solvers(binary):
    text = subprocess.run([binary, "solvers"], check=True, capture_output=True, text=True).stdout
    return [line.split()[0] for line in text.splitlines() if line and not line[0].isspace()]


def run(binary, path, solver, limit, no_bound):
    cmd = [binary, "solve", str(path), "--solver", solver, "--time-limit", str(limit), "--json"]
    if no_bound:
        cmd.append("--no-bound")
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        t0 = time.monotonic()
        p = subprocess.Popen(cmd, stdout=out, stderr=err)
        _, status, usage = os.wait4(p.pid, 0)
        wall = time.monotonic() - t0
        out.seek(0)
        err.seek(0)
        text, note = out.read(), err.read().decode(errors="replace").strip()[:120]
    code = os.waitstatus_to_exitcode(status)
    cost = ""
    if code == 0:
        try:
            cost = json.loads(text)["cost"]
        except (ValueError, KeyError):
            cost = "?"
    return wall, usage.ru_maxrss, code, cost, note


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("out", type=Path)
    ap.add_argument("--cellseq", default="target/release/cellseq")
    ap.add_argument("--limit", type=float, default=1.0)
    ap.add_argument("--set", choices=["small", "large", "all"], default="small")
    ap.add_argument("--solvers", default="")
    ap.add_argument("--no-bound", action="store_true")
    a = ap.parse_args()
    a.out.mkdir(parents=True, exist_ok=True)
    todo = {"small": SMALL, "large": LARGE, "all": SMALL + LARGE}[a.set]
    names = a.solvers.split(",") if a.solvers else solvers(a.cellseq)
    rows = []
    head = "instance\tsolver\tread_s\twall_s\tover_s\tpeak_mb\texit\tcost\tnote"
    print(head, flush=True)
    for kind, params in todo:
        path = generate(a.cellseq, a.out, kind, params)
        read = read_time(a.cellseq, path)
        for s in names:
            wall, rss, code, cost, err = run(a.cellseq, path, s, a.limit, a.no_bound)
            # the promise: the limit, or the reading when that alone takes longer
            over = wall - max(a.limit, read)
            row = [path.name, s, f"{read:.3f}", f"{wall:.3f}", f"{over:+.3f}",
                   f"{rss / 1024:.0f}", str(code), str(cost), err if code else ""]
            rows.append(row)
            print("\t".join(row), flush=True)
    safe_files.write_text(a.out / "time_limits.tsv",
                          "".join(line + "\n" for line in [head] + ["\t".join(r) for r in rows]))
    worst = max(rows, key=lambda r: float(r[4]))
    print(f"# largest overrun past max(limit, read): {worst[4]} s ({worst[1]} on {worst[0]},"
          f" read {worst[2]} s), limit {a.limit} s", file=sys.stderr)


if __name__ == "__main__":
    main()
