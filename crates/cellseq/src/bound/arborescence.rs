//! The Lagrangian arborescence bound.
//!
//! A feasible sequence closed through home is a Hamiltonian cycle; dropping the arc into home
//! leaves a spanning arborescence rooted at home. So a minimum spanning arborescence (Chu–Liu /
//! Edmonds) plus the cheapest arc into home is a lower bound (a "1-arborescence"). Every node
//! of the cycle has out-degree exactly one; relaxing those constraints with multipliers `π`
//! (arc i → j costs `c(i, j) + π_i`, minus `Σ π`) and tuning `π` by subgradient steps
//! (Held–Karp style) tightens the bound. Every iterate is a valid bound; the best is kept.

use super::cells::CellGraph;

#[derive(Clone, Copy)]
struct Edge {
    from: u32,
    to: u32,
    w: f64,
}

/// Minimum spanning arborescence rooted at `root` over `nv` nodes. Returns the indices of the
/// chosen edges, or `None` when some node cannot be reached.
fn msa(nv: usize, root: usize, edges: &[Edge]) -> Option<Vec<usize>> {
    let mut best = vec![usize::MAX; nv];
    for (k, e) in edges.iter().enumerate() {
        let t = e.to as usize;
        if t != root && e.from != e.to && (best[t] == usize::MAX || e.w < edges[best[t]].w) {
            best[t] = k;
        }
    }
    if (0..nv).any(|v| v != root && best[v] == usize::MAX) {
        return None;
    }
    // Find cycles of the best-in-edge graph.
    let mut comp = vec![usize::MAX; nv];
    let mut mark = vec![usize::MAX; nv];
    let mut in_cycle = vec![false; nv];
    let mut ncomp = 0usize;
    for s in 0..nv {
        let mut v = s;
        while v != root && mark[v] == usize::MAX && comp[v] == usize::MAX {
            mark[v] = s;
            v = edges[best[v]].from as usize;
        }
        if v != root && mark[v] == s && comp[v] == usize::MAX {
            // a new cycle through v
            let mut u = v;
            loop {
                comp[u] = ncomp;
                in_cycle[u] = true;
                u = edges[best[u]].from as usize;
                if u == v {
                    break;
                }
            }
            ncomp += 1;
        }
    }
    if ncomp == 0 {
        return Some((0..nv).filter(|&v| v != root).map(|v| best[v]).collect());
    }
    for c in comp.iter_mut() {
        if *c == usize::MAX {
            *c = ncomp;
            ncomp += 1;
        }
    }
    let mut sub = Vec::with_capacity(edges.len());
    let mut orig = Vec::with_capacity(edges.len());
    for (k, e) in edges.iter().enumerate() {
        let (f, t) = (e.from as usize, e.to as usize);
        let (cf, ct) = (comp[f], comp[t]);
        if cf == ct {
            continue;
        }
        let w = if in_cycle[t] {
            e.w - edges[best[t]].w
        } else {
            e.w
        };
        sub.push(Edge {
            from: cf as u32,
            to: ct as u32,
            w,
        });
        orig.push(k);
    }
    let chosen = msa(ncomp, comp[root], &sub)?;
    let mut out: Vec<usize> = chosen.iter().map(|&k| orig[k]).collect();
    let mut entered = vec![false; nv];
    for &k in &out {
        entered[edges[k].to as usize] = true;
    }
    for v in 0..nv {
        if in_cycle[v] && !entered[v] {
            out.push(best[v]);
        }
    }
    Some(out)
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

/// Runs `iterations` subgradient steps. `upper` (a known solution cost without the constant)
/// sets the step size; without it a target 5 % above the current bound is used.
pub fn lagrangian_bound(
    g: &CellGraph,
    iterations: usize,
    upper: Option<f64>,
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
