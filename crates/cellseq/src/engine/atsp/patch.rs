//! Construction by patching the assignment problem's cycles (Karp's patching).
//!
//! The open path becomes a cycle through a dummy node `D = n`: `D → j` costs the start of
//! `j`, `j → D` its finish. Arcs that no feasible sequence uses (precedence against them, a
//! fixed first or last cell elsewhere, the matrix's forbidden entries) are left out. The
//! optimal assignment on these `n + 1` nodes is a set of cycles; they are merged one at a
//! time, largest first, each into the growing tour by the cheapest exchange of two arcs
//! (`a → a'` in the tour and `b → b'` in the cycle become `a → b'` and `b → a'`). The tour cut
//! at `D` is a path; where the precedence forbids it, [`repair`] sorts it topologically,
//! keeping the patched order wherever the precedence allows.

use crate::bound::assignment::{Assignment, hungarian_duals, hungarian_duals_until};
use crate::clock::Deadline;
use crate::cost::CostModel;
use crate::model::CostMatrix;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The assignment graph of an instance: the cells with fixed modes plus the dummy node `n`
/// that closes the path; `INFINITY` marks an arc no feasible sequence uses.
#[derive(Debug, Clone)]
pub struct ApGraph {
    /// Number of cells (the dummy node is `n`).
    pub n: usize,
    /// Row-major `(n + 1)²` arc costs.
    cost: Vec<f64>,
}

impl ApGraph {
    /// Builds the graph of model `m` with every cell `c` in mode `modes[c]`; O(n²) arc costs.
    pub fn new(m: &CostModel, modes: &[u32]) -> ApGraph {
        let n = m.n();
        let d = n + 1;
        let closure = m.closure();
        let mut cost = vec![f64::INFINITY; d * d];
        for i in 0..n {
            let mi = modes[i] as usize;
            for j in 0..n {
                if i == j || closure.is_some_and(|cl| !cl.arc_allowed(i, j)) {
                    continue;
                }
                let c = m.arc(i, mi, j, modes[j] as usize);
                if c < CostMatrix::FORBIDDEN {
                    cost[i * d + j] = c;
                }
            }
            if m.dag.succs[i].is_empty() {
                cost[i * d + n] = m.finish(i, mi);
            }
            if m.dag.preds[i].is_empty() {
                cost[n * d + i] = m.start(i, mi);
            }
        }
        if n == 0 {
            cost[0] = 0.0;
        }
        ApGraph { n, cost }
    }

    /// Cost of the arc `i → j` (`INFINITY` when left out).
    #[inline]
    pub fn c(&self, i: usize, j: usize) -> f64 {
        self.cost[i * (self.n + 1) + j]
    }

    /// The optimal assignment with its dual potentials, `None` when no finite one exists.
    pub fn assignment(&self) -> Option<Assignment> {
        hungarian_duals(self.n + 1, |i, j| self.c(i, j))
    }
}

/// The cycles of a successor array, largest first (ties: the one holding the smaller node
/// first), each as its nodes in cycle order from its smallest node.
pub fn cycles(succ: &[usize]) -> Vec<Vec<usize>> {
    let mut seen = vec![false; succ.len()];
    let mut out = Vec::new();
    for s in 0..succ.len() {
        if seen[s] {
            continue;
        }
        let mut cyc = Vec::new();
        let mut v = s;
        while !seen[v] {
            seen[v] = true;
            cyc.push(v);
            v = succ[v];
        }
        out.push(cyc);
    }
    out.sort_by_key(|c| Reverse(c.len()));
    out
}

/// Patches the cycles of the assignment `succ` into one tour through the dummy node, largest
/// cycle first; returns the successor array of the tour and the number of arc costs looked
/// at, or `None` when some cycle cannot be joined by finite arcs.
pub fn patch(g: &ApGraph, succ: &[usize]) -> Option<(Vec<usize>, u64)> {
    let mut succ = succ.to_vec();
    let cyc = cycles(&succ);
    let mut tour: Vec<usize> = cyc[0].clone();
    let mut evals = 0u64;
    for c in &cyc[1..] {
        let mut best: Option<(f64, usize, usize)> = None;
        for &a in &tour {
            let a2 = succ[a];
            let ca = g.c(a, a2);
            for &b in c {
                let b2 = succ[b];
                let d = g.c(a, b2) + g.c(b, a2) - ca - g.c(b, b2);
                if d.is_finite() && best.is_none_or(|(bd, _, _)| d < bd) {
                    best = Some((d, a, b));
                }
            }
        }
        evals += (tour.len() * c.len()) as u64;
        let (_, a, b) = best?;
        let (a2, b2) = (succ[a], succ[b]);
        succ[a] = b2;
        succ[b] = a2;
        tour.extend_from_slice(c);
    }
    Some((succ, evals))
}

