//! The Lagrangian arborescence bound.
//!
//! A feasible sequence closed through home is a Hamiltonian cycle; dropping the arc into home
//! leaves a spanning arborescence rooted at home. So a minimum spanning arborescence (Chu–Liu /
//! Edmonds) plus the cheapest arc into home is a lower bound (a "1-arborescence"). Every node
//! of the cycle has out-degree exactly one; relaxing those constraints with multipliers `π`
//! (arc i → j costs `c(i, j) + π_i`, minus `Σ π`) and tuning `π` by subgradient steps
//! (Held–Karp style) tightens the bound. Every iterate is a valid bound; the best is kept.

use super::cells::CellGraph;
use crate::clock::Deadline;

#[derive(Clone, Copy)]
struct Edge {
    from: u32,
    to: u32,
    w: f64,
}

/// No heap node / no parent.
const NIL: u32 = u32::MAX;

/// Leftist min-heaps over the edges (node k is edge k) with a lazy addition per subtree, so
/// that a contracted cycle's in-edges are reduced in O(1) and heaps merge in O(log m).
struct Heaps {
    key: Vec<f64>,
    lazy: Vec<f64>,
    left: Vec<u32>,
    right: Vec<u32>,
    rank: Vec<u32>,
}

impl Heaps {
    fn new(edges: &[Edge]) -> Heaps {
        let m = edges.len();
        Heaps {
            key: edges.iter().map(|e| e.w).collect(),
            lazy: vec![0.0; m],
            left: vec![NIL; m],
            right: vec![NIL; m],
            rank: vec![1; m],
        }
    }
    fn rank(&self, h: u32) -> u32 {
        if h == NIL { 0 } else { self.rank[h as usize] }
    }
    /// Applies node `h`'s pending addition to its key and hands it to its children.
    fn push(&mut self, h: u32) {
        let h = h as usize;
        let d = self.lazy[h];
        if d != 0.0 {
            self.key[h] += d;
            for c in [self.left[h], self.right[h]] {
                if c != NIL {
                    self.lazy[c as usize] += d;
                }
            }
            self.lazy[h] = 0.0;
        }
    }
    /// The union of heaps `a` and `b` (recursion along right spines: depth O(log m)).
    fn merge(&mut self, a: u32, b: u32) -> u32 {
        if a == NIL {
            return b;
        }
        if b == NIL {
            return a;
        }
        self.push(a);
        self.push(b);
        // ties go to the lower edge index, as in the recursive form: the same arborescence
        // where several have the least weight
        let (ka, kb) = (self.key[a as usize], self.key[b as usize]);
        let (a, b) = if kb < ka || (kb == ka && b < a) {
            (b, a)
        } else {
            (a, b)
        };
        let r = self.merge(self.right[a as usize], b);
        let ai = a as usize;
        self.right[ai] = r;
        if self.rank(self.left[ai]) < self.rank(r) {
            self.right[ai] = self.left[ai];
            self.left[ai] = r;
        }
        self.rank[ai] = self.rank(self.right[ai]) + 1;
        a
    }
    /// The heap without its top (which the caller read after [`Heaps::push`]).
    fn pop(&mut self, h: u32) -> u32 {
        self.push(h);
        self.merge(self.left[h as usize], self.right[h as usize])
    }
}

/// Union–find with union by size and no path compression, so unions can be undone in order.
struct Dsu {
    parent: Vec<u32>,
    size: Vec<u32>,
    /// (the root that was attached, the size of the root it joined before)
    history: Vec<(u32, u32)>,
}

impl Dsu {
    fn new(n: usize) -> Dsu {
        Dsu {
            parent: (0..n as u32).collect(),
            size: vec![1; n],
            history: Vec::new(),
        }
    }
    fn find(&self, mut x: usize) -> usize {
        while self.parent[x] as usize != x {
            x = self.parent[x] as usize;
        }
        x
    }
    /// Joins the sets of `a` and `b`; false when they were one already.
    fn union(&mut self, a: usize, b: usize) -> bool {
        let (mut a, mut b) = (self.find(a), self.find(b));
        if a == b {
            return false;
        }
        if self.size[a] < self.size[b] {
            std::mem::swap(&mut a, &mut b);
        }
        self.history.push((b as u32, self.size[a]));
        self.parent[b] = a as u32;
        self.size[a] += self.size[b];
        true
    }
    /// Undoes the unions after the first `t`.
    fn rollback(&mut self, t: usize) {
        while self.history.len() > t {
            let (b, old) = self.history.pop().expect("history longer than t");
            let a = self.parent[b as usize] as usize;
            self.size[a] = old;
            self.parent[b as usize] = b;
        }
    }
}

