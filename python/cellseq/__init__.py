"""cellseq for Python: sequencing of CNC machining cells.

An open, precedence-constrained, generalized asymmetric TSP (with one mode per cell, TSPLIB's
Sequential Ordering Problem): read or build an instance, solve it with any registry solver,
check a sequence independently, compute lower bounds, optimize G-code programs and drawings,
run experiment plans. The work is done by the Rust library (the extension module
``cellseq._cellseq``); this package adds the pure-Python helpers.

>>> import numpy as np, cellseq
>>> inst = cellseq.Instance.from_matrix(np.array([[0, 1, 9], [9, 0, 2], [9, 9, 0.0]]))
>>> cellseq.solve(inst, "exact", max_evals=10_000).cost
3.0

Guide: docs/python.md.
"""

from __future__ import annotations

from typing import Any, Optional, Sequence, Tuple, Union
import os

from ._cellseq import (  # noqa: F401  (the public API)
    __version__,
    CellseqError,
    InternalError,
    Instance,
    Optimized,
    ParseError,
    Result,
    SolverError,
    bounds,
    check,
    generate,
    generators,
    optimize_drawing,
    optimize_gcode,
    read,
    sequence_paths,
    solve,
    solvers,
)
from ._cellseq import run_plan as _run_plan

__all__ = [
    "__version__",
    "CellseqError",
    "InternalError",
    "Instance",
    "Optimized",
    "ParseError",
    "Result",
    "SolverError",
    "bounds",
    "check",
    "generate",
    "generators",
    "optimize_drawing",
    "optimize_gcode",
    "order_paths",
    "read",
    "run_plan",
    "sequence_paths",
    "solve",
    "solver_names",
    "solvers",
]


def solver_names() -> list:
    """The registry names of every solver (``auto`` first)."""
    return [s["name"] for s in solvers()]


def run_plan(
    plan: Union[str, "os.PathLike[str]"],
    out: Union[str, "os.PathLike[str]", None] = None,
    threads: Optional[int] = None,
    shard: Optional[Tuple[int, int]] = None,
    frame: Optional[bool] = None,
) -> Any:
    """Runs (or resumes) an experiment plan, as ``cellseq run PLAN`` does, and returns its
    results table: one row per trial with the columns of ``results.csv`` (docs/harness.md).

    ``out`` is the results directory (default ``results/<plan name>``), ``threads`` the
    workers (default all cores), ``shard`` ``(i, n)`` runs only shard i of n. The table is a
    pandas ``DataFrame`` when pandas is installed and ``frame`` is not False (``frame=True``
    requires pandas), else a list of dicts.
    """
    rows = _run_plan(
        os.fspath(plan),
        None if out is None else os.fspath(out),
        threads,
        shard,
    )
    return _table(rows, frame)


def _table(rows: list, frame: Optional[bool]) -> Any:
    """``rows`` as a pandas DataFrame when asked for or available, else as they are."""
    if frame is False:
        return rows
    try:
        import pandas as pd
    except ImportError:
        if frame:
            raise
        return rows
    return pd.DataFrame(rows)


def order_paths(paths: Sequence[Any], **options: Any) -> Tuple[list, dict]:
    """``paths`` (``(k, 2)`` arrays of x, y) in the order and direction of
    :func:`sequence_paths` (same options): returns the new list of arrays, each drawn from
    its start (reversed, or a closed path rotated to start at another vertex), and the dict
    of :func:`sequence_paths`. Every path keeps its points; only order, direction and a closed
    path's seam change.
    """
    import numpy as np

    arrays = [np.asarray(p, dtype=float) for p in paths]
    r = sequence_paths(arrays, **options)
    out = []
    for i, rev, k in zip(r["order"], r["reversed"], r["start"]):
        out.append(_oriented(arrays[i], rev, k))
    return out, r


def _oriented(p: Any, reversed_: bool, start: int) -> Any:
    """Path ``p`` drawn backwards, or (closed) from vertex ``start``."""
    import numpy as np

    if reversed_:
        return p[::-1].copy()
    if start == 0:
        return p
    # closed: p[-1] == p[0]; start at p[start], end there again
    return np.concatenate([p[start:-1], p[: start + 1]])
