#!/usr/bin/env python3
"""Benchmark: `cellseq optimize` (default options) against `vpype linesort --two-opt` on every
SVG of the real-drawing corpus (tests/fixtures/svg/real/, sources in its SOURCES.md).

For each file:
  vpype read --no-crop FILE linesort --two-opt write OUT_vpype.svg
  cellseq optimize FILE -o OUT_cellseq.svg
and the original and both outputs are read by ONE reader, vpype's own
`vpype.read_multilayer_svg(path, quantization, crop=False)`, so every figure comes from the same
code: pen-up travel = sum over layers of `LineCollection.pen_up_length()` (end of a path to the
start of the next in the same layer; the travel from the origin and between layers is not
counted, for either tool: vpype's own metric), pen-down length = sum of
`LineCollection.length()`; both in mm (vpype works in CSS px, 96 per inch). A second figure,
"pen-up in all", adds the travel from the origin to the first path and between layers (layers
in the order the file has them): what a plotter travels drawing the whole file. This is the
headline figure (issue 25 asks for the plotter's pen-up travel); vpype's within-layer metric
is beside it. The table says whether cellseq is at or below vpype on each, and the pen-down
lengths beside each other (they should agree up to curve flattening). Not a timed test: wall times are printed for information
only.

  python3 -m venv /tmp/corpus-vpenv && /tmp/corpus-vpenv/bin/pip install vpype==1.15.0
  cargo build --release
  /tmp/corpus-vpenv/bin/python scripts/svg_vs_vpype.py [--cellseq target/release/cellseq]
      [--dir tests/fixtures/svg/real] [--timeout 600] [--out notes/table.md]
      [--vpype-cache DIR] [FILE ...]
  ... scripts/svg_vs_vpype.py --per-layer [--out notes/per-layer.md] [FILE ...]

--per-layer measures the two searches on identical scopes: every layer of every file, as
vpype's reader sees it (curves already flattened), is written by vpype as its own one-layer,
one-colour SVG, and both tools sequence that same file; the figure compared is the pen-up
travel within the layer without the leg from the origin (vpype's metric).

Every tool runs in a child process with a timeout; a refusal or a timeout is a row of the table,
never a silent gap.
"""

import argparse
import glob
import json
import os
import subprocess
import sys
import tempfile
import time

PX_PER_MM = 96.0 / 25.4
QUANTIZATION = 0.1  # px: curve flattening of the reader (vpype's default)


def measure(path):
    """(pen-up mm within layers, pen-down mm, paths, layers, pen-up mm in all) of an SVG, read
    by vpype's reader. "In all" adds the travel from the origin to the first path and from
    each layer's last path to the next layer's first, in the order the file has its layers:
    the travel a plotter makes drawing the whole file in one go."""
    import vpype

    doc = vpype.read_multilayer_svg(path, QUANTIZATION, crop=False)
    up = sum(float(layer.pen_up_length()[0]) for layer in doc.layers.values())
    down = sum(float(layer.length()) for layer in doc.layers.values())
    paths = sum(len(layer) for layer in doc.layers.values())
    at, links = 0j, 0.0
    for layer in doc.layers.values():
        if len(layer):
            links += abs(layer.lines[0][0] - at)
            at = layer.lines[-1][-1]
    return (up / PX_PER_MM, down / PX_PER_MM, paths, len(doc.layers),
            (up + links) / PX_PER_MM)


def run(cmd, timeout):
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, "timeout after %ss" % timeout, time.perf_counter() - t0
    return p.returncode, (p.stderr or p.stdout).strip(), time.perf_counter() - t0


def one(svg, args, tmp):
    name = os.path.basename(svg)
    row = {"file": name}
    try:
        row["orig"] = measure(svg)
    except Exception as e:  # the reader itself refuses the file
        row["orig_error"] = "%s: %s" % (type(e).__name__, e)
    vout = os.path.join(args.vpype_cache or tmp, "vpype_" + name)
    vpype_exe = os.path.join(os.path.dirname(sys.executable), "vpype")
    if args.vpype_cache and os.path.exists(vout):
        # vpype's output does not depend on cellseq: reuse it (its wall time is not measured)
        row["vpype_s"] = float("nan")
        row["vpype"] = measure(vout)
        return cellseq_part(svg, name, row, args, tmp)
    # --no-crop: both tools draw the whole drawing (vpype crops to the page by default), so
    # the pen-down lengths agree and the pen-up travel is of the same drawing
    rc, msg, dt = run([vpype_exe, "read", "--no-crop", svg, "linesort", "--two-opt", "write",
                       vout],
                      args.timeout)
    row["vpype_s"] = dt
    if rc == 0 and os.path.exists(vout):
        row["vpype"] = measure(vout)
    else:
        row["vpype_error"] = msg.splitlines()[-1] if msg else "exit %s" % rc
    return cellseq_part(svg, name, row, args, tmp)


