//! `greedy`: precedence-aware nearest neighbour.
//!
//! From the current (cell, mode) it moves to the cheapest (cell, mode) among cells whose
//! predecessors are all done. Geometric instances keep one k-d tree (kiddo) per tool over the
//! entry points of ready cells and grow the nearest-k query until no farther point can beat
//! the best exact arc cost found, so each step is exact and costs O(log n) in practice.
//! Matrix instances scan the ready cells.

use super::{outcome_of, Context, Outcome, ParamKind, ParamSpec, Params, Solver, SolverInfo};
use crate::cost::CostModel;
use crate::error::Result;
use crate::model::{Objective, Sequence, Visit};
use kiddo::{MutableKdTree, SquaredEuclidean};
use std::num::NonZero;

/// Registry entry.
pub static INFO: SolverInfo = SolverInfo {
    name: "greedy",
    summary: "precedence-aware nearest neighbour (k-d tree per tool on geometric instances)",
    params: &[ParamSpec {
        name: "randomize",
        default: "0",
        kind: ParamKind::Float,
        help: "probability of taking the second-best candidate at a step (0 = pure greedy)",
    }],
    make: |p: &Params| {
        Box::new(Greedy {
            randomize: p.float("randomize"),
        })
    },
};

/// The greedy solver.
pub struct Greedy {
    /// Probability of taking the second-best candidate.
    pub randomize: f64,
}

impl Solver for Greedy {
    fn solve(&self, ctx: &mut Context) -> Result<Outcome> {
        let seq = if ctx.model.is_geometric() {
            geometric(ctx.model, &mut |k| ctx.count(k))
        } else {
            matrix(ctx.model, &mut |k| ctx.count(k))
        };
        let out = outcome_of(ctx.model, seq);
        ctx.report(out.cost);
        Ok(out)
    }
}

/// Tracks which cells are ready (all predecessors done).
struct Fringe {
    missing: Vec<u32>,
}

impl Fringe {
    fn new(m: &CostModel) -> Self {
        Fringe {
            missing: m.dag.preds.iter().map(|p| p.len() as u32).collect(),
        }
    }
    /// Marks `c` done and calls `ready` for each successor that became ready.
    fn done(&mut self, m: &CostModel, c: usize, mut ready: impl FnMut(usize)) {
        for &s in &m.dag.succs[c] {
            let s = s as usize;
            self.missing[s] -= 1;
            if self.missing[s] == 0 {
                ready(s);
            }
        }
    }
}

/// Greedy over an explicit matrix: scans every ready (cell, mode).
pub fn matrix(m: &CostModel, count: &mut dyn FnMut(u64)) -> Sequence {
    let n = m.n();
    let mut fringe = Fringe::new(m);
    let mut ready: Vec<usize> = (0..n).filter(|&c| fringe.missing[c] == 0).collect();
    let mut seq: Sequence = Vec::with_capacity(n);
    while !ready.is_empty() {
        let mut best = (f64::INFINITY, usize::MAX, 0usize, 0usize);
        for (i, &c) in ready.iter().enumerate() {
            for md in 0..m.modes(c) {
                let cost = match seq.last() {
                    None => m.start(c, md),
                    Some(p) => m.arc(p.cell, p.mode, c, md),
                };
                if cost < best.0 || (cost == best.0 && c < best.1) {
                    best = (cost, c, md, i);
                }
            }
        }
        count(ready.len() as u64);
        let (_, c, md, i) = best;
        ready.swap_remove(i);
        seq.push(Visit::new(c, md));
        fringe.done(m, c, |s| ready.push(s));
    }
    seq
}

type Tree = MutableKdTree<f64, 2>;

