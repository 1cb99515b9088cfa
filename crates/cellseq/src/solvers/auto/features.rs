//! Instance features: the numbers a portfolio rule is chosen by, computed once per run.

use crate::cost::CostModel;
use crate::engine::atsp::free_density;
use crate::engine::{Costs, large, lk};
use crate::model::CostMatrix;
use crate::precedence::closure_density;
use serde::Serialize;

/// Largest number of arcs [`Features::of`] reads for the cost statistics; above it, a
/// deterministic evenly spaced sample of this many (node pairs at a fixed stride).
pub const COST_SAMPLE_ARCS: usize = 1 << 20;

/// What a portfolio rule can ask about an instance. Every field is computed by
/// [`Features::of`]; the names are those a portfolio file's `when` tables use.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Features {
    /// Number of cells.
    pub cells: usize,
    /// Mean number of modes (ways to cut it) per cell; 1 on single-mode instances.
    pub modes: f64,
    /// True for geometric instances (costs from points and tools), false for cost matrices.
    pub geometric: bool,
    /// True when the costs read the same backwards (every arc costs what the reverse arc
    /// does, cell directions flipped): on a cost matrix tested arc by arc
    /// (`crate::engine::lk::symmetric`); on a geometric instance known from how its links
    /// are costed (the air length, or time with no linking at cutting feed:
    /// `crate::engine::large::applies`), at any size.
    pub symmetric: bool,
    /// Ordered pairs of the precedence closure over n(n−1)/2
    /// ([`crate::precedence::closure_density`]).
    pub closure_density: f64,
    /// The closure density among the cells not ordered against every other cell (a fixed
    /// start and end left out): 0 when nothing but the ends is constrained
    /// (`crate::engine::atsp::free_density`).
    pub free_density: f64,
    /// Share of the cells in the widest level of the precedence (cells at the same longest-path
    /// depth from a cell without predecessors are mutually unordered): a lower bound on the
    /// largest group of cells free to go in any order, over n.
    pub widest_level: f64,
    /// Share of the arcs between distinct cells that cost nothing (among the arcs a feasible
    /// order can use, where the model keeps the precedence closure).
    pub zero_arcs: f64,
    /// Spread of the same arc costs: standard deviation over mean (coefficient of
    /// variation; 0 when every arc costs the same).
    pub cost_spread: f64,
}

impl Features {
    /// The features of model `m`. Cost statistics read at most `COST_SAMPLE_ARCS` arcs
    /// (forbidden arcs left out); the rest is exact within the limits of the functions named
    /// on each field.
    pub fn of(m: &CostModel) -> Features {
        let geometric = m.is_geometric();
        let closure = closure_density(&m.dag);
        // free_density is the plain closure density where the model keeps no closure
        let free = if m.dag.succs.iter().all(|s| s.is_empty()) || m.closure().is_some() {
            free_density(m)
        } else {
            closure
        };
        let (zero_arcs, cost_spread) = cost_stats(m);
        Features {
            cells: m.n(),
            modes: m.nodes() as f64 / m.n().max(1) as f64,
            geometric,
            symmetric: if geometric {
                large::applies(&Costs::open(m))
            } else {
                lk::symmetric(&Costs::open(m))
            },
            closure_density: closure,
            free_density: free,
            widest_level: widest_level(m),
            zero_arcs,
            cost_spread,
        }
    }

    /// The numeric value of feature `name` (booleans as 0 or 1), `None` for an unknown name.
    pub fn value(&self, name: &str) -> Option<f64> {
        let b = |x: bool| if x { 1.0 } else { 0.0 };
        Some(match name {
            "cells" => self.cells as f64,
            "modes" => self.modes,
            "geometric" => b(self.geometric),
            "symmetric" => b(self.symmetric),
            "closure_density" => self.closure_density,
            "free_density" => self.free_density,
            "widest_level" => self.widest_level,
            "zero_arcs" => self.zero_arcs,
            "cost_spread" => self.cost_spread,
            _ => return None,
        })
    }

    /// One line `name=value ...` for traces and `solve --explain`.
    pub fn line(&self) -> String {
        format!(
            "cells={} modes={:.3} geometric={} symmetric={} closure_density={:.4} \
             free_density={:.4} widest_level={:.4} zero_arcs={:.4} cost_spread={:.4}",
            self.cells,
            self.modes,
            self.geometric,
            self.symmetric,
            self.closure_density,
            self.free_density,
            self.widest_level,
            self.zero_arcs,
            self.cost_spread
        )
    }
}

/// Share of zero-cost arcs and the coefficient of variation of the arc costs between distinct
/// cells, over every node pair or an evenly spaced sample of [`COST_SAMPLE_ARCS`]; arcs no
/// feasible order can use (against the precedence closure, where the model keeps one) and
/// forbidden ones are left out.
fn cost_stats(m: &CostModel) -> (f64, f64) {
    let nodes = m.nodes();
    let pairs = nodes.saturating_mul(nodes);
    if pairs == 0 {
        return (0.0, 0.0);
    }
    // a stride with no common factor with the row length, so the sample meets every column
    let mut stride = pairs.div_ceil(COST_SAMPLE_ARCS).max(1);
    while stride > 1 && gcd(stride, nodes) != 1 {
        stride += 1;
    }
    let closure = m.closure();
    let (mut count, mut zeros, mut sum, mut sq) = (0usize, 0usize, 0.0f64, 0.0f64);
    let mut k = 0usize;
    while k < pairs {
        let (na, nb) = (k / nodes, k % nodes);
        k += stride;
        let ((a, ma), (b, mb)) = (m.cell_mode(na), m.cell_mode(nb));
        if a == b || closure.is_some_and(|cl| !cl.arc_allowed(a, b)) {
            continue;
        }
        let c = m.arc(a, ma, b, mb);
        if !c.is_finite() || c >= CostMatrix::FORBIDDEN {
            continue;
        }
        count += 1;
        if c.abs() <= 1e-12 {
            zeros += 1;
        }
        sum += c;
        sq += c * c;
    }
    if count == 0 {
        return (0.0, 0.0);
    }
    let nf = count as f64;
    let mean = sum / nf;
    let var = (sq / nf - mean * mean).max(0.0);
    let spread = if mean.abs() > 1e-12 {
        var.sqrt() / mean.abs()
    } else {
        0.0
    };
    (zeros as f64 / nf, spread)
}

fn gcd(mut a: usize, mut b: usize) -> usize {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// Share of the cells in the largest level of the longest-path layering of the precedence
/// (1 without precedence; 0 for an empty model).
fn widest_level(m: &CostModel) -> f64 {
    let n = m.n();
    if n == 0 {
        return 0.0;
    }
    crate::precedence::widest_level(&m.dag) as f64 / n as f64
}
