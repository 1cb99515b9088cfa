//! The cell graph used by the dense bounds: min-over-modes arc costs between cells plus a
//! home node, with every arc that precedence forbids removed (set to infinity).

use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::precedence::Closure;

/// Dense (n+1) × (n+1) cost matrix over cells; index `n` is home (start before / end after).
///
/// `c(home, j)` is the cheapest start into j (if j may be first), `c(i, home)` the cheapest
/// finish from i (if i may be last), `c(i, j)` the cheapest arc over all mode pairs when the
/// closure allows i → j. Forbidden arcs are `f64::INFINITY`.
#[derive(Debug, Clone)]
pub struct CellGraph {
    /// Number of cells (the home node is index `n`).
    pub n: usize,
    cost: Vec<f64>,
}

impl CellGraph {
    /// Builds the graph: O(nodes²) arc evaluations.
    pub fn new(m: &CostModel, cl: &Closure) -> CellGraph {
        Self::new_until(m, cl, Deadline::NONE).expect("no deadline")
    }

    /// Like [`CellGraph::new`], or `None` once `deadline` passes (checked once per cell).
    pub fn new_until(m: &CostModel, cl: &Closure, deadline: Deadline) -> Option<CellGraph> {
        let n = m.n();
        let d = n + 1;
        let mut cost = vec![f64::INFINITY; d * d];
        for j in 0..n {
            if cl.can_be_first(j) {
                cost[n * d + j] = (0..m.modes(j))
                    .map(|md| m.start(j, md))
                    .fold(f64::INFINITY, f64::min);
            }
            if cl.can_be_last(j) {
                cost[j * d + n] = (0..m.modes(j))
                    .map(|md| m.finish(j, md))
                    .fold(f64::INFINITY, f64::min);
            }
        }
        for i in 0..n {
            if deadline.passed() {
                return None;
            }
            for j in 0..n {
                if !cl.arc_allowed(i, j) {
                    continue;
                }
                cost[i * d + j] = m.cheapest_arc(i, j);
            }
        }
        Some(CellGraph { n, cost })
    }

    /// Number of graph nodes (cells + home).
    #[inline]
    pub fn size(&self) -> usize {
        self.n + 1
    }

    /// Cost of arc a → b (infinite when forbidden).
    #[inline]
    pub fn c(&self, a: usize, b: usize) -> f64 {
        self.cost[a * (self.n + 1) + b]
    }

    /// Cheapest arc into each node (cells and home), from any allowed source.
    pub fn min_in(&self) -> Vec<f64> {
        let d = self.size();
        (0..d)
            .map(|j| (0..d).map(|i| self.c(i, j)).fold(f64::INFINITY, f64::min))
            .collect()
    }

    /// Cheapest arc out of each node (cells and home), to any allowed target.
    pub fn min_out(&self) -> Vec<f64> {
        let d = self.size();
        (0..d)
            .map(|i| (0..d).map(|j| self.c(i, j)).fold(f64::INFINITY, f64::min))
            .collect()
    }

    /// True when every arc cost is an integer (bounds may then be rounded up).
    pub fn integral(&self) -> bool {
        self.cost
            .iter()
            .all(|c| !c.is_finite() || (c.fract() == 0.0 && c.abs() < 1e15))
    }
}
