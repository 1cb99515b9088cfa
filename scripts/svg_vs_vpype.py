#!/usr/bin/env python3
"""Benchmark: `cellseq optimize` (default options) against vpype's best reading of every SVG of
the real-drawing corpus (tests/fixtures/svg/real/, sources in its SOURCES.md).

vpype reads a file one of three ways and `linesort --two-opt` sorts each layer it read:
  layers  vpype read --no-crop FILE linesort --two-opt write OUT   (top-level groups are layers)
  colours vpype read --no-crop --attr stroke FILE ...              (a layer per stroke colour,
                                                                    groups merged)
  merged  vpype read --no-crop --single-layer FILE ...             (everything one layer)
and cellseq runs with its defaults (`cellseq optimize FILE -o OUT --json`, which says the pen
and block semantics it used). Every output and the original are measured by vpype's own
reader, so all figures come from one code:
  pen-up in all: the plotter's travel drawing the file in document order (AxiDraw plots in
    document order), from the origin, between all paths (`vpype.read_svg`, one collection);
    the headline;
  within layers: vpype's metric, the sum of `LineCollection.pen_up_length()` over the layers
    of `vpype.read_multilayer_svg` (travel from the origin and between layers left out);
  pen-down: the sum of `LineCollection.length()` (they should agree up to curve flattening);
all in mm (vpype works in CSS px, 96 per inch). "vpype best" is the least pen-up in all of
the readings `--target` names: by default `layers` and `colours`, the readings that keep the
file's pens (per layer as vpype reads it, and groups merged into one layer per colour); the
`merged` reading draws every pen's paths interleaved, which no multi-pen plotter or
colour-coded laser job does, and is shown beside them (`--target layers,colours,merged`
makes it part of the target). The table says whether cellseq is at or below the target and
shows every reading. Not a timed test: wall times are for information only.

  python3 -m venv /work/venv-vpype && /work/venv-vpype/bin/pip install vpype==1.15.0
  cargo build --release
  /work/venv-vpype/bin/python scripts/svg_vs_vpype.py [--cellseq target/release/cellseq]
      [--dir tests/fixtures/svg/real] [--timeout 600] [--out notes/table.md]
      [--vpype-cache DIR] [--target layers,colours] [FILE ...]
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

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
import safe_files  # noqa: E402

PX_PER_MM = 96.0 / 25.4
QUANTIZATION = 0.1  # px: curve flattening of the reader (vpype's default)


def measure(path):
    """(pen-up mm within layers, pen-down mm, paths, layers, pen-up mm in all) of an SVG, read
    by vpype's reader. "In all" is the travel of drawing every path in document order from the
    origin: what a plotter does with the whole file."""
    import vpype

    doc = vpype.read_multilayer_svg(path, QUANTIZATION, crop=False)
    up = sum(float(layer.pen_up_length()[0]) for layer in doc.layers.values())
    down = sum(float(layer.length()) for layer in doc.layers.values())
    paths = sum(len(layer) for layer in doc.layers.values())
    lc, _, _ = vpype.read_svg(path, QUANTIZATION, crop=False)
    total = float(lc.pen_up_length()[0]) + (abs(lc.lines[0][0]) if len(lc) else 0.0)
    return (up / PX_PER_MM, down / PX_PER_MM, paths, len(doc.layers), total / PX_PER_MM)


READINGS = {
    "layers": [],
    "colours": ["--attr", "stroke"],
    "merged": ["--single-layer"],
}


def run(cmd, timeout):
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return None, "timeout after %ss" % timeout, time.perf_counter() - t0
    return p.returncode, (p.stderr or p.stdout).strip(), time.perf_counter() - t0


def one(svg, args, tmp):
    name = os.path.basename(svg)
    row = {"file": name, "vpype": {}, "vpype_s": {}, "vpype_error": {}}
    try:
        row["orig"] = measure(svg)
    except Exception as e:  # the reader itself refuses the file
        row["orig_error"] = "%s: %s" % (type(e).__name__, e)
    vpype_exe = os.path.join(os.path.dirname(sys.executable), "vpype")
    for reading, opts in READINGS.items():
        vout = os.path.join(args.vpype_cache or tmp, "vpype_%s_%s" % (reading, name))
        if args.vpype_cache and os.path.exists(vout):
            # vpype's output does not depend on cellseq: reuse it (its wall time is not measured)
            row["vpype_s"][reading] = float("nan")
            row["vpype"][reading] = measure(vout)
            continue
        # --no-crop: both tools draw the whole drawing (vpype crops to the page by default), so
        # the pen-down lengths agree and the pen-up travel is of the same drawing
        rc, msg, dt = run([vpype_exe, "read", "--no-crop"] + opts
                          + [svg, "linesort", "--two-opt", "write", vout], args.timeout)
        row["vpype_s"][reading] = dt
        if rc == 0 and os.path.exists(vout):
            row["vpype"][reading] = measure(vout)
        else:
            row["vpype_error"][reading] = msg.splitlines()[-1] if msg else "exit %s" % rc
    return cellseq_part(svg, name, row, args, tmp)


def cellseq_part(svg, name, row, args, tmp):
    cout = os.path.join(tmp, "cellseq_" + name)
    t0 = time.perf_counter()
    try:
        p = subprocess.run([args.cellseq, "optimize", svg, "-o", cout, "--json"],
                           capture_output=True, text=True, timeout=args.timeout)
        rc, msg = p.returncode, (p.stderr or p.stdout).strip()
    except subprocess.TimeoutExpired:
        p, rc, msg = None, None, "timeout after %ss" % args.timeout
    row["cellseq_s"] = time.perf_counter() - t0
    if rc == 0 and os.path.exists(cout):
        row["cellseq"] = measure(cout)
        try:
            sem = json.loads(p.stdout).get("semantics", {})
        except ValueError:
            sem = {}
        row["semantics"] = "%s / %s" % (sem.get("pens", "?"), sem.get("blocks", "?"))
    else:
        row["cellseq_error"] = msg.splitlines()[-1] if msg else "exit %s" % rc
    return row


def best(row, target):
    """(reading, pen-up in all) of vpype's best reading among `target`, or None."""
    got = [(row["vpype"][r][4], r) for r in target if r in row["vpype"]]
    return min(got) if got else None


