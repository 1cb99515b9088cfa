"""Type stubs of the cellseq package (the extension module and the Python helpers)."""

import os
from typing import Any, Callable, Dict, Iterable, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, "os.PathLike[str]"]
_Visit = Union[int, Tuple[int, int]]
_Param = Union[int, float, bool, str]

class CellseqError(ValueError):
    """An input cellseq refuses; ``file`` and ``line`` name where, when known."""

    file: Optional[str]
    line: Optional[int]

class ParseError(CellseqError):
    """A text file is malformed at ``file``, line ``line``."""

class SolverError(RuntimeError):
    """A solver gave up (a memory limit, an instance it does not support)."""

class InternalError(RuntimeError):
    """A bug in cellseq: a Rust panic caught before it reached Python."""

class Instance:
    """Cells (each with one or more modes), precedence, and geometry or a cost matrix."""

    @staticmethod
    def from_matrix(
        costs: npt.ArrayLike,
        precedence: Optional[Iterable[Tuple[int, int]]] = None,
        modes: Optional[Sequence[int]] = None,
        name: str = "matrix",
    ) -> Instance:
        """An instance from a square cost matrix and ``(before, after)`` cell pairs."""
    @property
    def name(self) -> str: ...
    @property
    def n(self) -> int:
        """Number of cells."""
    def __len__(self) -> int: ...
    @property
    def modes(self) -> List[int]:
        """Number of modes of each cell."""
    @property
    def cell_ids(self) -> List[str]: ...
    @property
    def precedence(self) -> List[Tuple[int, int]]: ...
    @property
    def is_matrix(self) -> bool: ...
    @property
    def default_objective(self) -> str: ...
    @property
    def as_given(self) -> Optional[List[Tuple[int, int]]]:
        """The as-programmed order, when the instance has one."""
    @property
    def entry_points(self) -> Optional[npt.NDArray[np.float64]]:
        """``(n, 2)`` entry points of the cells' first modes (geometric instances)."""
    @property
    def metadata(self) -> Dict[str, Any]: ...
    def save(self, path: _Path) -> None:
        """Writes the instance (cellseq JSON, or TSPLIB SOP for ``.sop``), atomically."""

class Result:
    """A verified result of :func:`solve`."""

    @property
    def cost(self) -> float: ...
    @property
    def sequence(self) -> List[Tuple[int, int]]:
        """``(cell, mode)`` pairs, 0-based."""
    @property
    def lower_bound(self) -> Optional[float]: ...
    @property
    def proven_optimal(self) -> bool: ...
    @property
    def certified_gap_percent(self) -> Optional[float]: ...
    @property
    def report(self) -> Dict[str, float]:
        """The checker's figures: cost, air_length, cut_length, path_length, lifts,
        tool_changes, machining_time."""
    @property
    def trace(self) -> npt.NDArray[np.float64]:
        """``(k, 3)``: evaluations, seconds, cost at every improvement."""
    @property
    def solver(self) -> str: ...
    @property
    def seed(self) -> int: ...
    @property
    def objective(self) -> str: ...
    @property
    def evaluations(self) -> int: ...
    @property
    def elapsed_s(self) -> float: ...
    @property
    def params(self) -> Dict[str, str]: ...
    def to_dict(self, best_known: Optional[float] = None) -> Dict[str, Any]:
        """The object ``cellseq solve --json`` prints."""
    def save(self, path: _Path) -> None:
        """Writes the solution file (``cellseq-solution/1``), atomically."""

class Optimized:
    """An optimized program or drawing: the new text and the report of ``--json``."""

    @property
    def text(self) -> str: ...
    @property
    def report(self) -> Dict[str, Any]: ...
    def save(self, path: _Path, overwrite_input: bool = False) -> None: ...

def read(path: _Path) -> Instance:
    """Reads an instance file (``.sop``, ``.pcglns``, ``.pcgtsp``, cellseq ``.json``)."""

