#!/usr/bin/env python3
"""Compare `cellseq optimize` with vpype's `linesort` (greedy, and `--two-opt`) on SVG files:
pen-up travel (vpype's metric: sum of end->start distances between consecutive paths of a
layer, travel from the origin excluded, in mm) and wall time.

  python3 -m venv /tmp/vpenv && /tmp/vpenv/bin/pip install vpype==1.15.0
  /tmp/vpenv/bin/python scripts/peers/vpype_compare.py gen OUT.svg --paths 50000 --seed 1
  /tmp/vpenv/bin/python scripts/peers/vpype_compare.py run A.svg [B.svg ...] \
      --cellseq target/release/cellseq [--solvers drawing,greedy] [--timeout 400] \
      [--modes greedy,two-opt] [--time-limit S]

Every peer runs in a child process, one at a time. The pen-up of cellseq's output is measured
by reading the written SVG with vpype's own reader, so both tools are scored by the same code.
The generator writes the same kind of drawing as ../shared/peers/vpype_linesort_bench.py
(`gen --kind strokes`): short random-walk strokes scattered over an A3 page, in mm.
"""

import argparse
import json
import math
import os
import random
import subprocess
import sys
import tempfile
import time

from vpype_linesort_bench import write_polylines

PX_PER_MM = 96.0 / 25.4


def gen_svg(path, n_paths, seed=1, width=420.0, height=297.0):
    rnd = random.Random(seed)
    polys = []
    for _ in range(n_paths):
        x, y = rnd.uniform(5, width - 5), rnd.uniform(5, height - 5)
        pts = [(x, y)]
        ang = rnd.uniform(0, 2 * math.pi)
        for _ in range(rnd.randint(1, 6)):
            ang += rnd.gauss(0, 0.6)
            step = rnd.uniform(0.5, 3.0)
            x = min(max(x + step * math.cos(ang), 0), width)
            y = min(max(y + step * math.sin(ang), 0), height)
            pts.append((x, y))
        polys.append(pts)
    write_polylines(path, polys, width, height)


def pen_up_mm(svg):
    """vpype's metric on a file read by vpype."""
    import vpype_cli
    doc = vpype_cli.execute("read --no-crop '%s'" % svg)
    pen_up = sum(layer.pen_up_length()[0] for layer in doc.layers.values())
    n = sum(len(layer) for layer in doc.layers.values())
    return float(pen_up) / PX_PER_MM, n


def vpype_one(svg, mode, out):
    """Child: read, linesort (timed), write; prints JSON."""
    import vpype_cli
    doc = vpype_cli.execute("read --no-crop '%s'" % svg)
    cmd = "linesort" + (" --two-opt" if mode == "two-opt" else "")
    t0 = time.perf_counter()
    doc = vpype_cli.execute(cmd, document=doc)
    sort_s = time.perf_counter() - t0
    vpype_cli.execute("write '%s'" % out, document=doc)
    print(json.dumps({"sort_s": sort_s}))


def run_vpype(svg, mode, timeout, tmp):
    out = os.path.join(tmp, "vpype.%s.svg" % mode)
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, os.path.abspath(__file__), "_vpype", svg, mode, out],
                           capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"tool": "vpype linesort " + mode, "error": "timeout after %ss" % timeout}
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        return {"tool": "vpype linesort " + mode, "error": p.stderr[-300:]}
    r = json.loads(p.stdout.strip().splitlines()[-1])
    mm, n = pen_up_mm(out)
    return {"tool": "vpype linesort " + mode, "paths": n, "pen_up_mm": round(mm, 1),
            "sort_s": round(r["sort_s"], 3), "wall_s": round(wall, 3)}


def run_cellseq(exe, svg, solver, time_limit, timeout, tmp):
    out = os.path.join(tmp, "cellseq.%s.svg" % solver)
    cmd = [exe, "optimize", svg, "-o", out, "--json", "--solver", solver, "--skip-unsupported"]
    if time_limit is not None:
        cmd += ["--time-limit", str(time_limit)]
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"tool": "cellseq " + solver, "error": "timeout after %ss" % timeout}
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        return {"tool": "cellseq " + solver, "error": p.stderr[-300:]}
    j = json.loads(p.stdout)
    mm, n = pen_up_mm(out)
    return {"tool": "cellseq " + solver, "paths": n, "pen_up_mm": round(mm, 1),
            "own_pen_up_mm": round(j["after"]["pen_up_mm"], 1),
            "sort_s": round(j["solve_s"], 3), "wall_s": round(wall, 3)}


def main():
    if len(sys.argv) > 1 and sys.argv[1] == "_vpype":
        vpype_one(sys.argv[2], sys.argv[3], sys.argv[4])
        return 0
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    g = sub.add_parser("gen")
    g.add_argument("out")
    g.add_argument("--paths", type=int, required=True)
    g.add_argument("--seed", type=int, default=1)
    r = sub.add_parser("run")
    r.add_argument("svg", nargs="+")
    r.add_argument("--cellseq", default="target/release/cellseq")
    r.add_argument("--solvers", default="drawing,greedy")
    r.add_argument("--modes", default="greedy,two-opt")
    r.add_argument("--time-limit", type=float, default=None)
    r.add_argument("--timeout", type=float, default=400)
    a = ap.parse_args()
    if a.cmd == "gen":
        gen_svg(a.out, a.paths, a.seed)
        return 0
    print("| svg | tool | paths | pen-up mm (vpype metric) | sort s | wall s |")
    print("|---|---|---:|---:|---:|---:|")
    for svg in a.svg:
        with tempfile.TemporaryDirectory() as tmp:
            before, n = pen_up_mm(svg)
            print("| %s | (file order) | %d | %.1f | - | - |" % (os.path.basename(svg), n, before))
            rows = [run_vpype(svg, m, a.timeout, tmp) for m in a.modes.split(",") if m]
            rows += [run_cellseq(a.cellseq, svg, s, a.time_limit, a.timeout, tmp)
                     for s in a.solvers.split(",") if s]
            for row in rows:
                if "error" in row:
                    print("| %s | %s | - | %s | - | - |" % (os.path.basename(svg), row["tool"],
                                                        row["error"].replace("\n", " ")))
                else:
                    print("| %s | %s | %d | %.1f | %.3f | %.3f |" % (
                        os.path.basename(svg), row["tool"], row["paths"], row["pen_up_mm"],
                        row["sort_s"], row["wall_s"]), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