def cellseq_part(svg, name, row, args, tmp):
    cout = os.path.join(tmp, "cellseq_" + name)
    rc, msg, dt = run([args.cellseq, "optimize", svg, "-o", cout], args.timeout)
    row["cellseq_s"] = dt
    if rc == 0 and os.path.exists(cout):
        row["cellseq"] = measure(cout)
    else:
        row["cellseq_error"] = msg.splitlines()[-1] if msg else "exit %s" % rc
    return row


def fmt(row):
    cell = lambda s: str(s).replace("|", "\\|")[:150]
    o, v, c = row.get("orig"), row.get("vpype"), row.get("cellseq")
    f = lambda m, k: "%.1f" % m[k] if m else "—"
    ratio, verdict, verdict_in = "—", "**no** (no output)", "**no**"
    if v and c:
        ratio = "%.3f" % (c[4] / v[4]) if v[4] > 0 else ("1.000" if c[4] == 0 else "inf")
        verdict = "yes" if at_or_below(c[4], v[4]) else "**no**"
        verdict_in = "yes" if at_or_below(c[0], v[0]) else "**no**"
    elif not v:
        verdict = verdict_in = "n/a (vpype failed)"
    notes = []
    for k in ("orig_error", "vpype_error", "cellseq_error"):
        if k in row:
            notes.append("%s: %s" % (k.split("_")[0], cell(row[k])))
    if o and c and o[1] > 0 and abs(c[1] - o[1]) > 0.01 * o[1]:
        notes.append("cellseq pen-down differs from the original by %.1f %%"
                     % (100 * (c[1] - o[1]) / o[1]))
    paths = "%d / %d" % (o[2], o[3]) if o else "—"
    return ("| %s | %s | %s / %s / %s | %s | %s | %s / %s / %s | %s | %s / %s / %s "
            "| %.1f / %.1f | %s |") % (
        row["file"], paths, f(o, 4), f(v, 4), f(c, 4), ratio, verdict,
        f(o, 0), f(v, 0), f(c, 0), verdict_in, f(o, 1), f(v, 1), f(c, 1),
        row.get("vpype_s", 0), row.get("cellseq_s", 0), "; ".join(notes))


def at_or_below(c, v):
    return c <= v * (1 + 1e-9) + 1e-6


def per_layer(files, args, tmp):
    """Rows of the identical-scope comparison: one per (file, vpype layer)."""
    import vpype

    vpype_exe = os.path.join(os.path.dirname(sys.executable), "vpype")
    rows = []
    for svg in files:
        name = os.path.basename(svg)
        doc = vpype.read_multilayer_svg(svg, QUANTIZATION, crop=False)
        for lid, lc in doc.layers.items():
            if len(lc) < 2:
                continue
            one_doc = vpype.Document(page_size=doc.page_size)
            one_doc.add(lc, layer_id=1)
            src = os.path.join(tmp, "layer%d_%s" % (lid, name))
            with open(src, "w") as fh:
                vpype.write_svg(fh, one_doc, set_date=False)
            row = {"file": name, "layer": lid, "paths": len(lc),
                   "orig": measure(src)[0]}
            # the same travel with the leg from the origin (what cellseq minimizes)
            row["vpype_o"] = row["cellseq_o"] = None
            vout = os.path.join(tmp, "vpype_layer%d_%s" % (lid, name))
            rc, msg, _ = run([vpype_exe, "read", "--no-crop", src, "linesort", "--two-opt",
                              "write", vout], args.timeout)
            if rc == 0:
                m = measure(vout)
                row["vpype"], row["vpype_o"] = m[0], m[4]
            else:
                row["vpype"] = None
            cout = os.path.join(tmp, "cellseq_layer%d_%s" % (lid, name))
            rc, msg, _ = run([args.cellseq, "optimize", src, "-o", cout], args.timeout)
            if rc == 0:
                m = measure(cout)
                row["cellseq"], row["cellseq_o"] = m[0], m[4]
            else:
                row["cellseq"] = None
            row["error"] = None if rc == 0 else msg.splitlines()[-1:]
            rows.append(row)
            print(fmt_layer(row), flush=True)
    return rows


