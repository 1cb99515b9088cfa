//! Search for asymmetric instances with little or no precedence (random ATSP as an open path,
//! free groups of cells with asymmetric costs).
//!
//! - [`patch`]: the assignment problem on the cells plus a dummy node that closes the path
//!   into a cycle, solved with its dual potentials; its cycles patched into one (Karp's
//!   patching, the cheapest exchange of two arcs between the growing tour and the next
//!   cycle), cut at the dummy node and, where precedence exists and the patched order breaks
//!   it, repaired by a topological sort that follows the patched order.
//! - [`cands`]: candidate lists ranked by the assignment's reduced costs
//!   `c(i, j) − u(i) − v(j)` (every assignment arc has reduced cost 0), ties by raw cost, so
//!   that among the many zero-cost arcs of a random instance those that fit a cheap cycle
//!   cover come first; outgoing and incoming lists.
//! - [`or3`]: Or-3opt, the pure asymmetric 3-opt that swaps two adjacent blocks and keeps
//!   their orientation (segment insertion without reversal), driven by the candidate lists
//!   with don't-look queues and checked against the precedence, inside an iterated local
//!   search whose kicks swap two nearby blocks (the double bridge of a path).
//! - [`bnb`]: depth-first branch and bound on the assignment relaxation (subtour elimination
//!   with one augmenting path per child), whose nodes' patched tours feed the Or-3opt search
//!   and whose exhausted tree proves the best tour optimal.

pub mod bnb;
pub mod cands;
pub mod or3;
pub mod patch;

use crate::cost::CostModel;
use crate::precedence::closure_density;

/// The precedence closure density among the cells that are not ordered against every other
/// cell (a fixed first or last cell, or one the precedence pins there): ordered pairs over
/// `k(k − 1)/2` for the `k` such cells. 0 when the only precedence is a fixed start and end,
/// as in a TSPLIB SOP file without constraints. Above [`crate::cost::CLOSURE_MAX_CELLS`] cells
/// with precedence, the plain closure density.
pub fn free_density(m: &CostModel) -> f64 {
    let n = m.n();
    if m.dag.succs.iter().all(|s| s.is_empty()) {
        return 0.0;
    }
    let Some(cl) = m.closure() else {
        return closure_density(&m.dag);
    };
    let pinned: Vec<usize> = (0..n)
        .filter(|&v| cl.ancestors(v) + cl.descendants(v) + 1 == n)
        .collect();
    let k = n - pinned.len();
    if k < 2 {
        return 0.0;
    }
    let mut pairs = 0usize;
    for v in 0..n {
        if pinned.contains(&v) {
            continue;
        }
        let to_pinned = pinned.iter().filter(|&&p| cl.before(v, p)).count();
        pairs += cl.descendants(v) - to_pinned;
    }
    pairs as f64 / (k as f64 * (k as f64 - 1.0) / 2.0)
}

/// A random matrix instance for tests: `n` single-mode cells named by index, costs drawn
/// uniformly from `0..max_cost` by ChaCha8 seeded with `seed` (0 on the diagonal), and the
/// precedence pairs `prec`.
#[cfg(test)]
pub(crate) fn random_matrix_instance(
    n: usize,
    seed: u64,
    max_cost: i32,
    prec: &[(usize, usize)],
) -> crate::model::Instance {
    use crate::model::{Cell, CostMatrix, Instance, Mode};
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let costs = (0..n * n)
        .map(|k| {
            if k / n == k % n {
                0.0
            } else {
                rng.random_range(0..max_cost) as f64
            }
        })
        .collect();
    Instance {
        name: "t".into(),
        cells: (0..n)
            .map(|i| Cell::new(i.to_string(), "", vec![Mode::default()]))
            .collect(),
        precedence: prec.to_vec(),
        matrix: Some(CostMatrix { size: n, costs }),
        ..Instance::default()
    }
}