/// Greedy over a geometric instance with one k-d tree per tool.
pub fn geometric(m: &CostModel, count: &mut dyn FnMut(u64)) -> Sequence {
    let n = m.n();
    let ntools = (0..n).map(|c| m.tool(c) as usize + 1).max().unwrap_or(1);
    let mut trees: Vec<Tree> = (0..ntools).map(|_| Tree::default()).collect();
    let mut in_tree = vec![0u32; ntools];
    let add = |trees: &mut Vec<Tree>, in_tree: &mut Vec<u32>, c: usize| {
        let t = m.tool(c) as usize;
        for md in 0..m.modes(c) {
            let nd = m.node(c, md);
            let p = m.entry(nd);
            trees[t].add(&[p.x, p.y], nd as u32).expect("k-d tree insert");
            in_tree[t] += 1;
        }
    };
    let mut fringe = Fringe::new(m);
    for c in 0..n {
        if fringe.missing[c] == 0 {
            add(&mut trees, &mut in_tree, c);
        }
    }
    // lower bound on any move cost given its planar length d
    let rr = m.rapid_rate();
    let lb_rate = match m.objective() {
        Objective::Time => {
            // links run at cutting feed, which is slower than rapid: rapid rate is the minimum
            rr.min(min_cut_rate(m))
        }
        _ => 1.0,
    };
    let mut seq: Sequence = Vec::with_capacity(n);
    let mut done = vec![false; n];
    while seq.len() < n {
        let prev = seq.last().copied();
        let mut best = (f64::INFINITY, usize::MAX);
        let cost_to = |nd: usize| -> f64 {
            let (c, md) = m.cell_mode(nd);
            match prev {
                None => m.start(c, md),
                Some(p) => m.arc(p.cell, p.mode, c, md),
            }
        };
        // query the tree of the current tool first (cheapest moves), then the others
        let cur_tool = prev.map(|p| m.tool(p.cell) as usize);
        // where to query tree t, and the part of every move into t that does not depend on
        // the target (so that cost >= offset + planar distance * lb_rate)
        let query_at = |t: usize| -> ([f64; 2], f64) {
            match prev {
                Some(p) if Some(t) == cur_tool => {
                    let e = m.exit(m.node(p.cell, p.mode));
                    ([e.x, e.y], 0.0)
                }
                Some(p) => {
                    let tc = m.tool_change_point();
                    ([tc.x, tc.y], m.change_offset(p.cell, p.mode))
                }
                None => {
                    let h = m.home_point();
                    ([h.x, h.y], 0.0)
                }
            }
        };
        let mut order: Vec<usize> = (0..ntools).filter(|&t| in_tree[t] > 0).collect();
        if let Some(ct) = cur_tool {
            order.sort_by_key(|&t| (t != ct, t));
        }
        for t in order {
            let (q, offset) = query_at(t);
            let mut k = 8usize;
            loop {
                let kk = k.min(in_tree[t] as usize);
                let res = trees[t]
                    .query(&q)
                    .nearest_n::<SquaredEuclidean<f64>>(NonZero::new(kk).expect("k > 0"))
                    .execute();
                count(res.len() as u64);
                for r in &res {
                    let nd = r.item as usize;
                    let c = cost_to(nd);
                    if c < best.0 || (c == best.0 && nd < best.1) {
                        best = (c, nd);
                    }
                }
                let exhausted = res.len() < k || kk == in_tree[t] as usize;
                let far = res.last().map(|r| r.distance.sqrt()).unwrap_or(0.0);
                if exhausted || best.0 <= offset + far * lb_rate {
                    break;
                }
                k *= 4;
            }
        }
        let nd = best.1;
        let (c, md) = m.cell_mode(nd);
        seq.push(Visit::new(c, md));
        done[c] = true;
        let t = m.tool(c) as usize;
        for k in 0..m.modes(c) {
            let node = m.node(c, k);
            let p = m.entry(node);
            trees[t].remove(&[p.x, p.y], node as u32);
            in_tree[t] -= 1;
        }
        let mut newly = Vec::new();
        fringe.done(m, c, |s| newly.push(s));
        for s in newly {
            add(&mut trees, &mut in_tree, s);
        }
    }
    seq
}

fn min_cut_rate(m: &CostModel) -> f64 {
    (0..m.n()).map(|c| m.cut_rate(c)).fold(f64::INFINITY, f64::min)
}
