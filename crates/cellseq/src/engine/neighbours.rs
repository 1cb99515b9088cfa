//! K-nearest candidate lists per cell: good successors (`out`) and good predecessors (`inn`).
//!
//! Geometric instances use kiddo k-d trees over entry and exit points (no n × n matrix);
//! matrix instances rank the cheapest arcs of the matrix.

use crate::cost::CostModel;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::num::NonZero;

/// Candidate lists of at most K cells per cell.
#[derive(Debug, Clone)]
pub struct Neighbours {
    /// `out[c]`: cells that are cheap to go to from c, best first.
    pub out: Vec<Vec<u32>>,
    /// `inn[c]`: cells that are cheap to come from into c, best first.
    pub inn: Vec<Vec<u32>>,
}

impl Neighbours {
    /// Per cell, its out-neighbours, then the in-neighbours not among them: the cells worth
    /// linking to it in either direction, each once.
    pub fn merged(&self) -> Vec<Vec<u32>> {
        self.out
            .iter()
            .zip(&self.inn)
            .map(|(out, inn)| {
                let mut v = out.clone();
                for &x in inn {
                    if !v.contains(&x) {
                        v.push(x);
                    }
                }
                v
            })
            .collect()
    }

    /// Builds lists of `k` neighbours per cell.
    pub fn new(m: &CostModel, k: usize) -> Self {
        let k = k.min(m.n().saturating_sub(1));
        if k == 0 {
            return Neighbours {
                out: vec![Vec::new(); m.n()],
                inn: vec![Vec::new(); m.n()],
            };
        }
        if m.is_geometric() {
            geometric(m, k)
        } else {
            matrix(m, k)
        }
    }
}

fn min_cost(m: &CostModel, a: usize, b: usize) -> f64 {
    let mut best = f64::INFINITY;
    for ma in 0..m.modes(a) {
        for mb in 0..m.modes(b) {
            best = best.min(m.arc(a, ma, b, mb));
        }
    }
    best
}

fn matrix(m: &CostModel, k: usize) -> Neighbours {
    let n = m.n();
    let mut cost = vec![0.0f64; n * n];
    for a in 0..n {
        for b in 0..n {
            cost[a * n + b] = if a == b {
                f64::INFINITY
            } else {
                min_cost(m, a, b)
            };
        }
    }
    let pick = |f: &dyn Fn(usize) -> f64| -> Vec<u32> {
        let mut v: Vec<u32> = (0..n as u32).collect();
        v.sort_by(|&x, &y| f(x as usize).total_cmp(&f(y as usize)).then(x.cmp(&y)));
        v.truncate(k);
        v
    };
    let out = (0..n).map(|a| pick(&|b| cost[a * n + b])).collect();
    let inn = (0..n).map(|b| pick(&|a| cost[a * n + b])).collect();
    Neighbours { out, inn }
}

fn geometric(m: &CostModel, k: usize) -> Neighbours {
    let n = m.n();
    // immutable trees: built once, and robust to many coincident or collinear points
    let build = |exit: bool| -> ImmutableKdTree<f64, 2> {
        let pts: Vec<(u32, [f64; 2])> = (0..m.nodes())
            .map(|nd| {
                let p = if exit { m.exit(nd) } else { m.entry(nd) };
                (nd as u32, [p.x, p.y])
            })
            .collect();
        ImmutableKdTree::new_from_entries(&pts).expect("k-d tree build")
    };
    let entries = build(false);
    let exits = build(true);
    let query = |tree: &ImmutableKdTree<f64, 2>, c: usize, use_exit: bool| -> Vec<u32> {
        let mut want = k * 2 + 1;
        loop {
            let mut best: Vec<(f64, u32)> = Vec::new();
            for md in 0..m.modes(c) {
                let nd = m.node(c, md);
                let p = if use_exit { m.exit(nd) } else { m.entry(nd) };
                let kk = want.min(m.nodes());
                let res = tree
                    .query(&[p.x, p.y])
                    .nearest_n::<SquaredEuclidean<f64>>(NonZero::new(kk).expect("k > 0"))
                    .execute();
                for r in res {
                    let (o, _) = m.cell_mode(r.item as usize);
                    // same-tool neighbours first: a tool change costs more than any short hop
                    let pen = if m.tool(o) == m.tool(c) { 0.0 } else { 1e12 };
                    if o != c {
                        best.push((r.distance + pen, o as u32));
                    }
                }
            }
            best.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            let mut cells: Vec<u32> = Vec::with_capacity(k);
            for (_, o) in best {
                if !cells.contains(&o) {
                    cells.push(o);
                    if cells.len() == k {
                        break;
                    }
                }
            }
            if cells.len() == k || want >= m.nodes() {
                return cells;
            }
            want *= 4;
        }
    };
    // independent per cell: built in parallel, identical whatever the number of threads
    let out = (0..n)
        .into_par_iter()
        .map(|c| query(&entries, c, true))
        .collect();
    let inn = (0..n)
        .into_par_iter()
        .map(|c| query(&exits, c, false))
        .collect();
    Neighbours { out, inn }
}
