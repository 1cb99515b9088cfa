#!/usr/bin/env python3
"""vpype's `linesort` beside the plugin's `cellsort` on SVGs: pen-up travel per layer (vpype's
metric, `pen_up_length`), pen-down length, and wall time of each command, in one process.

  scripts/cellsort_vs_linesort.py [FILE.svg ...] [--two-opt/--greedy] [--cellsort-args ARGS]
                                  [--out REPORT.md] [--json]

Default files: tests/fixtures/svg/real/*.svg. Needs vpype 1.15 and the cellseq package with
the vpype-cellseq plugin installed (scripts/test.sh makes such a venv: target/py-venv).
Both commands run in this process through `vpype_cli.execute` on the same document read once
with `read --no-crop`; times are of the sorting command alone (`sort_s`), each the best of
`--repeat` runs.
"""

import argparse
import copy
import glob
import json
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
import safe_files  # noqa: E402

import vpype_cli

MM_PER_PX = 25.4 / 96.0
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def layers(doc):
    """Per layer id: (lines, pen-up px, pen-down px)."""
    return {
        lid: (len(lc), lc.pen_up_length()[0], lc.length())
        for lid, lc in sorted(doc.layers.items())
    }


def timed(cmd, doc, repeat):
    """The document `cmd` makes of a copy of `doc`, and the best wall time of `repeat` runs."""
    best = float("inf")
    out = None
    for _ in range(repeat):
        d = copy.deepcopy(doc)
        t = time.perf_counter()
        out = vpype_cli.execute(cmd, document=d)
        best = min(best, time.perf_counter() - t)
    return out, best


def compare(path, two_opt=True, cellsort_args="", repeat=1):
    """One file's row: per-layer figures of the original, linesort and cellsort."""
    doc = vpype_cli.execute(f"read --no-crop '{path}'")
    ls_cmd = "linesort --two-opt" if two_opt else "linesort"
    ls, ls_s = timed(ls_cmd, doc, repeat)
    cs, cs_s = timed(f"cellsort {cellsort_args}", doc, repeat)
    return {
        "file": os.path.basename(path),
        "original": layers(doc),
        "linesort": layers(ls),
        "cellsort": layers(cs),
        "linesort_s": ls_s,
        "cellsort_s": cs_s,
    }


def row_md(r):
    o, l, c = r["original"], r["linesort"], r["cellsort"]
    up = lambda t: sum(v[1] for v in t.values()) * MM_PER_PX  # noqa: E731
    down = lambda t: sum(v[2] for v in t.values()) * MM_PER_PX  # noqa: E731
    worse = [lid for lid in c if c[lid][1] > l[lid][1] * (1 + 1e-9) + 1e-9]
    lines = sum(v[0] for v in o.values())
    return (
        f"| {r['file']} | {lines} / {len(o)} | {up(o):.1f} | {up(l):.1f} | {up(c):.1f} | "
        f"{up(c) / up(l) if up(l) > 0 else 1.0:.3f} | {'yes' if not worse else 'no: ' + str(worse)} | "
        f"{down(o):.1f} / {down(l):.1f} / {down(c):.1f} | "
        f"{r['linesort_s']:.3f} | {r['cellsort_s']:.3f} |"
    )


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*")
    ap.add_argument("--greedy", action="store_true", help="linesort without --two-opt")
    ap.add_argument("--cellsort-args", default="", help="options of cellsort, quoted")
    ap.add_argument("--repeat", type=int, default=1)
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--out")
    a = ap.parse_args()
    files = a.files or sorted(glob.glob(os.path.join(ROOT, "tests/fixtures/svg/real/*.svg")))
    rows = []
    for f in files:
        rows.append(compare(f, not a.greedy, a.cellsort_args, a.repeat))
        print(f"{rows[-1]['file']}: linesort {rows[-1]['linesort_s']:.3f} s, "
              f"cellsort {rows[-1]['cellsort_s']:.3f} s", file=sys.stderr)
    if a.json:
        print(json.dumps(rows, indent=1, default=str))
        return
    ls = "linesort" if a.greedy else "linesort --two-opt"
    head = [
        f"`{ls}` against `cellsort {a.cellsort_args}`; pen-up = vpype's `pen_up_length`"
        " (within layers), mm; sort time in seconds (best of "
        f"{a.repeat}), both in one process.",
        "",
        "| file | lines / layers | pen-up original | linesort | cellsort | cellsort / linesort "
        "| cellsort <= linesort on every layer | pen-down orig / linesort / cellsort "
        "| linesort s | cellsort s |",
        "|---|---|---:|---:|---:|---:|---|---|---:|---:|",
    ]
    body = [row_md(r) for r in rows]
    tot_l = sum(r["linesort_s"] for r in rows)
    tot_c = sum(r["cellsort_s"] for r in rows)
    foot = ["", f"Total sort time: linesort {tot_l:.2f} s, cellsort {tot_c:.2f} s."]
    text = "\n".join(head + body + foot) + "\n"
    if a.out:
        safe_files.write_text(a.out, text)
    print(text)


if __name__ == "__main__":
    main()
