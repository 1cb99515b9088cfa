//! The precedence DAG: adjacency, cycle detection, closure and reduction, topological orders.

pub mod closure;

pub use closure::Closure;

use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Predecessor and successor lists of a precedence DAG over `n` cells.
#[derive(Debug, Clone, Default)]
pub struct Dag {
    /// `preds[v]`: cells that must come before v (as given, deduplicated).
    pub preds: Vec<Vec<u32>>,
    /// `succs[v]`: cells that must come after v (as given, deduplicated).
    pub succs: Vec<Vec<u32>>,
}

impl Dag {
    /// Builds adjacency lists from edges `(a, b)` = a before b. Duplicate edges are dropped.
    pub fn new(n: usize, edges: &[(usize, usize)]) -> Self {
        let mut preds = vec![Vec::new(); n];
        let mut succs = vec![Vec::new(); n];
        for &(a, b) in edges {
            succs[a].push(b as u32);
            preds[b].push(a as u32);
        }
        for l in preds.iter_mut().chain(succs.iter_mut()) {
            l.sort_unstable();
            l.dedup();
        }
        Dag { preds, succs }
    }

    /// Number of cells.
    pub fn n(&self) -> usize {
        self.preds.len()
    }

    /// True when there is no precedence at all (no cell has a successor).
    pub fn is_empty(&self) -> bool {
        self.succs.iter().all(|v| v.is_empty())
    }

    /// The DAG with only the edges of its transitive reduction. For large sparse graphs
    /// (more than `max_n` cells) the graph is returned unchanged.
    pub fn reduced(&self, max_n: usize) -> Dag {
        let n = self.n();
        if n > max_n {
            return self.clone();
        }
        let order = match topological_order(self) {
            Ok(o) => o,
            Err(_) => return self.clone(),
        };
        let mut pos = vec![0usize; n];
        for (i, &v) in order.iter().enumerate() {
            pos[v as usize] = i;
        }
        let words = n.div_ceil(64);
        // reach[v] = strict descendants of v.
        let mut reach = vec![0u64; n * words];
        let mut edges = Vec::new();
        for &v in order.iter().rev() {
            let v = v as usize;
            // successors sorted by topological position: process nearest first
            let mut ss: Vec<usize> = self.succs[v].iter().map(|&s| s as usize).collect();
            ss.sort_by_key(|&s| pos[s]);
            let mut acc = vec![0u64; words];
            for s in ss {
                if acc[s / 64] >> (s % 64) & 1 == 0 {
                    edges.push((v, s));
                    acc[s / 64] |= 1 << (s % 64);
                    for w in 0..words {
                        acc[w] |= reach[s * words + w];
                    }
                }
            }
            reach[v * words..(v + 1) * words].copy_from_slice(&acc);
        }
        Dag::new(n, &edges)
    }
}

/// Kahn's topological order. On a cycle returns the cells of one cycle, in order.
pub fn topological_order(dag: &Dag) -> Result<Vec<u32>, Vec<usize>> {
    let n = dag.n();
    let mut indeg: Vec<usize> = dag.preds.iter().map(|p| p.len()).collect();
    let mut stack: Vec<u32> = (0..n as u32).filter(|&v| indeg[v as usize] == 0).collect();
    stack.reverse();
    let mut out = Vec::with_capacity(n);
    while let Some(v) = stack.pop() {
        out.push(v);
        for &s in &dag.succs[v as usize] {
            indeg[s as usize] -= 1;
            if indeg[s as usize] == 0 {
                stack.push(s);
            }
        }
    }
    if out.len() == n {
        return Ok(out);
    }
    // Find a cycle among the remaining cells: walk predecessors that are still blocked.
    let blocked: Vec<bool> = indeg.iter().map(|&d| d > 0).collect();
    let start = blocked.iter().position(|&b| b).unwrap_or(0);
    let mut seen = vec![usize::MAX; n];
    let mut path = Vec::new();
    let mut v = start;
    loop {
        if seen[v] != usize::MAX {
            let mut cyc: Vec<usize> = path[seen[v]..].to_vec();
            cyc.reverse();
            return Err(cyc);
        }
        seen[v] = path.len();
        path.push(v);
        v = dag.preds[v]
            .iter()
            .map(|&p| p as usize)
            .find(|&p| blocked[p])
            .unwrap_or(v);
    }
}