/// Minimum spanning arborescence rooted at `root` over `nv` nodes (Chu–Liu / Edmonds in the
/// O(m log n) form of Tarjan and of Gabow, Galil, Spencer and Tarjan: every node's in-edges
/// in a mergeable heap; a cycle is contracted by merging its heaps, each reduced by the
/// cycle edge it replaces, and expanded again at the end by undoing the unions). Returns the
/// indices of the chosen edges, or `None` when some node cannot be reached. Memory is O(m):
/// the former recursive form copied the edge list once per contraction level, up to n
/// times (hundreds of MB at 400 nodes with many equal costs).
fn msa(nv: usize, root: usize, edges: &[Edge]) -> Option<Vec<usize>> {
    let mut h = Heaps::new(edges);
    // each node's in-edges sorted by weight make a valid leftist heap as a chain of left
    // children (rank 1 throughout), built in O(m log m) with a sort instead of m merges
    let mut into: Vec<Vec<u32>> = vec![Vec::new(); nv];
    for (k, e) in edges.iter().enumerate() {
        let t = e.to as usize;
        if t != root && e.from != e.to {
            into[t].push(k as u32);
        }
    }
    let mut heap = vec![NIL; nv];
    for (t, list) in into.iter_mut().enumerate() {
        list.sort_by(|&a, &b| {
            edges[a as usize]
                .w
                .total_cmp(&edges[b as usize].w)
                .then(a.cmp(&b))
        });
        for w in list.windows(2) {
            h.left[w[0] as usize] = w[1];
        }
        heap[t] = list.first().copied().unwrap_or(NIL);
    }
    drop(into);
    let mut dsu = Dsu::new(nv);
    let mut seen = vec![usize::MAX; nv];
    seen[root] = root;
    let mut chosen = vec![NIL; nv];
    // contracted cycles: (their node, unions before it, the cycle's edges)
    let mut cycles: Vec<(usize, usize, Vec<u32>)> = Vec::new();
    let (mut path, mut taken) = (Vec::new(), Vec::new());
    for s in 0..nv {
        let mut u = s;
        path.clear();
        taken.clear();
        while seen[u] == usize::MAX {
            // the cheapest edge into u from outside u's contracted node
            let e = loop {
                let top = heap[u];
                if top == NIL {
                    return None;
                }
                h.push(top);
                heap[u] = h.pop(top);
                if dsu.find(edges[top as usize].from as usize) != u {
                    break top;
                }
            };
            let w = h.key[e as usize];
            if heap[u] != NIL {
                h.lazy[heap[u] as usize] -= w;
            }
            path.push(u);
            taken.push(e);
            seen[u] = s;
            u = dsu.find(edges[e as usize].from as usize);
            if seen[u] == s {
                // a cycle through u: contract it into one node
                let (t, end) = (dsu.history.len(), taken.len());
                let mut merged = NIL;
                loop {
                    let x = path.pop().expect("the cycle is on the path");
                    merged = h.merge(merged, heap[x]);
                    if !dsu.union(u, x) {
                        break;
                    }
                }
                let start = path.len();
                u = dsu.find(u);
                heap[u] = merged;
                seen[u] = usize::MAX;
                cycles.push((u, t, taken[start..end].to_vec()));
                taken.truncate(start);
            }
        }
        for &e in &taken {
            chosen[dsu.find(edges[e as usize].to as usize)] = e;
        }
    }
    // expand the cycles, last contracted first: each keeps its edges but the one into the
    // node its in-edge enters
    for (u, t, cyc) in cycles.into_iter().rev() {
        dsu.rollback(t);
        let into = chosen[u];
        for &e in &cyc {
            chosen[dsu.find(edges[e as usize].to as usize)] = e;
        }
        chosen[dsu.find(edges[into as usize].to as usize)] = into;
    }
    Some(
        (0..nv)
            .filter(|&v| v != root)
            .map(|v| chosen[v] as usize)
            .collect(),
    )
}

