#!/usr/bin/env python3
"""Improving carry moves left in solutions of a TSPLIB SOP instance (notes/lab/carry.md).

A carry move (engine::carry) moves one cell forward past the precedence successors in its way
and carries a segment of at most three cells that holds all of them to a place after the
cell's new one; backward, the same with predecessors. This scan tries every such move,
without the candidate lists the solver uses, builds each new order from its definition and
checks it in full: an independent count of the moves a walk's record still holds.

    python3 scripts/carry_scan.py INSTANCE.sop A.json [B.json ...]
        per solution: its cost, the number of improving forward and backward carry moves and
        the best gain of each (0: none)

The solutions are `cellseq solve --out` files (cellseq-solution/1 JSON).
"""

import argparse
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "peers"))
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from sequence_diff import read_or_exit, read_sequence  # noqa: E402
from sop_common import precedence_pairs, read_sop, tour_cost  # noqa: E402

MAX_CARRIED = 3


def feasible(seq, pairs):
    pos = {c: k for k, c in enumerate(seq)}
    return all(pos[a] < pos[b] for a, b in pairs)


def forward_moves(M, seq, after, pairs):
    """Gains (< 0) of the improving carry moves of `seq` in which a cell moves forward past
    the cells of `after[cell]` in its way; costs from M."""
    n = len(seq)
    base = tour_cost(M, seq)
    gains = []
    for a in range(n):
        x = seq[a]
        for b in range(a + 1, n):
            blockers = [q for q in range(a + 1, b + 1) if seq[q] in after[x]]
            if not blockers:
                continue
            f, last = blockers[0], blockers[-1]
            for st in range(a + 1, f + 1):
                for en in range(last, min(b, st + MAX_CARRIED)):
                    seg = seq[st:en + 1]
                    for t in range(b, n):
                        new = []
                        for q, y in enumerate(seq):
                            if q != a and not st <= q <= en:
                                new.append(y)
                            if q == b:
                                new.append(x)
                                if t == b:
                                    new.extend(seg)
                            if q == t and t > b:
                                new.extend(seg)
                        cost = tour_cost(M, new)
                        if cost < base and feasible(new, pairs):
                            gains.append(cost - base)
    return gains


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("instance")
    ap.add_argument("solutions", nargs="+")
    args = ap.parse_args()
    _, n, M = read_or_exit(args.instance, read_sop)
    pairs = precedence_pairs(M)
    succ = [set() for _ in range(n)]
    pred = [set() for _ in range(n)]
    for a, b in pairs:
        succ[a].add(b)
        pred[b].add(a)
    # backward moves are forward moves of the reversed order on the transposed costs
    MT = [[M[j][i] for j in range(n)] for i in range(n)]
    rpairs = [(b, a) for a, b in pairs]
    for path in args.solutions:
        seq = read_sequence(path, n)
        fw = forward_moves(M, seq, succ, pairs)
        bw = forward_moves(MT, seq[::-1], pred, rpairs)
        print(f"{path}: cost {tour_cost(M, seq):g} forward {len(fw)} best {min(fw, default=0):g} "
              f"backward {len(bw)} best {min(bw, default=0):g}")


if __name__ == "__main__":
    main()
