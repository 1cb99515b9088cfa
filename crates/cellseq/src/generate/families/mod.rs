//! Instance families: seeded generators of benchmark-style instances that the solvers and a
//! portfolio can be trained on, away from the public benchmarks they are scored on.
//!
//! | kind | what it is |
//! |---|---|
//! | `random-sop` | asymmetric integer costs uniform in [0, c], random precedence of closure density p % |
//! | `atsp` | random asymmetric costs without precedence (`class=amat`), or their shortest-path closure (`tmat`, costs that satisfy the triangle inequality) |
//! | `symmetric` | symmetric integer costs uniform in [0, c], precedence density p % |
//! | `near-symmetric` | symmetric costs plus an asymmetric part uniform in [0, asym % of c] |
//! | `time-window` | storage crane jobs in time windows: precedence an interval order (transitively closed, dense when windows are short), asymmetric Chebyshev travel costs |
//! | `compiler-dag` | straight-line instruction blocks: switching costs (Hamming distance of 32-bit instruction words), register and memory dependencies (sparse, not transitively closed) |
//! | `geometric-sparse` | geometric CNC part: pockets cut in layers (roughing, then a finishing contour) and spot-drilled holes, sparse precedence, 10³–10⁵ cells |
//! | `generalized` | matrix instance whose cells have several modes (nodes near each other in the plane), precedence density p % |
//!
//! The matrix families are SOP-shaped: a dummy start cell (index 0) and a dummy end cell (the
//! last index) around `n` free cells, exactly what [`crate::formats::tsplib::parse_sop`] makes
//! of a TSPLIB SOP file, so [`sop::to_sop_text`] writes them for LKH-3 and the two files
//! describe the same instance. Arcs from the start and into the end cost 0 (the path may
//! start and end anywhere). Details and the training set: `docs/families.md`.

pub mod compiler;
pub mod dag;
pub mod geometric;
pub mod matrix;
pub mod sop;
pub mod time_window;

use crate::error::{Error, Result};
use crate::model::{Cell, CostMatrix, Instance, Mode, Visit};
use crate::params::{ParamKind, ParamSpec};
use crate::precedence::{Dag, topological_order};

/// Largest number of matrix nodes a family generates (a matrix of 5000 nodes takes 200 MB).
pub const MAX_MATRIX_NODES: usize = 5000;

/// Largest `n` of a matrix family: [`MAX_MATRIX_NODES`] less the dummy start and end cells.
pub const MAX_N: u64 = MAX_MATRIX_NODES as u64 - 2;

/// The `n` parameter (free cells) with a default, in `1..=max`.
pub(crate) const fn n_spec(default: &'static str, max: u64) -> ParamSpec {
    ParamSpec {
        name: "n",
        default,
        kind: ParamKind::int(1, max),
        help: "number of cells (matrix families add a dummy start and end cell)",
    }
}

/// The `c` parameter (cost range).
pub(crate) const C_SPEC: ParamSpec = ParamSpec {
    name: "c",
    default: "100",
    kind: ParamKind::int(1, 1_000_000),
    help: "costs are integers in [0, c]",
};

/// The `p` parameter (closure density in percent).
pub(crate) const fn p_spec(default: &'static str) -> ParamSpec {
    ParamSpec {
        name: "p",
        default,
        kind: ParamKind::float(0.0, 100.0),
        help: "precedence closure density in percent of the n(n-1)/2 pairs of free cells (0..=100)",
    }
}

/// Refuses a matrix family whose `n` cells of up to `nodes_per_cell` nodes each (and the two
/// dummies) make more than [`MAX_MATRIX_NODES`] nodes.
pub(crate) fn check_matrix_n(kind: &str, n: usize, nodes_per_cell: usize) -> Result<()> {
    let nodes = n.saturating_mul(nodes_per_cell).saturating_add(2);
    if n == 0 || nodes > MAX_MATRIX_NODES {
        return Err(Error::Param(format!(
            "{kind}: n must be at least 1 and the matrix at most {MAX_MATRIX_NODES} nodes \
             (n = {n} gives {nodes})"
        )));
    }
    Ok(())
}

/// The number of cells of a family instance whose parameters need no check beyond their
/// ranges: `n`, plus the two dummies of a matrix family (`dummies`).
pub(crate) fn cells_of(p: &crate::params::Params, dummies: u64) -> Result<u64> {
    Ok(p.int("n") + dummies)
}

/// Builds an SOP-shaped matrix instance: a dummy start cell 0, the free cells 1..=n (free
/// cell `i` is cell `i + 1` and has `modes[i]` modes), a dummy end cell n + 1. `cost(u, v)`
/// gives the cost between free nodes `u` and `v` (numbered cell by cell, 0-based, without the
/// dummies); `edges` are precedence pairs of free cells (a before b). The start precedes
/// every cell and the end follows every cell, as in TSPLIB SOP files; an arc that precedence
/// rules out directly is stored as [`CostMatrix::FORBIDDEN`], the arc start → end costs
/// 1 000 000 as in TSPLIB. Cell ids are `"1"`..`"n+2"` like the TSPLIB reader's. The
/// as-programmed order is a topological order of the precedence.
pub(crate) fn sop_shaped(
    name: String,
    modes: &[usize],
    cost: impl Fn(usize, usize) -> f64,
    edges: &[(usize, usize)],
) -> Instance {
    let n = modes.len();
    let free_nodes: usize = modes.iter().sum();
    let size = free_nodes + 2;
    let last = size - 1;
    // node ranges per cell (cells 0..n+2)
    let mut start_of = Vec::with_capacity(n + 3);
    start_of.push(0usize);
    start_of.push(1);
    for &k in modes {
        let s = *start_of.last().expect("non-empty");
        start_of.push(s + k);
    }
    start_of.push(size);
    let mut costs = vec![0.0; size * size];
    for u in 0..free_nodes {
        for v in 0..free_nodes {
            if u != v {
                costs[(u + 1) * size + v + 1] = cost(u, v);
            }
        }
        costs[(u + 1) * size] = CostMatrix::FORBIDDEN; // back into the start
        costs[last * size + u + 1] = CostMatrix::FORBIDDEN; // out of the end
    }
    costs[last] = 1_000_000.0;
    costs[last * size] = CostMatrix::FORBIDDEN;
    let mut precedence = Vec::with_capacity(edges.len() + 2 * n + 1);
    precedence.push((0, n + 1));
    for i in 1..=n {
        precedence.push((0, i));
        precedence.push((i, n + 1));
    }
    for &(a, b) in edges {
        let (a, b) = (a + 1, b + 1);
        precedence.push((a, b));
        for u in start_of[b]..start_of[b + 1] {
            for v in start_of[a]..start_of[a + 1] {
                costs[u * size + v] = CostMatrix::FORBIDDEN;
            }
        }
    }
    let cells: Vec<Cell> = (0..n + 2)
        .map(|c| {
            let k = if c == 0 || c == n + 1 {
                1
            } else {
                modes[c - 1]
            };
            Cell::new((c + 1).to_string(), "", vec![Mode::default(); k])
        })
        .collect();
    let order =
        topological_order(&Dag::new(n + 2, &precedence)).expect("generated precedence is acyclic");
    Instance {
        name,
        cells,
        precedence,
        as_given: Some(
            order
                .into_iter()
                .map(|c| Visit::new(c as usize, 0))
                .collect(),
        ),
        matrix: Some(CostMatrix { size, costs }),
        first: Some(0),
        last: Some(n + 1),
        ..Instance::default()
    }
}

#[cfg(test)]
mod tests;