/// Greedy patching: while several cycles remain, the cheapest exchange of two arcs between
/// any two of them joins that pair; O(d²) per join, so only when `(cycles − 1)·d²` stays
/// under [`GREEDY_PATCH_WORK`] (else [`patch`]). Returns the tour and the arc costs looked at.
pub fn patch_greedy(g: &ApGraph, succ: &[usize]) -> Option<(Vec<usize>, u64)> {
    let d = succ.len();
    let cyc = cycles(succ);
    if ((cyc.len() - 1) as u64).saturating_mul((d * d) as u64) > GREEDY_PATCH_WORK {
        return patch(g, succ);
    }
    let mut succ = succ.to_vec();
    let mut comp = vec![0usize; d];
    for (k, c) in cyc.iter().enumerate() {
        for &v in c {
            comp[v] = k;
        }
    }
    let mut evals = 0u64;
    for _ in 1..cyc.len() {
        let mut best: Option<(f64, usize, usize)> = None;
        for a in 0..d {
            let a2 = succ[a];
            let ca = g.c(a, a2);
            for b in 0..d {
                if comp[b] == comp[a] {
                    continue;
                }
                let b2 = succ[b];
                let x = g.c(a, b2) + g.c(b, a2) - ca - g.c(b, b2);
                if x.is_finite() && best.is_none_or(|(bx, _, _)| x < bx) {
                    best = Some((x, a, b));
                }
            }
        }
        evals += (d * d) as u64;
        let (_, a, b) = best?;
        let (a2, b2) = (succ[a], succ[b]);
        succ[a] = b2;
        succ[b] = a2;
        let (from, to) = (comp[b], comp[a]);
        for c in comp.iter_mut() {
            if *c == from {
                *c = to;
            }
        }
    }
    Some((succ, evals))
}

/// Work limit of [`patch_greedy`] (arc costs looked at).
pub const GREEDY_PATCH_WORK: u64 = 50_000_000;

/// The path of a one-cycle tour through the dummy node `n`: the cells after it, in order.
pub fn path_of(succ: &[usize]) -> Vec<u32> {
    let n = succ.len() - 1;
    let mut out = Vec::with_capacity(n);
    let mut v = succ[n];
    while v != n {
        out.push(v as u32);
        v = succ[v];
    }
    out
}

/// A topological order of `m`'s precedence that follows `order` wherever the precedence
/// allows: at each step the ready cell that comes first in `order` (Kahn's algorithm with
/// the positions as priorities). `order` itself when it is feasible.
pub fn repair(m: &CostModel, order: &[u32]) -> Vec<u32> {
    let n = m.n();
    let mut pos = vec![0usize; n];
    for (p, &c) in order.iter().enumerate() {
        pos[c as usize] = p;
    }
    let mut indeg: Vec<usize> = (0..n).map(|c| m.dag.preds[c].len()).collect();
    let mut heap: BinaryHeap<Reverse<(usize, u32)>> = (0..n)
        .filter(|&c| indeg[c] == 0)
        .map(|c| Reverse((pos[c], c as u32)))
        .collect();
    let mut out = Vec::with_capacity(n);
    while let Some(Reverse((_, c))) = heap.pop() {
        out.push(c);
        for &s in &m.dag.succs[c as usize] {
            let s = s as usize;
            indeg[s] -= 1;
            if indeg[s] == 0 {
                heap.push(Reverse((pos[s], s as u32)));
            }
        }
    }
    out
}

/// The patched construction: the assignment on `g`, its cycles patched ([`patch_greedy`] or,
/// without `greedy`, [`patch`]), cut at the dummy node
/// and repaired against the precedence. Returns the cell order, the assignment (for its
/// potentials) and the number of arc costs looked at; `None` when the assignment or the
/// patching finds no finite arcs.
pub fn construct(m: &CostModel, g: &ApGraph, greedy: bool) -> Option<(Vec<u32>, Assignment, u64)> {
    construct_until(m, g, greedy, Deadline::NONE)
}

/// Like [`construct`], or `None` when `deadline` passes during the assignment.
pub fn construct_until(
    m: &CostModel,
    g: &ApGraph,
    greedy: bool,
    deadline: Deadline,
) -> Option<(Vec<u32>, Assignment, u64)> {
    let d = (g.n + 1) as u64;
    let ap = hungarian_duals_until(g.n + 1, |i, j| g.c(i, j), deadline)?;
    let (tour, evals) = if greedy {
        patch_greedy(g, &ap.col)?
    } else {
        patch(g, &ap.col)?
    };
    let order = repair(m, &path_of(&tour));
    Some((order, ap, d * d + evals))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cycles_and_path() {
        // 0 -> 1 -> 0, 2 -> 3 -> 4 -> 2
        let succ = [1, 0, 3, 4, 2];
        let c = cycles(&succ);
        assert_eq!(c, vec![vec![2, 3, 4], vec![0, 1]]);
        // tour through dummy 4: 4 -> 2 -> 0 -> 3 -> 1 -> 4
        let tour = [3, 4, 0, 1, 2];
        assert_eq!(path_of(&tour), vec![2, 0, 3, 1]);
    }
}