def main_per_layer(files, args):
    head = ["| file | vpype layer | paths | pen-up original (mm) | vpype two-opt | cellseq "
            "| cellseq / vpype | cellseq ≤ vpype | with origin leg: vpype / cellseq |",
            "|---|---:|---:|---:|---:|---:|---:|---|---|"]
    print("\n".join(head), flush=True)
    with tempfile.TemporaryDirectory() as tmp:
        rows = per_layer(files, args, tmp)
    both = [r for r in rows if r["vpype"] is not None and r["cellseq"] is not None]
    ok = sum(1 for r in both if at_or_below(r["cellseq"], r["vpype"]))
    summary = ("\nIdentical scopes: cellseq at or below vpype linesort --two-opt on %d of %d "
               "layers (%d with both results); sum %.1f mm against vpype's %.1f mm."
               % (ok, len(rows), len(both), sum(r["cellseq"] for r in both),
                  sum(r["vpype"] for r in both)))
    print(summary)
    if args.out:
        with open(args.out, "w") as fh:
            fh.write("\n".join(head + [fmt_layer(r) for r in rows]) + "\n" + summary + "\n")


def fmt_layer(r):
    v, c = r["vpype"], r["cellseq"]
    o = lambda x: "%.3f" % x if x is not None else "—"
    return "| %s | %d | %d | %.3f | %s | %s | %s | %s | %s / %s |" % (
        r["file"], r["layer"], r["paths"], r["orig"],
        "%.3f" % v if v is not None else "—", "%.3f" % c if c is not None else "—",
        "%.3f" % (c / v) if v and c is not None else "—",
        ("yes" if at_or_below(c, v) else "**no**") if v is not None and c is not None
        else "n/a", o(r["vpype_o"]), o(r["cellseq_o"]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("files", nargs="*")
    ap.add_argument("--dir", default=os.path.join(root, "tests/fixtures/svg/real"))
    ap.add_argument("--cellseq", default=os.path.join(root, "target/release/cellseq"))
    ap.add_argument("--timeout", type=float, default=600)
    ap.add_argument("--out", help="also write the Markdown table here")
    ap.add_argument("--vpype-cache", help="keep vpype's outputs in this directory and reuse "
                    "them on a later run (vpype's result does not depend on cellseq)")
    ap.add_argument("--per-layer", action="store_true",
                    help="compare the two searches on identical one-layer files instead")
    args = ap.parse_args()
    files = args.files or sorted(glob.glob(os.path.join(args.dir, "*.svg")))
    if not files:
        sys.exit("no SVG files found")
    if args.per_layer:
        return main_per_layer(files, args)
    head = ["| file | paths / layers | pen-up in all: orig / vpype / cellseq (mm) "
            "| cellseq / vpype | cellseq ≤ vpype | within layers (vpype's metric): orig / vpype "
            "/ cellseq | within: cellseq ≤ vpype | pen-down orig / vpype / cellseq (mm) "
            "| wall s vpype / cellseq | notes |",
            "|---|---|---|---:|---|---|---|---|---|---|"]
    print("\n".join(head), flush=True)
    lines, rows = list(head), []
    with tempfile.TemporaryDirectory() as tmp:
        for f in files:
            row = one(f, args, tmp)
            rows.append(row)
            lines.append(fmt(row))
            print(lines[-1], flush=True)
    both = [r for r in rows if r.get("vpype") and r.get("cellseq")]
    ok = sum(1 for r in both if at_or_below(r["cellseq"][0], r["vpype"][0]))
    ok_all = sum(1 for r in both if at_or_below(r["cellseq"][4], r["vpype"][4]))
    refused = sum(1 for r in rows if "cellseq_error" in r)
    summary = ("\ncellseq's default leaves no more pen-up travel than vpype linesort --two-opt "
               "on %d of %d files (the plotter's pen-up travel: from the origin, within and "
               "between layers); on vpype's own metric (within layers only) on %d of %d; "
               "%d refused or failed." % (ok_all, len(rows), ok, len(rows), refused))
    print(summary)
    lines.append(summary)
    if args.out:
        with open(args.out, "w") as fh:
            fh.write("\n".join(lines) + "\n")
    print(json.dumps({"files": len(rows), "at_or_below": ok_all, "at_or_below_within": ok,
                      "refused": refused}))


if __name__ == "__main__":
    main()
