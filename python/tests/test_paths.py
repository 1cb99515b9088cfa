"""cellseq.sequence_paths / order_paths: the order, direction and start of polylines."""

import itertools
import math

import numpy as np
import pytest

import cellseq


def travel(paths, start=None):
    """Pen-up travel between consecutive paths (and from `start`)."""
    t = sum(math.dist(a[-1], b[0]) for a, b in zip(paths, paths[1:]))
    return t + (math.dist(start, paths[0][0]) if start is not None else 0.0)


def random_paths(n, seed, closed_every=0):
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        k = int(rng.integers(2, 6))
        p = rng.uniform(0, 100, size=(k, 2))
        if closed_every and i % closed_every == 0:
            p = np.vstack([p, p[:1]]) if k >= 3 else p
        out.append(p)
    return out


def brute(paths, reversible):
    """The least travel between paths over every order and direction (open paths)."""
    best = math.inf
    for order in itertools.permutations(range(len(paths))):
        dirs = itertools.product([False, True], repeat=len(paths)) if reversible else [
            (False,) * len(paths)]
        for ds in dirs:
            seq = [paths[i][::-1] if d else paths[i] for i, d in zip(order, ds)]
            best = min(best, travel(seq))
    return best


@pytest.mark.parametrize("n", [2, 3, 5, 6])
def test_small_layers_are_optimal(n):
    paths = random_paths(n, seed=n)
    new, r = cellseq.order_paths(paths, max_evals=2_000_000)
    assert r["pen_up_after"] == pytest.approx(travel(new))
    assert travel(new) == pytest.approx(brute(paths, True), abs=1e-9)
    fixed, _ = cellseq.order_paths(paths, reversible=False, max_evals=2_000_000)
    assert all(r2 is False for r2 in _["reversed"])
    assert travel(fixed) == pytest.approx(brute(paths, False), abs=1e-9)


def test_every_path_keeps_its_points():
    paths = random_paths(300, seed=9, closed_every=3)
    new, r = cellseq.order_paths(paths)
    assert sorted(r["order"]) == list(range(300))
    assert r["pen_up_after"] <= r["pen_up_before"]
    assert r["pen_up_after"] == pytest.approx(travel(new))
    assert r["pen_up_before"] == pytest.approx(travel(paths))
    rotated = 0
    for i, p, rev, k in zip(r["order"], new, r["reversed"], r["start"]):
        src = paths[i]
        if rev:
            assert np.array_equal(p, src[::-1])
        elif k:
            # a closed path from another vertex: the same cycle of points
            rotated += 1
            assert np.array_equal(src[0], src[-1]) and np.array_equal(p[0], p[-1])
            assert np.array_equal(p[0], src[k])
            ring = list(map(tuple, src[:-1]))
            assert list(map(tuple, p[:-1])) == ring[k:] + ring[:k]
        else:
            assert np.array_equal(p, src)
    assert rotated > 0


def test_deterministic_and_seeded():
    paths = random_paths(200, seed=1)
    a = cellseq.sequence_paths(paths, max_evals=300_000, seed=4)
    b = cellseq.sequence_paths(paths, max_evals=300_000, seed=4)
    assert a["order"] == b["order"] and a["reversed"] == b["reversed"]


def test_a_start_counts_the_lead_in():
    paths = random_paths(50, seed=3)
    free = cellseq.sequence_paths(paths)
    assert free["lead_in_after"] is None
    at = cellseq.sequence_paths(paths, start=(0.0, 0.0))
    new = [paths[i][::-1] if rv else paths[i] for i, rv in zip(at["order"], at["reversed"])]
    assert at["lead_in_after"] == pytest.approx(math.dist((0, 0), new[0][0]))
    assert at["lead_in_after"] + at["pen_up_after"] <= at["lead_in_before"] + at["pen_up_before"]


def test_the_given_order_is_kept_when_not_beaten():
    line = [np.array([[0.0, 0], [1, 0]]), np.array([[1.0, 0], [2, 0]]), np.array([[2.0, 0], [3, 0]]),
            np.array([[3.0, 0], [4, 0]]), np.array([[4.0, 0], [5, 0]])]
    r = cellseq.sequence_paths(line)
    assert r["order"] == [0, 1, 2, 3, 4] and r["kept_original"] and r["pen_up_after"] == 0


def test_bad_paths_are_refused():
    with pytest.raises(ValueError, match="path 1"):
        cellseq.sequence_paths([np.zeros((2, 2)), np.zeros((3, 3))])
    with pytest.raises(ValueError, match="path 0"):
        cellseq.sequence_paths([np.array([[0.0, np.inf], [1, 1]])])
    with pytest.raises(ValueError, match="path 0"):
        cellseq.sequence_paths([np.zeros((0, 2))])
    with pytest.raises(ValueError, match="max_starts"):
        cellseq.sequence_paths([np.zeros((2, 2))], max_starts=0)
    with pytest.raises(ValueError, match="solver"):
        cellseq.sequence_paths([np.zeros((2, 2))], solver="nope")
    assert cellseq.sequence_paths([])["order"] == []
