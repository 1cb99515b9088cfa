#!/usr/bin/env python3
"""Where two solutions of one TSPLIB SOP instance differ, and what their best mix costs.

A research aid for walks that stall (notes/lab/dense-traps.md). Two sequences of the same
cells split into *windows*: maximal runs of positions that differ while the prefixes before
and after them hold the same set of cells. Windows that touch are merged (their shared link
depends on both). Outside the windows both sequences agree, so each window can be taken
from either sequence: the cheapest such mix is the result of a partition crossover
(`ils --param cross=true` does the same with every kick).

    python3 scripts/sequence_diff.py INSTANCE.sop A.json B.json [C.json ...]
        every pair: the cost of each, its windows (positions, length, cost in each
        sequence, cells displaced: not on a longest common order) and the mix's cost
    python3 scripts/sequence_diff.py INSTANCE.sop A.json --window 130 193 --out W.sop
        positions 130..193 of A as an instance of its own (the cells before and after it as
        the fixed start and end, precedence among the window's cells kept), for
        `cellseq solve W.sop --solver beam` to say whether the window's order is optimal

The solutions are `cellseq solve --out` files (cellseq-solution/1 JSON); a TSPLIB SOP file's
cells are named 1..n for its nodes 0..n-1.
"""

import argparse
import bisect
import itertools
import json
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
from sop_common import read_sop, tour_cost, write_sop  # noqa: E402


def read_or_exit(path, read):
    """read(path), or an exit naming the file and the problem (no traceback)."""
    try:
        return read(path)
    except (OSError, ValueError, KeyError, TypeError) as e:
        sys.exit(f"{path}: {e.__class__.__name__}: {e}")


def read_sequence(path, n):
    """The node order (0-based) of a cellseq solution file of a TSPLIB SOP instance."""

    def read(p):
        with open(p) as f:
            return [int(v["cell"]) - 1 for v in json.load(f)["sequence"]]

    seq = read_or_exit(path, read)
    if sorted(seq) != list(range(n)):
        sys.exit(f"{path}: not a sequence of the instance's {n} nodes")
    return seq


def windows(a, b):
    """Position ranges (inclusive) where a and b differ between equal prefix sets, merged
    when they touch."""
    found, start, sa, sb = [], 0, set(), set()
    for k, (x, y) in enumerate(zip(a, b)):
        sa.add(x)
        sb.add(y)
        if sa == sb:
            if a[start:k + 1] != b[start:k + 1]:
                found.append((start, k))
            start = k + 1
    merged = []
    for w in found:
        if merged and w[0] <= merged[-1][1] + 1:
            merged[-1] = (merged[-1][0], w[1])
        else:
            merged.append(w)
    return merged


def span_cost(M, seq, s, e):
    """Cost of the links from position s-1 to position e+1 (the window and its two ends)."""
    lo, hi = max(s - 1, 0), min(e + 1, len(seq) - 1)
    return sum(M[seq[k]][seq[k + 1]] for k in range(lo, hi))


def displaced(a, b, s, e):
    """Cells of window s..e that leave a's order in b: not on a longest common subsequence."""
    pos = {c: k for k, c in enumerate(b[s:e + 1])}
    perm = [pos[c] for c in a[s:e + 1]]
    tails = []
    for x in perm:
        k = bisect.bisect_left(tails, x)
        tails[k:k + 1] = [x]
    return len(perm) - len(tails)


def compare(M, named):
    for (na, a), (nb, b) in itertools.combinations(named, 2):
        ca, cb = tour_cost(M, a), tour_cost(M, b)
        mix = ca
        print(f"{na} ({ca:g}) against {nb} ({cb:g})")
        for s, e in windows(a, b):
            wa, wb = span_cost(M, a, s, e), span_cost(M, b, s, e)
            mix += min(wa, wb) - wa
            print(f"  positions {s}-{e}: {e - s + 1} cells, {displaced(a, b, s, e)} displaced, "
                  f"cost {wa:g} against {wb:g}")
        print(f"  best mix (partition crossover): {mix:g}")


def write_window(M, seq, s, e, out):
    """Positions s..e of seq as a TSPLIB SOP instance anchored at seq[s-1] and seq[e+1]."""
    if not 1 <= s <= e < len(seq) - 1:
        sys.exit(f"window {s}..{e}: must lie within 1..{len(seq) - 2}")
    nodes = [seq[s - 1]] + seq[s:e + 1] + [seq[e + 1]]
    k = len(nodes)
    rows = []
    for x, i in enumerate(nodes):
        row = []
        for y, j in enumerate(nodes):
            if x == y:
                row.append(0)
            elif y == 0 or x == k - 1:
                row.append(-1)  # the start before every node, every node before the end
            elif M[i][j] == -1:
                row.append(-1)  # j before i, as in the instance
            else:
                row.append(max(M[i][j], 0))
        rows.append(row)
    write_sop(out, f"window-{s}-{e}", rows)
    print(f"wrote {out}: {k} nodes, the window's cost in the sequence {span_cost(M, seq, s, e):g}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("instance")
    ap.add_argument("solutions", nargs="+")
    ap.add_argument("--window", nargs=2, type=int, metavar=("START", "END"))
    ap.add_argument("--out")
    args = ap.parse_args()
    _, n, M = read_or_exit(args.instance, read_sop)
    named = [(p, read_sequence(p, n)) for p in args.solutions]
    if args.window:
        if not args.out or len(named) != 1:
            sys.exit("--window takes one solution and --out")
        write_window(M, named[0][1], *args.window, args.out)
    else:
        compare(M, named)


if __name__ == "__main__":
    main()