def fmt(row, target):
    cell = lambda s: str(s).replace("|", "\\|")[:150]
    o, c = row.get("orig"), row.get("cellseq")
    v = row["vpype"]
    f = lambda m, k: "%.1f" % m[k] if m else "—"
    b = best(row, target)
    ratio, verdict = "—", "**no** (no output)"
    if b and c:
        ratio = "%.3f" % (c[4] / b[0]) if b[0] > 0 else ("1.000" if c[4] == 0 else "inf")
        verdict = "yes" if at_or_below(c[4], b[0]) else "**no**"
    elif not b:
        verdict = "n/a (vpype failed)"
    notes = []
    for k in ("orig_error", "cellseq_error"):
        if k in row:
            notes.append("%s: %s" % (k.split("_")[0], cell(row[k])))
    for r, e in row["vpype_error"].items():
        notes.append("vpype %s: %s" % (r, cell(e)))
    if o and c and o[1] > 0 and abs(c[1] - o[1]) > 0.01 * o[1]:
        notes.append("cellseq pen-down differs from the original by %.1f %%"
                     % (100 * (c[1] - o[1]) / o[1]))
    paths = "%d / %d" % (o[2], o[3]) if o else "—"
    readings = " / ".join(f(v.get(r), 4) for r in READINGS)
    secs = "%s / %.1f" % (" / ".join("%.1f" % row["vpype_s"].get(r, float("nan"))
                                     for r in READINGS), row.get("cellseq_s", 0))
    return ("| %s | %s | %s | %s | %s | %s (%s) | %s | %s | %s | %s / %s | %s | %s |") % (
        row["file"], paths, row.get("semantics", "—"), f(o, 4), readings,
        "%.1f" % b[0] if b else "—", b[1] if b else "—", f(c, 4), ratio, verdict,
        f(o, 1), f(c, 1), secs, "; ".join(notes))


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
        safe_files.write_text(
            args.out, "\n".join(head + [fmt_layer(r) for r in rows]) + "\n" + summary + "\n")


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
    ap.add_argument("--target", default="layers,colours",
                    help="the vpype readings whose best is the target (of %s)"
                    % ", ".join(READINGS))
    ap.add_argument("--per-layer", action="store_true",
                    help="compare the two searches on identical one-layer files instead")
    args = ap.parse_args()
    files = args.files or sorted(glob.glob(os.path.join(args.dir, "*.svg")))
    if not files:
        sys.exit("no SVG files found")
    if args.per_layer:
        return main_per_layer(files, args)
    target = [t.strip() for t in args.target.split(",") if t.strip()]
    if not target or any(t not in READINGS for t in target):
        sys.exit("--target: a comma-separated list of %s" % ", ".join(READINGS))
    head = ["| file | paths / layers | cellseq pens / blocks | pen-up in all: original "
            "| vpype layers / colours / merged | vpype best (%s) | cellseq | cellseq / best "
            "| cellseq ≤ best | pen-down orig / cellseq (mm) | wall s: vpype %s / cellseq "
            "| notes |" % (", ".join(target), " / ".join(READINGS)),
            "|---|---|---|---:|---|---|---:|---:|---|---|---|---|"]
    print("\n".join(head), flush=True)
    lines, rows = list(head), []
    with tempfile.TemporaryDirectory() as tmp:
        for f in files:
            row = one(f, args, tmp)
            rows.append(row)
            lines.append(fmt(row, target))
            print(lines[-1], flush=True)
    both = [r for r in rows if best(r, target) and r.get("cellseq")]
    ok = sum(1 for r in both if at_or_below(r["cellseq"][4], best(r, target)[0]))
    refused = sum(1 for r in rows if "cellseq_error" in r)
    summary = ("\ncellseq's default leaves no more pen-up travel (in all, document order) than "
               "vpype's best reading (%s, linesort --two-opt) on %d of %d files (%d with both "
               "results); %d refused or failed." % (", ".join(target), ok, len(rows),
                                                    len(both), refused))
    print(summary)
    lines.append(summary)
    if args.out:
        safe_files.write_text(args.out, "\n".join(lines) + "\n")
    print(json.dumps({"files": len(rows), "at_or_below": ok, "with_both": len(both),
                      "refused": refused}))


if __name__ == "__main__":
    main()