def generate(kind: str, seed: int = 1, params: Optional[Dict[str, _Param]] = None) -> Instance:
    """Generates an instance of ``kind`` (see :func:`generators`)."""

def generators() -> List[Dict[str, Any]]: ...
def solvers() -> List[Dict[str, Any]]: ...
def solver_names() -> List[str]: ...
def solve(
    instance: Instance,
    solver: str = "auto",
    time_limit: Optional[float] = None,
    max_evals: Optional[int] = None,
    seed: int = 1,
    params: Optional[Dict[str, _Param]] = None,
    *,
    objective: Optional[str] = None,
    lower_bound: bool = True,
    progress: Optional[Callable[[int, float, float], Any]] = None,
) -> Result:
    """Solves ``instance`` with a registry solver; the result is checked independently."""

def check(
    instance: Instance, sequence: Iterable[_Visit], objective: Optional[str] = None
) -> Dict[str, float]:
    """The independent checker's report, or ``CellseqError`` naming the broken rule."""

def bounds(instance: Instance, objective: Optional[str] = None) -> Dict[str, Any]:
    """Valid lower bounds: ``best``, ``best_name``, ``parts``."""

def optimize_gcode(
    path: Optional[_Path] = None,
    *,
    text: Optional[str] = None,
    solver: str = "auto",
    time_limit: Optional[float] = None,
    max_evals: Optional[int] = None,
    seed: int = 1,
    merge_tool_blocks: bool = False,
    reversible: Optional[bool] = None,
    margin: float = 0.5,
) -> Optimized:
    """Optimizes a G-code program as ``cellseq optimize`` does (state-exact, verified)."""

def optimize_drawing(
    path: Optional[_Path] = None,
    *,
    text: Optional[str] = None,
    format: Optional[str] = None,
    output: Optional[str] = None,
    solver: str = "drawing",
    time_limit: Optional[float] = None,
    max_evals: Optional[int] = None,
    seed: int = 1,
    params: Optional[Dict[str, _Param]] = None,
    reversible: bool = True,
    scopes: bool = True,
    pens: str = "auto",
    blocks: str = "auto",
    cut: Optional[bool] = None,
    keep_group_order: bool = False,
    tolerance: float = 0.01,
    contain_tol: float = 0.01,
    max_starts: int = 8,
    skip_unsupported: bool = False,
    max_points: int = 10_000_000,
) -> Optimized:
    """Optimizes an SVG or DXF drawing as ``cellseq optimize`` does (verified).

    ``pens``: ``layer``, ``colour``, ``none`` or ``auto``; ``blocks``: ``group``, ``none`` or
    ``auto`` (docs/drawings.md); ``scopes=False`` is ``pens="none", blocks="none"``. The
    report's ``semantics`` names the reading used and every reading tried.
    """

def sequence_paths(
    paths: Sequence[npt.ArrayLike],
    *,
    start: Optional[Tuple[float, float]] = None,
    reversible: bool = True,
    max_starts: int = 8,
    solver: str = "drawing",
    time_limit: Optional[float] = None,
    max_evals: Optional[int] = None,
    seed: int = 1,
    params: Optional[Dict[str, _Param]] = None,
    progress: Optional[Callable[[int, float, float], Any]] = None,
) -> Dict[str, Any]:
    """The order, direction and start vertex in which to draw ``paths``."""

def order_paths(
    paths: Sequence[npt.ArrayLike], **options: Any
) -> Tuple[List[npt.NDArray[np.float64]], Dict[str, Any]]:
    """``paths`` reordered and oriented by :func:`sequence_paths`."""

def run_plan(
    plan: _Path,
    out: Optional[_Path] = None,
    threads: Optional[int] = None,
    shard: Optional[Tuple[int, int]] = None,
    frame: Optional[bool] = None,
) -> Any:
    """Runs an experiment plan; its results as a DataFrame (pandas) or a list of dicts."""