/// A topological order that, among ready cells, always takes the one with the smallest
/// `rank` (ties by index): the order closest to a wished order that respects precedence.
pub fn ranked_topological_order(dag: &Dag, rank: &[usize]) -> Result<Vec<usize>, Vec<usize>> {
    let n = dag.n();
    let mut indeg: Vec<usize> = dag.preds.iter().map(|p| p.len()).collect();
    let mut heap: BinaryHeap<Reverse<(usize, usize)>> = (0..n)
        .filter(|&v| indeg[v] == 0)
        .map(|v| Reverse((rank[v], v)))
        .collect();
    let mut out = Vec::with_capacity(n);
    while let Some(Reverse((_, v))) = heap.pop() {
        out.push(v);
        for &s in &dag.succs[v] {
            let s = s as usize;
            indeg[s] -= 1;
            if indeg[s] == 0 {
                heap.push(Reverse((rank[s], s)));
            }
        }
    }
    if out.len() == n {
        Ok(out)
    } else {
        topological_order(dag).map(|_| out)
    }
}

/// Number of pairs (a, b) with a ≺ b in the transitive closure of `edges`.
/// Exact up to 20 000 cells (bitset closure); beyond that counts the given edges.
pub fn closure_size(n: usize, edges: &[(usize, usize)]) -> usize {
    if edges.is_empty() {
        return 0;
    }
    dag_closure_size(&Dag::new(n, edges))
}

/// Precedence density of `dag`: pairs of its transitive closure over n(n−1)/2 (0 for
/// fewer than two nodes). Exact up to 20 000 nodes, like [`closure_size`].
pub fn closure_density(dag: &Dag) -> f64 {
    let n = dag.n();
    if n < 2 {
        return 0.0;
    }
    dag_closure_size(dag) as f64 / (n as f64 * (n as f64 - 1.0) / 2.0)
}

/// Cells in the largest level of the longest-path layering of `dag` (a cell's level: the
/// most predecessors on one chain before it); 0 for an empty or cyclic graph.
pub fn widest_level(dag: &Dag) -> usize {
    let Ok(order) = topological_order(dag) else {
        return 0;
    };
    let mut level = vec![0usize; dag.n()];
    for &v in &order {
        let v = v as usize;
        for &s in &dag.succs[v] {
            let s = s as usize;
            level[s] = level[s].max(level[v] + 1);
        }
    }
    let depth = level.iter().copied().max().unwrap_or(0);
    let mut count = vec![0usize; depth + 1];
    for &l in &level {
        count[l] += 1;
    }
    count.into_iter().max().unwrap_or(0)
}

/// [`closure_size`] of a built [`Dag`].
fn dag_closure_size(dag: &Dag) -> usize {
    let n = dag.n();
    if dag.succs.iter().all(|s| s.is_empty()) {
        return 0;
    }
    if n > 20_000 {
        return dag.succs.iter().map(|s| s.len()).sum();
    }
    let Ok(order) = topological_order(dag) else {
        return dag.succs.iter().map(|s| s.len()).sum();
    };
    let words = n.div_ceil(64);
    let mut reach = vec![0u64; n * words];
    let mut total = 0usize;
    for &v in order.iter().rev() {
        let v = v as usize;
        let mut acc = vec![0u64; words];
        for &s in &dag.succs[v] {
            let s = s as usize;
            acc[s / 64] |= 1 << (s % 64);
            for w in 0..words {
                acc[w] |= reach[s * words + w];
            }
        }
        total += acc.iter().map(|w| w.count_ones() as usize).sum::<usize>();
        reach[v * words..(v + 1) * words].copy_from_slice(&acc);
    }
    total
}