/// Result of the Lagrangian arborescence bound.
#[derive(Debug, Clone, Copy)]
pub struct LagrangeResult {
    /// Best bound on the arc part of the cost.
    pub bound: f64,
    /// Subgradient iterations run (read by the tests).
    #[cfg_attr(not(feature = "internals"), allow(dead_code))]
    pub iterations: usize,
    /// True when the relaxation's solution was itself a Hamiltonian path (bound = optimum;
    /// read by the tests).
    #[cfg_attr(not(feature = "internals"), allow(dead_code))]
    pub tight: bool,
}

/// Runs `iterations` subgradient steps, or fewer when `deadline` passes (the best so far is
/// kept; `None` when it passes before the first). `upper` (a known solution cost without the
/// constant) sets the step size; without it a target 5 % above the current bound is used.
pub fn lagrangian_bound(
    g: &CellGraph,
    iterations: usize,
    upper: Option<f64>,
    deadline: Deadline,
) -> Option<LagrangeResult> {
    let d = g.size();
    let home = g.n;
    let mut edges = Vec::new();
    let mut base = Vec::new();
    for i in 0..d {
        for j in 0..g.n {
            let c = g.c(i, j);
            if c.is_finite() {
                edges.push(Edge {
                    from: i as u32,
                    to: j as u32,
                    w: c,
                });
                base.push(c);
            }
        }
    }
    let into_home: Vec<(usize, f64)> = (0..g.n)
        .filter_map(|i| {
            let c = g.c(i, home);
            c.is_finite().then_some((i, c))
        })
        .collect();
    if into_home.is_empty() && g.n > 0 {
        return None;
    }
    let mut pi = vec![0.0f64; d];
    let mut best = f64::NEG_INFINITY;
    let mut lambda = 2.0;
    let mut stall = 0usize;
    let mut tight = false;
    let mut it = 0usize;
    while it < iterations.max(1) {
        if deadline.passed() {
            if it == 0 {
                return None;
            }
            break;
        }
        it += 1;
        for (e, b) in edges.iter_mut().zip(&base) {
            e.w = b + pi[e.from as usize];
        }
        let chosen = msa(d, home, &edges)?;
        let mut deg = vec![0i64; d];
        let mut val: f64 = 0.0;
        for &k in &chosen {
            val += edges[k].w;
            deg[edges[k].from as usize] += 1;
        }
        if g.n > 0 {
            let (hi, hc) = into_home.iter().map(|&(i, c)| (i, c + pi[i])).fold(
                (usize::MAX, f64::INFINITY),
                |a, b| if b.1 < a.1 { b } else { a },
            );
            val += hc;
            deg[hi] += 1;
        }
        val -= pi.iter().sum::<f64>();
        if best == f64::NEG_INFINITY || val > best + 1e-9 * best.abs().max(1.0) {
            best = val;
            stall = 0;
        } else {
            stall += 1;
            if stall >= 10 {
                lambda /= 2.0;
                stall = 0;
            }
        }
        let norm: i64 = deg.iter().map(|&x| (x - 1) * (x - 1)).sum();
        if norm == 0 {
            tight = true;
            break;
        }
        let target = match upper {
            Some(u) if u > best + 1e-9 => u,
            _ => best.abs().max(1.0) * 0.05 + best,
        };
        if lambda < 1e-5 {
            break;
        }
        let step = lambda * (target - val).max(1e-9 * best.abs().max(1.0)) / norm as f64;
        for (p, &dg) in pi.iter_mut().zip(&deg) {
            *p += step * (dg - 1) as f64;
        }
    }
    Some(LagrangeResult {
        bound: best,
        iterations: it,
        tight,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn msa_contracts_a_cycle() {
        // root 0; 1 <-> 2 cheap cycle, entry from root expensive to 1, cheaper to 2.
        let e = |f: u32, t: u32, w: f64| Edge { from: f, to: t, w };
        let edges = vec![e(0, 1, 10.0), e(0, 2, 5.0), e(1, 2, 1.0), e(2, 1, 1.0)];
        let ch = msa(3, 0, &edges).unwrap();
        let total: f64 = ch.iter().map(|&k| edges[k].w).sum();
        assert_eq!(total, 6.0);
        assert_eq!(ch.len(), 2);
    }
}
