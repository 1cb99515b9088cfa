"""vpype plugin: ``cellsort`` sequences each layer's lines with cellseq.

Each line is a cell of a cellseq instance: an open line may be drawn in either direction
(unless ``--no-flip``), a closed line (last point equal to the first) may start at one of
``--max-starts`` evenly spaced vertices; the ``drawing`` solver orders them for the least
pen-up travel (:func:`cellseq.sequence_paths`). Layers keep their order, ids and properties.
"""

from __future__ import annotations

import time
from typing import List, Optional, Tuple

import click
import numpy as np
import vpype as vp
import vpype_cli

import cellseq

__all__ = ["cellsort", "sort_layer"]

#: Millimetres per vpype unit (CSS pixel).
MM_PER_PX = 25.4 / 96.0


def _xy(line: np.ndarray) -> np.ndarray:
    """A vpype line (complex array) as a ``(k, 2)`` array of x, y."""
    return np.column_stack((line.real, line.imag))


def _oriented(line: np.ndarray, reversed_: bool, start: int) -> np.ndarray:
    """``line`` drawn backwards, or (closed) from vertex ``start``."""
    if reversed_:
        return line[::-1].copy()
    if start == 0:
        return line
    return np.concatenate([line[start:-1], line[: start + 1]])


def sort_layer(
    lines: vp.LineCollection,
    start: Optional[Tuple[float, float]] = None,
    **options,
) -> Tuple[List[np.ndarray], dict]:
    """The lines of one layer in cellseq's order, and :func:`cellseq.sequence_paths`' dict.

    ``start`` is where the pen is before the layer; ``None`` (vpype's convention, as
    ``linesort``): anywhere, only the travel between lines counts.
    """
    src = [line for line in lines]
    r = cellseq.sequence_paths([_xy(line) for line in src], start=start, **options)
    out = [_oriented(src[i], rev, k) for i, rev, k in zip(r["order"], r["reversed"], r["start"])]
    return out, r


def _layer_budget(
    time_limit: Optional[float], t0: float, lines: int, left: int
) -> Optional[float]:
    """This layer's share of what is left of the time limit, by its number of lines."""
    if time_limit is None:
        return None
    remaining = time_limit - (time.perf_counter() - t0)
    # a little is kept for rebuilding the layers
    share = max(remaining * 0.97, 0.0) * lines / max(left, 1)
    return max(share, 1e-3)


@click.command()
@click.option(
    "-t",
    "--time-limit",
    type=click.FloatRange(min=0.0, min_open=True, max=1e6),
    default=None,
    help="Seconds for the whole command, shared among layers by their number of lines "
    "(default: an evaluation budget of 4000 per line, at least 10^6 per layer: the same "
    "result on any machine).",
)
@click.option(
    "--max-evals",
    type=click.IntRange(min=1),
    default=None,
    help="Evaluation budget of each layer (deterministic).",
)
@click.option("--seed", type=click.IntRange(min=0, max=2**64 - 1), default=1, help="Seed.")
@click.option(
    "-f",
    "--no-flip",
    is_flag=True,
    help="Keep every line's direction (and every closed line's first vertex).",
)
@click.option(
    "--max-starts",
    type=click.IntRange(min=1, max=1000),
    default=8,
    help="Start vertices tried per closed line (evenly spaced; 1: only its first).",
)
@click.option(
    "--from-origin",
    is_flag=True,
    help="Count the travel from the origin to the first line and between layers (the pen "
    "starts at (0, 0) and each layer where the previous one ended) instead of vpype's "
    "within-layer travel.",
)
@click.option(
    "--solver",
    default="drawing",
    help="cellseq registry solver (default `drawing`).",
)
@vpype_cli.global_processor
def cellsort(
    document: vp.Document,
    time_limit: Optional[float],
    max_evals: Optional[int],
    seed: int,
    no_flip: bool,
    max_starts: int,
    from_origin: bool,
    solver: str,
) -> vp.Document:
    """Sort each layer's lines with cellseq for the least pen-up travel.

    Like `linesort` (lines may be drawn backwards unless --no-flip), with cellseq's `drawing`
    solver: greedy construction, 2-opt and Or-opt with reversal, iterated local search; a
    closed line may also start at another vertex. A layer's order is kept unless the new one
    is shorter. Layers keep their order and properties. Prints the pen-up travel before and
    after (vpype's metric, within layers) to stderr.
    """
    t0 = time.perf_counter()
    ids = list(document.layers.keys())
    total = sum(len(document.layers[i]) for i in ids)
    left = total
    before = after = 0.0
    pen: Optional[Tuple[float, float]] = (0.0, 0.0) if from_origin else None
    for lid in ids:
        lc = document.layers[lid]
        n = len(lc)
        before += lc.pen_up_length()[0]
        if n == 0:
            continue
        new, r = sort_layer(
            lc,
            start=pen,
            reversible=not no_flip,
            max_starts=max_starts,
            solver=solver,
            time_limit=_layer_budget(time_limit, t0, n, left),
            max_evals=max_evals,
            seed=seed,
        )
        left -= n
        out = vp.LineCollection(new)
        after += out.pen_up_length()[0]
        document.replace(out, lid)
        if from_origin:
            end = new[-1][-1]
            pen = (float(end.real), float(end.imag))
    gain = 100.0 * (before - after) / before if before > 0 else 0.0
    click.echo(
        f"cellsort: pen-up {before * MM_PER_PX:.1f} -> {after * MM_PER_PX:.1f} mm "
        f"(-{gain:.1f} %), {len(ids)} layer(s), {total} lines, "
        f"{time.perf_counter() - t0:.2f} s",
        err=True,
    )
    return document


cellsort.help_group = "Plugins"
